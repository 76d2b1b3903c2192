"""The thread take-up's key figures (scenario takeup) computed independently of sewfmu, from
the papers as docs/takeup.md.

Nothing here imports sewfmu, and the paper's closed form is not used either: the four-bar's loop
equation is solved by scipy.optimize.fsolve continuing from the previous crank angle, its
velocity and acceleration by the differentiated loop equation (2×2 linear solves), and E is the
point of the rigid coupler triangle BCE (φ_BE = φ_BC + ∠CBE, the specification's erratum).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import fsolve

# defaults of docs/takeup.md (SI units); coordinates (Z, X)
TAKEUP = {"L_AB": 0.011, "L_BC": 0.032, "L_CD": 0.024, "L_BE": 0.065,
          "angle_CBE": math.radians(70.0), "z_D": 0.026, "x_D": -0.020}
OMEGA = 5000 * 2 * math.pi / 60      # rad/s, 5000 rpm
STEP_DEG = 0.5                       # the scenario's communication step: the paper's Δθ


def _e(a):
    return np.array([math.cos(a), math.sin(a)])


def _e1(a):
    return np.array([-math.sin(a), math.cos(a)])


class Takeup:
    """Unknowns q = (φ_BC, φ_CD), φ_CD the direction of D→C. Loop: B + L_BC·e(φ_BC) = D + L_CD·e(φ_CD),
    B = L_AB·e(θ); C on the left of B→D (docs/takeup.md)."""

    def __init__(self, p: dict = TAKEUP):
        self.p = p
        self.D = np.array([p["z_D"], p["x_D"]])

    def residual(self, q, theta):
        p = self.p
        return p["L_AB"] * _e(theta) + p["L_BC"] * _e(q[0]) - self.D - p["L_CD"] * _e(q[1])

    def solve(self, theta, guess):
        q, _, ok, msg = fsolve(self.residual, guess, args=(theta,), xtol=1e-14, full_output=True)
        if np.abs(self.residual(q, theta)).max() > 1e-15:
            raise RuntimeError(f"take-up: no assembly at θ = {math.degrees(theta):.3f}°: {msg}")
        B = self.p["L_AB"] * _e(theta)
        C = B + self.p["L_BC"] * _e(q[0])
        d, c = self.D - B, C - B
        if d[0] * c[1] - d[1] * c[0] <= 0:
            raise RuntimeError(f"take-up: left the specified branch at θ = {math.degrees(theta):.3f}°")
        return q

    def motion(self, theta, q, omega):
        """E, dE/dt, d²E/dt² at constant crank speed, from the differentiated loop equation."""
        p = self.p
        J = np.column_stack([p["L_BC"] * _e1(q[0]), -p["L_CD"] * _e1(q[1])])
        dq = np.linalg.solve(J, -p["L_AB"] * _e1(theta))                       # per rad of crank
        rhs = p["L_AB"] * _e(theta) + p["L_BC"] * _e(q[0]) * dq[0] ** 2 - p["L_CD"] * _e(q[1]) * dq[1] ** 2
        ddq = np.linalg.solve(J, rhs)
        be = q[0] + p["angle_CBE"]
        E = p["L_AB"] * _e(theta) + p["L_BE"] * _e(be)
        dE = p["L_AB"] * _e1(theta) + p["L_BE"] * _e1(be) * dq[0]
        ddE = -p["L_AB"] * _e(theta) + p["L_BE"] * (_e1(be) * ddq[0] - _e(be) * dq[0] ** 2)
        return E, dE * omega, ddE * omega ** 2

    def first_guess(self, theta):
        """Some configuration with C to the left of B→D, for the first fsolve only."""
        B = self.p["L_AB"] * _e(theta)
        d = self.D - B
        left = np.array([-d[1], d[0]]) / np.hypot(*d)                        # normal to the left
        C = 0.5 * (B + self.D) + left * 0.02
        return np.array([math.atan2(*(C - B)[::-1]), math.atan2(*(C - self.D)[::-1])])


def path(thetas, p: dict = TAKEUP, omega: float = OMEGA):
    """E, its velocity and acceleration at the crank angles (continuation from the first)."""
    t = Takeup(p)
    q = t.first_guess(thetas[0])
    out = []
    for theta in thetas:
        q = t.solve(theta, q)
        out.append(t.motion(theta, q, omega))
    E, V, A = (np.array(x) for x in zip(*out))
    return E, V, A


UNITS = {"path_extent_z_mm": "mm", "path_extent_x_mm": "mm", "stroke_mm": "mm",
         "peak_speed_m_s": "m/s", "peak_acceleration_m_s2": "m/s2",
         "central_difference_step_deg": "deg", "central_difference_max_error_m_s": "m/s",
         "central_difference_max_error_percent_of_peak_speed": "%"}


def reference() -> tuple[dict, dict]:
    """(figures, notes) of scenario takeup over its last revolution, read as defined at the run's
    communication points θ = 0°, 0.5°, …, 360° (samples 720…1440). The central difference at a
    sample uses its two neighbours; the run's last sample has none, and the sample at 360° of the
    revolution repeats the one at 0°, so the error is the largest over the 720 distinct angles."""
    n = int(round(360 / STEP_DEG))
    thetas = np.radians(np.arange(-1, n + 2) * STEP_DEG)          # one neighbour either side
    E, V, A = path(thetas)
    inner = slice(1, n + 2)                                           # θ = 0 … 360°
    cd = (E[2:] - E[:-2]) / (2 * math.radians(STEP_DEG)) * OMEGA     # at θ = 0 … 360°
    speed = np.hypot(*V[inner].T)
    cd_error = np.hypot(*(cd - V[inner]).T)[:-1]                      # 0 … 359.5°
    diff = E[inner][:, None, :] - E[inner][None, :, :]
    stroke = float(np.sqrt((diff ** 2).sum(-1)).max())               # largest distance of two points
    figures = {
        "path_extent_z_mm": float(np.ptp(E[inner, 0]) * 1e3),
        "path_extent_x_mm": float(np.ptp(E[inner, 1]) * 1e3),
        "stroke_mm": stroke * 1e3,
        "peak_speed_m_s": float(speed.max()),
        "peak_acceleration_m_s2": float(np.hypot(*A[inner].T).max()),
        "central_difference_step_deg": STEP_DEG,
        "central_difference_max_error_m_s": float(cd_error.max()),
        "central_difference_max_error_percent_of_peak_speed": float(cd_error.max() / speed.max() * 100),
    }
    # for information: the same from a 10× finer grid (continuous extremes)
    fine_E, fine_V, fine_A = path(np.radians(np.arange(0, 10 * n + 1) * STEP_DEG / 10))
    notes = {"fine_grid": {"path_extent_z_mm": float(np.ptp(fine_E[:, 0]) * 1e3),
                           "path_extent_x_mm": float(np.ptp(fine_E[:, 1]) * 1e3),
                           "peak_speed_m_s": float(np.hypot(*fine_V.T).max()),
                           "peak_acceleration_m_s2": float(np.hypot(*fine_A.T).max())}}
    return figures, notes
