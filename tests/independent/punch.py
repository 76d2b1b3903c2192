"""The punch drive solved independently of sewfmu: the key figures of punch_drive (and punch_split,
the same physics cut at the fabric) from the paper as docs/punch_drive.md gives it.

Nothing here imports sewfmu. The linkage is solved from its loop-closure equations by a generic
root finder (scipy.optimize.fsolve), continuing from the previous crank angle; its derivatives by
the differentiated loop equations; the punch's equation of motion by scipy's solve_ivp with the
contact condition as an event function, so that landings and losses are located by the
integrator's root finder, not read from samples; the figures from that continuous solution.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, fsolve, minimize_scalar

G = 9.81                      # m/s², as in the specification

# defaults of docs/punch_drive.md (SI units), the paper's values with docs/punch_drive.md's placement
LINKAGE = {"L_O1A": 0.006, "L_AB": 0.039, "L_O2B": 0.010, "L_O2C": 0.0071,
           "angle_BO2C": math.radians(110.0), "L_CD": 0.065, "x_O2": 0.0, "y_O2": 0.040,
           "x_D": 0.0, "xi0": 0.0045}
PUNCH = {"m": 0.063, "F10": 20.0, "c1": 2000.0, "b1": 0.71, "c2": 5.0e4, "b2": 97.64,
         "c3": 1.0e5, "b3": 7.10, "F30": 0.0}
OMEGA = 100.0                 # rad/s, punch_drive's shaft speed (no start ramp)
REVOLUTIONS = 10              # from the setup position; the figures are of the last one

# the solver's settings (the "how" of figures.json quotes them)
RTOL, ATOL = 1e-11, 1e-14
GRID = 2048                   # crank angles per turn at which the loop equations are solved


def _e(angle):
    """Unit vector at `angle`."""
    return np.array([math.cos(angle), math.sin(angle)])


def _e_prime(angle):
    """d/dangle of the unit vector."""
    return np.array([-math.sin(angle), math.cos(angle)])


class SixBar:
    """The six-bar O1-A-B-O2-C-D. Unknowns q = (θ2, θ3, θ4, y_D) for a crank angle α:
    θ2 the direction of A→B, θ3 of O2→B, θ4 of C→D, y_D the slider's height. Loop equations:

        L_O1A·e(α) + L_AB·e(θ2) − O2 − L_O2B·e(θ3) = 0              (loop O1-A-B-O2)
        O2 + L_O2C·e(θ3 − β) + L_CD·e(θ4) − (x_D, y_D) = 0          (loop O2-C-D)
    """

    def __init__(self, p: dict = LINKAGE):
        self.p = p
        self.o2 = np.array([p["x_O2"], p["y_O2"]])

    def residual(self, q, alpha):
        p = self.p
        t2, t3, t4, yd = q
        r1 = p["L_O1A"] * _e(alpha) + p["L_AB"] * _e(t2) - self.o2 - p["L_O2B"] * _e(t3)
        r2 = (self.o2 + p["L_O2C"] * _e(t3 - p["angle_BO2C"]) + p["L_CD"] * _e(t4)
              - np.array([p["x_D"], yd]))
        return np.concatenate([r1, r2])

    def jacobian(self, q):
        """∂(residual)/∂q: also the matrix of the velocity and acceleration loop equations."""
        p = self.p
        t2, t3, t4, _ = q
        J = np.zeros((4, 4))
        J[0:2, 0] = p["L_AB"] * _e_prime(t2)
        J[0:2, 1] = -p["L_O2B"] * _e_prime(t3)
        J[2:4, 1] = p["L_O2C"] * _e_prime(t3 - p["angle_BO2C"])
        J[2:4, 2] = p["L_CD"] * _e_prime(t4)
        J[2:4, 3] = (0.0, -1.0)
        return J

    def solve(self, alpha, guess):
        """Positions by fsolve from `guess`; checked for the assembly branch the spec names."""
        q, info, ok, msg = fsolve(self.residual, guess, args=(alpha,), fprime=lambda q, a: self.jacobian(q),
                                  xtol=1e-14, full_output=True)
        res = np.abs(self.residual(q, alpha)).max()
        if ok != 1 and res > 1e-15:
            raise RuntimeError(f"six-bar: no assembly at α = {math.degrees(alpha):.3f}°: {msg}")
        p = self.p
        a = p["L_O1A"] * _e(alpha)
        b = self.o2 + p["L_O2B"] * _e(q[1])
        # B on the +x side of the line A→O2 (to its right: the line runs upwards), D below C
        cross = (self.o2 - a)[0] * (b - a)[1] - (self.o2 - a)[1] * (b - a)[0]
        if cross >= 0 or math.sin(q[2]) >= 0:
            raise RuntimeError(f"six-bar: left the specified branch at α = {math.degrees(alpha):.3f}°")
        return q

    def derivatives(self, q, alpha):
        """dq/dα and d²q/dα² from the differentiated loop equations (the crank is the input)."""
        p = self.p
        t2, t3, t4, _ = q
        J = self.jacobian(q)
        rhs1 = np.concatenate([-p["L_O1A"] * _e_prime(alpha), np.zeros(2)])
        dq = np.linalg.solve(J, rhs1)
        # differentiate once more: J·q'' = Σ s·L·e(θ)·θ'² over the loop's angle terms (α' = 1)
        d2, d3, d4 = dq[0], dq[1], dq[2]
        rhs2 = np.concatenate([
            p["L_O1A"] * _e(alpha) + p["L_AB"] * _e(t2) * d2 ** 2 - p["L_O2B"] * _e(t3) * d3 ** 2,
            p["L_O2C"] * _e(t3 - p["angle_BO2C"]) * d3 ** 2 + p["L_CD"] * _e(t4) * d4 ** 2])
        ddq = np.linalg.solve(J, rhs2)
        return dq, ddq

    def first_guess(self, alpha):
        """A rough configuration on the specified branch, for the first fsolve only."""
        p = self.p
        b = self.o2 + p["L_O2B"] * _e(0.0)                      # B to the right of O2
        a = p["L_O1A"] * _e(alpha)
        t2 = math.atan2(*(b - a)[::-1])
        c = self.o2 + p["L_O2C"] * _e(-p["angle_BO2C"])
        return np.array([t2, 0.0, -math.pi / 2, c[1] - p["L_CD"]])

    def sweep(self, alphas):
        """Positions along a sequence of crank angles, each solve continuing from the last."""
        out = np.empty((len(alphas), 4))
        q = self.first_guess(alphas[0])
        for k, alpha in enumerate(alphas):
            q = self.solve(alpha, q)
            out[k] = q
        return out


@dataclass
class Excitation:
    """ξ(φ), dξ/dφ, d²ξ/dφ² of the six-bar, as trigonometric interpolants of their values at
    GRID shaft angles. ξ is periodic and analytic in φ, so the interpolant converges
    geometrically; `interpolation_error` is its largest deviation, at off-grid angles, from
    fresh loop-closure solves (make_references reports it)."""
    alpha0: float
    stroke: float
    coeffs: list = field(default_factory=list)       # per derivative order: rfft coefficients
    interpolation_error: float = math.nan

    def __call__(self, phi):
        """(ξ, ξ', ξ'') at shaft angle(s) phi."""
        phi = np.atleast_1d(np.asarray(phi, dtype=float))
        k = np.arange(len(self.coeffs[0]))
        basis = np.exp(1j * np.outer(phi, k))
        return tuple((basis @ c).real for c in self.coeffs)


def excitation(p: dict = LINKAGE, grid: int = GRID) -> Excitation:
    linkage = SixBar(p)
    # α0: the crank angle of D's highest point. A 1° scan over a whole turn (which also shows that
    # the linkage assembles everywhere), then the root of dy_D/dα between the scan's neighbours.
    scan = np.radians(np.arange(0.0, 360.0, 1.0))
    qs = linkage.sweep(scan)
    k = int(np.argmax(qs[:, 3]))
    state = {"q": qs[k]}

    def dyd(alpha):
        state["q"] = linkage.solve(alpha, state["q"])
        return linkage.derivatives(state["q"], alpha)[0][3]

    alpha0 = brentq(dyd, scan[k] - math.radians(1.0), scan[k] + math.radians(1.0), xtol=1e-15, rtol=1e-15)
    y_top = linkage.solve(alpha0, state["q"])[3]

    def evaluate(phis):
        alphas = alpha0 - phis                       # the crank turns clockwise as φ grows
        qs = linkage.sweep(alphas)
        d = np.array([linkage.derivatives(q, a) for q, a in zip(qs, alphas)])
        # ξ = xi0 − (y_D(α0) − y_D(α0 − φ)); d/dφ = −d/dα
        return (p["xi0"] - (y_top - qs[:, 3]), -d[:, 0, 3], d[:, 1, 3])

    phis = 2 * math.pi * np.arange(grid) / grid
    values = evaluate(phis)
    ex = Excitation(alpha0=alpha0, stroke=float(np.ptp(values[0])))
    coeffs = []
    for v in values:
        c = np.fft.rfft(v) / grid
        c[1:] *= 2.0
        c[-1] /= 2.0                                  # the Nyquist term is not doubled
        coeffs.append(c)
    # the coefficients fall geometrically, below 1e-13 of the first harmonic by k ≈ 40, and
    # end in rounding noise (about 1e-18 m): drop that tail, so that each evaluation is cheap
    keep = 8 + max(int(np.nonzero(np.abs(c) > 1e-13 * abs(c[1]))[0].max()) for c in coeffs)
    ex.coeffs = [c[:keep] for c in coeffs]
    # check the interpolant halfway between grid points against fresh loop-closure solves
    mid = phis[::16] + math.pi / grid
    direct = evaluate(mid)
    interp = ex(mid)
    ex.interpolation_error = max(float(np.abs(a - b).max() / np.abs(a).max())
                                 for a, b in zip(direct, interp))
    return ex


@dataclass
class Solution:
    events: list            # (t, "onset" | "loss")
    segments: list          # (t0, t1, in_contact, dense output of (y, ẏ, ∫F2 dt))
    omega: float
    t_end: float
    punch: dict


def solve(omega: float = OMEGA, revolutions: int = REVOLUTIONS, punch: dict = PUNCH,
          ex: Excitation | None = None, method: str = "DOP853", rtol: float = RTOL,
          atol: float = ATOL) -> Solution:
    """The punch from the setup position (y = xi0, ẏ = 0) for `revolutions` turns at constant ω.

    The fabric's force is F2 = −(c2·y + b2·ẏ) while y < 0 and that is > 0, i.e. while
    s = max(y, y + (b2/c2)·ẏ) < 0: s is continuous and changes sign exactly where F2 switches,
    so it is the event function of both the landing and the loss (and of a re-contact below the
    surface). Between switches the right-hand side is smooth; each piece is one solve_ivp call.
    """
    ex = ex or excitation()
    m, c1, b1, c2, b2, c3, b3 = (punch[k] for k in ("m", "c1", "b1", "c2", "b2", "c3", "b3"))
    F10, F30 = punch["F10"], punch["F30"]
    tau = b2 / c2

    def rhs(t, x, contact):
        y, v, _ = x
        xi, dxi, _ = ex(omega * t)
        xi, xi_dot = xi[0], dxi[0] * omega                 # ε = 0: constant shaft speed
        F1 = F10 + c1 * y + b1 * v
        F3 = F30 + c3 * (xi - y) + b3 * (xi_dot - v)      # spring 11, bilateral (the default)
        F2 = -(c2 * y + b2 * v) if contact else 0.0
        return [v, (-F1 + F2 + F3 - m * G) / m, F2]

    def switch(t, x, contact):
        return max(x[0], x[0] + tau * x[1])

    switch.terminal = True
    t_end = revolutions * 2 * math.pi / omega
    t, x, contact = 0.0, np.array([ex(0.0)[0][0], 0.0, 0.0]), False
    events, segments = [], []
    while t < t_end:
        # free: stop where s falls through 0 (contact begins); in contact: where it rises through 0
        switch.direction = 1.0 if contact else -1.0
        sol = solve_ivp(rhs, (t, t_end), x, method=method, rtol=rtol, atol=atol, args=(contact,),
                        events=switch, dense_output=True)
        if sol.status == -1:
            raise RuntimeError(sol.message)
        segments.append((t, sol.t[-1], contact, sol.sol))
        t, x = sol.t[-1], sol.y[:, -1]
        if sol.status == 1:
            contact = not contact
            events.append((t, "onset" if contact else "loss"))
    return Solution(events, segments, omega, t_end, punch)


def F2_of(sol: Solution, t):
    """The fabric's force at time(s) t (at a switch instant: the value after it)."""
    t = np.atleast_1d(t)
    out = np.zeros_like(t, dtype=float)
    for t0, t1, contact, dense in sol.segments:
        if contact:
            inside = (t >= t0) & (t <= t1)
            if inside.any():
                y, v, _ = dense(t[inside])
                out[inside] = -(sol.punch["c2"] * y + sol.punch["b2"] * v)
    return out


def _integral_F2(sol: Solution, t: float) -> float:
    for t0, t1, _, dense in sol.segments:
        if t0 <= t <= t1:
            return float(dense(t)[2])
    raise ValueError(t)


def figures(sol: Solution) -> dict:
    """The key figures of docs/punch_drive.md over the last whole revolution, crank angle within
    it in degrees: first onset, last loss, the angle with F2 > 0, the number of contact
    intervals, the largest F2, and the mean F2 over the middle half of [onset, loss] by angle."""
    period = 2 * math.pi / sol.omega
    t_a = sol.t_end - period
    deg = lambda t: math.degrees(sol.omega * (t - t_a))
    # contact intervals, clipped to the revolution
    intervals = []
    for t0, t1, contact, _ in sol.segments:
        if contact and t1 > t_a:
            intervals.append((max(t0, t_a), t1))
    if not intervals:
        raise RuntimeError("no contact in the last revolution")
    # the largest F2: sampled densely in each contact piece, then refined by a bounded search
    peak = 0.0
    for t0, t1 in intervals:
        ts = np.linspace(t0, t1, 2001)
        f = F2_of(sol, ts)
        k = int(np.argmax(f))
        peak = max(peak, float(f[k]))
        lo, hi = ts[max(k - 1, 0)], ts[min(k + 1, len(ts) - 1)]
        if hi > lo:
            r = minimize_scalar(lambda t: -F2_of(sol, t)[0], bounds=(lo, hi), method="bounded",
                                options={"xatol": 1e-12})
            peak = max(peak, -float(r.fun))
    onset, loss = deg(intervals[0][0]), deg(intervals[-1][1])
    quarter = 0.25 * (loss - onset)
    ta = t_a + math.radians(onset + quarter) / sol.omega
    tb = t_a + math.radians(loss - quarter) / sol.omega
    weld_mean = (_integral_F2(sol, tb) - _integral_F2(sol, ta)) / (tb - ta)
    return {
        "contact_onset_deg": onset,
        "contact_loss_deg": loss,
        "contact_duration_deg": sum(deg(b) - deg(a) for a, b in intervals),
        "n_contacts": len(intervals),
        "F2_peak": peak,
        "F2_weld_mean": weld_mean,
    }


UNITS = {"contact_onset_deg": "deg", "contact_loss_deg": "deg", "contact_duration_deg": "deg",
         "n_contacts": "1", "F2_peak": "N", "F2_weld_mean": "N"}


def reference(method: str = "DOP853", rtol: float = RTOL, atol: float = ATOL) -> tuple[dict, dict]:
    """(figures, notes): the key figures of punch_drive at its defaults, and facts for the
    "how" text (α0, stroke, the interpolant's error)."""
    ex = excitation()
    sol = solve(ex=ex, method=method, rtol=rtol, atol=atol)
    notes = {"alpha0_deg": math.degrees(ex.alpha0), "stroke_mm": ex.stroke * 1e3,
             "interpolation_error_rel": ex.interpolation_error, "switches": len(sol.events)}
    return figures(sol), notes
