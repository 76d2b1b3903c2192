"""Key figures and plots of the punch drive, like the paper's figure 4 (the last revolution).

The figures are computed from sampled signals, the same way for the co-simulation's recorded
communication points and for the monolithic reference's dense samples:

- contact intervals are the runs of samples with contact; an onset is placed where y crosses zero
  (linear interpolation; y is smooth there), a loss where F2 reaches zero (F2 is continuous at a
  loss: extrapolated from the last two samples in contact);
- contact_onset_deg / contact_loss_deg: first onset and last loss in the last revolution, as the
  crank angle within that revolution; contact_duration_deg: the angle with F2 > 0 in it;
- F2_weld_mean: the mean of F2 over the middle half of [onset, loss], by crank angle.
"""
from __future__ import annotations

import math
import textwrap
import time
from dataclasses import dataclass

import numpy as np

from sewfmu.components.parameters import with_values
from sewfmu.components.punch_contact import GRAVITY, PunchContactParams
from sewfmu.components.punch_linkage import SIX_BAR, PunchLinkage, PunchLinkageParams
from sewfmu.components.shaft import MainShaft, ShaftParams
from sewfmu.scenarios.files.matplotlib_home import pyplot
from sewfmu.scenarios.mechanisms.animation import angle_label
from sewfmu.scenarios.mechanisms.base import (
    Mechanism,
    RegressionCase,
    column,
    last_revolution,
    parameters,
    shaft_at,
    whole_revolution,
)
from sewfmu.scenarios.mechanisms.sampling import sampled

# the key figures of a run and their units (summary.json, sweeps, reports)
FIGURES = {"contact_onset_deg": "deg", "contact_loss_deg": "deg", "contact_duration_deg": "deg",
           "n_contacts": "1", "F2_peak": "N", "F2_weld_mean": "N"}


def _zero_between(a0, f0, a1, f1, lo, hi):
    """Zero of the line through (a0, f0), (a1, f1), clipped to [lo, hi]."""
    if f1 == f0:
        return 0.5 * (lo + hi)
    return min(max(a0 - f0 * (a1 - a0) / (f1 - f0), lo), hi)


def summary(phi: np.ndarray, y: np.ndarray, F2: np.ndarray, contact: np.ndarray,
            F2_max: np.ndarray | None = None) -> dict:
    """The punch's key figures over the last shaft revolution of the samples. F2_max, where
    given, is the largest F2 within each sample interval (the FMU's peak hold)."""
    start, end = whole_revolution(float(phi[-1]))
    k0 = max(int(np.searchsorted(phi, start)) - 1, 0)      # one sample before, for the edges
    k1 = int(np.searchsorted(phi, end + 1e-9, side="right"))
    ang = np.degrees(phi[k0:k1] - start)
    y, F2 = y[k0:k1], F2[k0:k1]
    peaks = F2 if F2_max is None else np.maximum(F2, F2_max[k0:k1])
    # a sample's peak hold covers the interval before it: count those ending inside the revolution
    F2_peak = float(peaks[ang > 0].max(initial=0.0))
    on = np.asarray(contact[k0:k1], dtype=bool) & (F2 > 0)
    intervals = []
    k, n = 0, len(ang)
    while k < n:
        if not on[k]:
            k += 1
            continue
        i0 = k
        while k < n and on[k]:
            k += 1
        i1 = k - 1
        if i0 == 0:
            onset = ang[0]
        elif y[i0 - 1] > 0 >= y[i0]:
            onset = _zero_between(ang[i0 - 1], y[i0 - 1], ang[i0], y[i0], ang[i0 - 1], ang[i0])
        elif i1 > i0:          # re-contact below the surface: extrapolate F2 back to zero
            onset = _zero_between(ang[i0], F2[i0], ang[i0 + 1], F2[i0 + 1], ang[i0 - 1], ang[i0])
        else:
            onset = 0.5 * (ang[i0 - 1] + ang[i0])
        if i1 == n - 1:
            loss = ang[-1]
        elif i1 > i0:
            loss = _zero_between(ang[i1 - 1], F2[i1 - 1], ang[i1], F2[i1], ang[i1], ang[i1 + 1])
        else:
            loss = 0.5 * (ang[i1] + ang[i1 + 1])
        onset, loss = max(onset, 0.0), min(loss, 360.0)
        if loss > onset:
            intervals.append((onset, loss))
    if not intervals:
        return {"contact_onset_deg": None, "contact_loss_deg": None, "contact_duration_deg": 0.0,
                "n_contacts": 0, "F2_peak": F2_peak,
                "F2_weld_mean": None}
    onset, loss = intervals[0][0], intervals[-1][1]
    quarter = 0.25 * (loss - onset)
    return {
        "contact_onset_deg": float(onset),
        "contact_loss_deg": float(loss),
        "contact_duration_deg": float(sum(b - a for a, b in intervals)),
        "n_contacts": len(intervals),
        "F2_peak": F2_peak,
        "F2_weld_mean": _mean_between(ang, F2, onset + quarter, loss - quarter),
    }


def _mean_between(x: np.ndarray, f: np.ndarray, a: float, b: float) -> float:
    """Mean of f over [a, b] by the trapezoidal rule on the samples, edges interpolated."""
    inside = (x > a) & (x < b)
    xs = np.concatenate([[a], x[inside], [b]])
    fs = np.concatenate([[np.interp(a, x, f)], f[inside], [np.interp(b, x, f)]])
    return float(np.trapezoid(fs, xs) / (b - a))


# the punch's signals: all from PunchContact, or, split at the fabric, from PunchBody and Fabric
_FROM_FABRIC = ("F2", "F2_max", "contact")


def signal(result, name: str):
    """A punch signal of a run of punch_drive (role punch) or punch_split (roles body, fabric)."""
    roles = result.scenario.roles
    if "punch" in roles:
        role = "punch"
    else:
        role = "fabric" if name in _FROM_FABRIC else "body"
    return result.columns.get(f"{roles[role]}.{name}") if name == "F2_max" \
        else column(result, role, name)


def summary_of_run(result) -> dict:
    return summary(column(result, "shaft", "phi"), signal(result, "y"), signal(result, "F2"),
                   signal(result, "contact"), signal(result, "F2_max"))


def summary_of_monolithic(solution) -> dict:
    return summary(solution.phi, solution.y, solution.F2, solution.contact)


def monolithic_figures(scenario, rtol: float | None = None,
                       punch_roles: tuple[str, ...] = ("punch",)) -> tuple[dict, float]:
    """Key figures of the punch drive solved as one ODE (DOP853, tight tolerances, or `rtol`
    with atol = rtol/1000) and the solver's wall time. `punch_roles`: the instances whose
    parameters together make the punch (the split drive's body and fabric)."""
    params = {role: dict(scenario.instances[name].parameters)
              for role, name in scenario.roles.items()}
    params["punch"] = {k: v for role in punch_roles for k, v in params.pop(role).items()}
    t_end = scenario.end_time()
    omega = params["shaft"].get("omega0", ShaftParams().omega0)
    started = time.perf_counter()
    tolerances = {} if rtol is None else {"rtol": rtol, "atol": rtol * 1e-3}
    solution = solve(params["shaft"], params["linkage"], params["punch"], t_end,
                     sample_step=math.radians(0.01) / omega,
                     sample_from=_last_revolution_from(params["shaft"], t_end, omega),
                     **tolerances)
    return summary_of_monolithic(solution), time.perf_counter() - started


def _last_revolution_from(shaft: dict, t_end: float, omega: float) -> float:
    """The time to sample from: a little before the last whole revolution the figures read,
    which starts up to two revolutions before a run that ends between two (a stop time that is
    not a whole number of turns)."""
    model = MainShaft(with_values(ShaftParams(), **shaft))
    phi_end = model.state(t_end)[0]
    start = 2 * math.pi * (math.floor(phi_end / (2 * math.pi) + 1e-9) - 1)
    if start < 0.0:
        return 0.0
    return max(0.0, model.time_of_angle(start) - 0.1 * math.pi / omega)


# --- plots ------------------------------------------------------------------------------------
def plot(curves, path, title: str) -> None:
    """y(φ) and F2(φ) over the last revolution; `curves` is a list of (label, run result)."""
    plt = pyplot()          # matplotlib, its files out of the user's home

    fig, (ax_y, ax_f) = plt.subplots(2, 1, sharex=True, figsize=(8, 6.5))
    for label, result in curves:
        mask = last_revolution(result)
        phi = column(result, "shaft", "phi")
        deg = np.degrees(phi[mask] - whole_revolution(float(phi[-1]))[0])
        ax_y.plot(deg, signal(result, "y")[mask] * 1e3, label=label)
        ax_f.plot(deg, signal(result, "F2")[mask], label=label)
    if f"{result.scenario.roles['linkage']}.xi" in result.columns:   # the slider, if recorded
        ax_y.plot(deg, column(result, "linkage", "xi")[mask] * 1e3, "k:", lw=1,
                  label="ξ (slider)")
    ax_y.axhline(0.0, color="0.6", lw=0.8)
    ax_y.set_ylabel("punch height y [mm]")
    ax_f.set_ylabel("fabric force F2 [N]")
    ax_f.set_xlabel("crank angle in the last revolution φ [°]")
    ax_f.set_xlim(0, 360)
    ax_f.set_xticks(range(0, 361, 45))
    for ax in (ax_y, ax_f):
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    fig.suptitle("\n".join(textwrap.wrap(title, 80)), fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def excitation(t) -> dict:
    """The six-bar's excitation of the punch at ω = 200 s⁻¹ (its regression input)."""
    e = sampled(PunchLinkage().motion, 200.0 * t, 200.0, 0.0)
    return {"xi": e.xi, "xi_dot": e.xi_dot, "xi_ddot": e.xi_ddot}


# --- the drawing (the GIF, the page) ------------------------------------------------------------
MM = 1e3
HOLDER = 14.0      # mm: slider to punch tip with spring 11 unloaded (Δ = 0), as drawn
PUNCH = 8.0        # mm: height of the punch body
BAR = 25.0         # mm: length of the force bar at the run's largest F2


class Scene:
    to_scale = True
    tracked = "tip"

    def __init__(self, result):
        self.result = result
        self.model = PunchLinkage(with_values(PunchLinkageParams(),
                                              **parameters(result, "linkage")))
        p = self.model.p
        self.phi = column(result, "shaft", "phi")
        self.xi = column(result, "linkage", "xi")
        self.y = signal(result, "y")
        self.F2 = signal(result, "F2")
        self.x = p.x_D * MM
        # the fabric surface in the linkage's frame: the slider's top height less the lift xi0
        self.surface = (self.model.y_top - p.xi0) * MM - HOLDER
        self.F2_scale = max(float(np.max(self.F2[last_revolution(result)])), 1e-9)
        joints = [self._joints(i) for i in range(0, len(self.phi), max(1, len(self.phi) // 400))]
        xs = [pt[0] for js in joints for pt in js.values()] + [self.x]
        ys = [pt[1] for js in joints for pt in js.values()] + [self.surface]
        self.xlim = (min(xs) - 14.0, max(max(xs), self.x + 14.0) + BAR + 4.0)
        self.ylim = (self.surface - 9.0, max(ys) + 6.0)

    def _joints(self, i: int) -> dict[str, tuple[float, float]]:
        """The six-bar's joints (mm) at sample i; D at the recorded slider height."""
        d = (self.x, self.surface + HOLDER + self.xi[i] * MM)
        if self.model.p.mode != SIX_BAR:
            return {"D": d}
        js = self.model.joints(self.model.alpha0 - self.phi[i])
        out = {name: (m.x * MM, m.y * MM) for name, m in js.items()}
        out["D"] = d
        return out

    def points(self, i: int) -> dict[str, tuple[float, float]]:
        """The drawing's points at sample i (mm), for a page that draws it itself (chains)."""
        tip = self.surface + self.y[i] * MM
        return {**self._joints(i), "top": (self.x, tip + PUNCH), "tip": (self.x, tip),
                "fabric_left": (self.x - 12.0, self.surface), "fabric_right": (self.x + 12.0, self.surface)}

    def chains(self) -> list[tuple[str, ...]]:
        six_bar = (("O1", "A", "B", "O2", "C", "D"),) if self.model.p.mode == SIX_BAR else ()
        return [*six_bar, ("D", "top"), ("top", "tip"), ("fabric_left", "fabric_right")]

    def draw(self, ax, i: int) -> tuple[float, float]:
        j = self._joints(i)
        if "A" in j:
            for chain in (("O1", "A", "B", "O2", "C", "D"),):
                ax.plot(*zip(*[j[n] for n in chain]), "o-", color="0.25", lw=1.6, ms=3)
            ax.plot(*j["B"], "o", color="0.25", ms=3)
            for pivot in ("O1", "O2"):
                ax.plot(*j[pivot], "^", color="0.4", ms=8)
        # slider and its guide
        ax.plot([self.x, self.x], [self.surface + HOLDER - 2, self.ylim[1]], color="0.8", lw=4,
                zorder=0)
        ax.add_patch(_rect(self.x - 2.5, j["D"][1] - 1.5, 5.0, 3.0, "0.55"))
        tip = self.surface + self.y[i] * MM
        top = tip + PUNCH
        _spring(ax, self.x, top, j["D"][1] - 1.5)
        ax.add_patch(_rect(self.x - 3.0, tip, 6.0, PUNCH, "#4477aa"))
        # the fabric, and the force it presses with
        contact = self.F2[i] > 0.0
        ax.add_patch(_rect(self.x - 12.0, self.surface - 3.0, 24.0, 3.0,
                           "#d9a441" if contact else "#eed9a4"))
        length = BAR * self.F2[i] / self.F2_scale
        ax.add_patch(_rect(self.x + 14.0, self.surface - 3.0, max(length, 0.0), 2.0, "#aa3377"))
        ax.text(self.x + 14.0, self.surface - 7.5, f"F2 = {self.F2[i]:5.1f} N", fontsize=8)
        ax.text(self.x - 12.0, self.surface - 7.5, "fabric", fontsize=8)
        ax.set_title(f"punch drive   {angle_label(self.result, i)}", fontsize=9)
        ax.set_xlabel("x [mm]", fontsize=8)
        ax.tick_params(labelsize=7)
        return self.x, tip


def _rect(x, y, w, h, color):
    from matplotlib.patches import Rectangle  # matplotlib: only when drawing
    return Rectangle((x, y), w, h, facecolor=color, edgecolor="0.2", lw=0.6)


def _spring(ax, x, bottom, top, turns=6, width=1.6):
    """A zigzag between two heights: spring 11, its length to scale."""
    zs = np.linspace(bottom, top, 2 * turns + 1)
    xs = x + width * np.array([0] + [(-1) ** k for k in range(2 * turns - 1)] + [0])
    ax.plot(xs, zs, color="0.3", lw=0.9)


# --- the monolithic solution ------------------------------------------------------------
# The monolithic solution of the punch drive: the same physics as one ODE, solved by scipy.
# Independent of the co-simulation on purpose: the excitation is the linkage's exact kinematics at
# the shaft angle phi(t) (no Taylor extrapolation), the force law is written here again from
# docs/punch_drive.md, and the punch is integrated numerically (solve_ivp, DOP853 by default) with
# the contact and spring switches located as terminal events, restarting in the new mode. Where a
# preloaded compression-only spring 11 holds the punch on its stop, the punch moves with the exact
# excitation until the stop force leaves [0, F30] (found by scanning and brentq).
@dataclass
class MonolithicSolution:
    time: np.ndarray
    phi: np.ndarray
    y: np.ndarray
    y_dot: np.ndarray
    F2: np.ndarray
    F3: np.ndarray
    contact: np.ndarray
    held: np.ndarray           # the punch rides on the stop of a preloaded compression-only spring
    switch_times: list[float]
    n_rhs: int


def _fabric_push(p, y, v):
    """The fabric's Kelvin-Voigt force on the punch while they touch, before the contact's
    one-sidedness (F2 = max(0, this)); y and v may be arrays."""
    return -(p.c2 * y + p.b2 * v)


def solve(shaft: dict, linkage: dict, punch: dict, t_end: float, sample_step: float,
          sample_from: float = 0.0, method: str = "DOP853", rtol: float = 1e-10,
          atol: float = 1e-13, sample_switches: bool = True) -> MonolithicSolution:
    """Solve the punch drive from the setup position to t_end; sample the solution every
    sample_step from sample_from on, and at the switch instants if sample_switches."""
    from scipy.integrate import solve_ivp  # scipy: only when the monolithic solution is asked

    sh = MainShaft(with_values(ShaftParams(), **shaft))
    lk = PunchLinkage(with_values(PunchLinkageParams(), **linkage))
    p = with_values(PunchContactParams(), **punch)
    n_rhs = 0

    def excitation(t):
        phi, omega, eps = sh.state(t)
        e = lk.motion(phi, omega, eps)
        return float(e.xi), float(e.xi_dot), float(e.xi_ddot)

    def forces(t, y, v, contact, spring_on):
        xi, xi_dot, _ = excitation(t)
        f1 = p.F10 + p.c1 * y + p.b1 * v
        f2 = _fabric_push(p, y, v) if contact else 0.0
        f3 = p.F30 + p.c3 * (xi - y) + p.b3 * (xi_dot - v) if spring_on else 0.0
        return f1, f2, f3

    def contact_g(t, s):               # < 0 inside {y < 0 and F2* > 0}
        return max(s[0], -_fabric_push(p, s[0], s[1]))

    def spring_g(t, s):                # < 0 inside {Delta > 0 and F3* > 0}
        xi, xi_dot, _ = excitation(t)
        delta = xi - s[0]
        return max(-delta, -(p.F30 + p.c3 * delta + p.b3 * (xi_dot - s[1])))

    xi0, xi_dot0, _ = excitation(0.0)
    state = np.array([xi0, 0.0])
    contact = False
    spring_on = True if not p.compression_only else spring_g(0.0, state) < 0
    held = _holds(p, 0.0, state, contact, spring_on, excitation)
    t0 = 0.0
    pieces = []            # (t_start, t_end, dense solution, contact, spring_on, held)
    switches = []
    while t0 < t_end:
        if held:
            t1, released = _ride_on_stop(p, t0, t_end, contact, excitation)
            pieces.append((t0, t1, _riding(excitation), contact, True, True))
            xi, xi_dot, xi_ddot = excitation(t1)
            state = np.array([xi, xi_dot])
            t0 = t1
            if released == "contact":
                switches.append(t0)
                contact = not contact
            elif released == "stop":
                switches.append(t0)
                held = False
                spring_on = _stop_force(p, xi, xi_dot, xi_ddot, contact) > p.F30
            continue

        def rhs(t, s, contact=contact, spring_on=spring_on):
            nonlocal n_rhs
            n_rhs += 1
            f1, f2, f3 = forces(t, s[0], s[1], contact, spring_on)
            return [s[1], (-f1 + f2 + f3) / p.m - GRAVITY]

        ev_contact = lambda t, s: contact_g(t, s)
        ev_contact.terminal = True
        ev_contact.direction = +1 if contact else -1     # leaving the current mode only
        events = [ev_contact]
        if p.compression_only:
            ev_spring = lambda t, s: spring_g(t, s)
            ev_spring.terminal = True
            ev_spring.direction = +1 if spring_on else -1
            events.append(ev_spring)
        sol = solve_ivp(rhs, (t0, t_end), state, method=method, rtol=rtol, atol=atol,
                        events=events, dense_output=True)
        if not sol.success:
            raise RuntimeError(f"reference solver failed at t = {sol.t[-1]:g} s: {sol.message}")
        pieces.append((t0, sol.t[-1], sol.sol, contact, spring_on, False))
        state = sol.y[:, -1].copy()
        t0 = float(sol.t[-1])
        if sol.status == 1:                        # a switch
            switches.append(t0)
            if sol.t_events[0].size:
                contact = not contact
            else:
                spring_on = not spring_on
                held = _holds(p, t0, state, contact, spring_on, excitation)
    return _sample(pieces, t_end, sample_step, sample_from, sh, lk, p,
                   switches if sample_switches else [], n_rhs)


# --- the punch held on the stop of a preloaded compression-only spring 11 ------------------------
# (the paper's spring 11 gives F3 a jump from 0 to F30 at Delta = 0; components/punch_contact.py
# explains why the punch is then held on the stop. Written here again for the reference.)

def _stop_force(p, y, v, xi_ddot, contact):
    """The stop force that makes the punch move with the slider."""
    f1 = p.F10 + p.c1 * y + p.b1 * v
    f2 = max(0.0, _fabric_push(p, y, v)) if contact else 0.0
    return p.m * (xi_ddot + GRAVITY) + f1 - f2


def _holds(p, t, state, contact, spring_on, excitation) -> bool:
    """At a crossing of the stop: the stop can hold the punch, and the excursion the new mode
    starts (2·|Delta'| / |Delta''|) is below 1/16 of the shortest natural period."""
    if not (p.compression_only and p.F30 > 0.0):
        return False
    xi, xi_dot, xi_ddot = excitation(t)
    y, v = state
    f3_star = p.F30 + p.c3 * (xi - y) + p.b3 * (xi_dot - v)
    if f3_star < 0.5 * p.F30 or not 0.0 <= _stop_force(p, xi, xi_dot, xi_ddot, contact) <= p.F30:
        return False
    f1 = p.F10 + p.c1 * y + p.b1 * v
    f2 = max(0.0, _fabric_push(p, y, v)) if contact else 0.0
    a = (-f1 + f2 + (f3_star if spring_on else 0.0)) / p.m - GRAVITY
    period = 2.0 * math.pi * math.sqrt(p.m / (p.c1 + p.c2 + p.c3))
    return 2.0 * abs(xi_dot - v) <= abs(xi_ddot - a) * period / 16


def _ride_on_stop(p, t0, t_end, contact, excitation):
    """(time, reason) where riding on the stop ends: 'contact' (the fabric contact switches),
    'stop' (the stop force leaves [0, F30]) or None at t_end. Scans in 10 µs and refines by
    brentq."""
    from scipy.optimize import brentq  # scipy: only when the monolithic solution is asked

    def release(t):
        xi, xi_dot, xi_ddot = excitation(t)
        f = _stop_force(p, xi, xi_dot, xi_ddot, contact)
        return max(f - p.F30, -f)

    def touch(t):
        xi, xi_dot, _ = excitation(t)
        g = max(xi, -_fabric_push(p, xi, xi_dot))
        return g if contact else -g

    if release(t0) > 0.0:                 # e.g. the fabric took over the load at a landing
        return t0, "stop"
    scan = 1e-5
    t_prev = t0
    while t_prev < t_end:
        t = min(t_prev + scan, t_end)
        hits = [(brentq(f, t_prev, t, xtol=1e-15, rtol=4 * np.finfo(float).eps), name)
                for f, name in ((touch, "contact"), (release, "stop")) if f(t) > 0.0]
        if hits:
            return min(hits)
        t_prev = t
    return t_end, None


def _riding(excitation):
    """Dense 'solution' of a held piece: (y, y') = (xi, xi') at the given times."""
    def dense(times):
        return np.array([excitation(float(t))[:2] for t in np.atleast_1d(times)]).T
    return dense


def _sample(pieces, t_end, sample_step, sample_from, shaft, linkage, p, switches,
            n_rhs) -> MonolithicSolution:
    k0 = int(math.ceil(sample_from / sample_step - 1e-9))
    k1 = int(math.floor(t_end / sample_step + 1e-9))
    # the switch instants are samples too: the impact force is a jump at the onset
    inside = [t for t in switches if sample_from <= t <= t_end]
    times = np.unique(np.concatenate([np.arange(k0, k1 + 1) * sample_step, inside, [t_end]]))
    y = np.empty_like(times)
    v = np.empty_like(times)
    contact = np.zeros(times.shape, dtype=bool)
    spring_on = np.zeros(times.shape, dtype=bool)
    held = np.zeros(times.shape, dtype=bool)
    for start, end, dense, c, s_on, on_stop in pieces:
        mask = (times >= start) & (times <= end)
        if mask.any():
            y[mask], v[mask] = dense(times[mask])
            contact[mask] = c
            spring_on[mask] = s_on
            held[mask] = on_stop
    motion = np.array([shaft.state(t) for t in times])
    e = sampled(linkage.motion, motion[:, 0], motion[:, 1], motion[:, 2])
    f2 = np.where(contact, np.maximum(_fabric_push(p, y, v), 0.0), 0.0)
    f3 = np.where(spring_on, p.F30 + p.c3 * (e.xi - y) + p.b3 * (e.xi_dot - v), 0.0)
    if p.compression_only:
        f3 = np.maximum(f3, 0.0)
    f1 = p.F10 + p.c1 * y + p.b1 * v
    f3 = np.where(held, p.m * (e.xi_ddot + GRAVITY) + f1 - f2, f3)
    return MonolithicSolution(times, motion[:, 0], y, v, f2, f3, contact, held, list(switches),
                             n_rhs)

class PunchDrive(Mechanism):
    """The punch drive: the shaft turns the six-bar, whose slider drives the punch onto the
    fabric (PunchContact: the punch with its contact)."""
    name = "punch"
    roles = {"shaft": "MainShaft", "linkage": "PunchLinkage", "punch": "PunchContact"}
    figures = FIGURES
    Scene = Scene
    regression = {"PunchLinkage": RegressionCase(2 * math.pi / 100, 2.5e-4, shaft_at(100.0)),
                  "PunchContact": RegressionCase(4 * math.pi / 200, 2.5e-4, excitation)}
    summary_of_run = staticmethod(summary_of_run)
    plot = staticmethod(plot)
    monolithic_figures = staticmethod(monolithic_figures)


MECHANISM = PunchDrive()
