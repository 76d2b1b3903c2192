"""The carriage's key figures (scenario carriage_startstop) computed independently of sewfmu, from
the papers as docs/carriage.md.

Nothing here imports sewfmu. The stiffness is the inverse of the cantilever's flexibility matrix
(closed form); the Ritz shapes are the static deflection lines built from it; the mass matrix and
the load vector p are integrated by adaptive quadrature (scipy.integrate.quad, split at z = a);
the frequencies come from a general symmetric-definite eigen-solver (scipy.linalg.eigh). The
start-stop response is the 2-DOF system M·Ü + C·U̇ + K·U = −p·a(t) integrated by solve_ivp with the
drive's continuous cycloidal a(t) (no step-wise linearisation of the input), one transport window
or rest at a time so that the integrator never steps across the jumps of da/dt.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import quad, solve_ivp
from scipy.linalg import eigh

# defaults of docs/carriage.md (SI units)
CARRIAGE = {"l": 0.515, "a": 0.22, "EJ": 2604.0, "m_n": 1.0, "m_k": 2.5, "J_c": 0.1178,
            "zeta": 0.02}
DRIVE = {"stitch_length": 0.003, "window": 0.5, "phi_start": 0.0}
OMEGA = 1600 * 2 * math.pi / 60     # rad/s: carriage_startstop's 1600 stitches/min
REVOLUTIONS = 60
STEPS_PER_REVOLUTION = 360          # the scenario's communication step: 1° of crank
RTOL, ATOL = 1e-11, 1e-15           # U is of the order of 1e-3 m


def _deflection(z, s, EJ):
    """Deflection at z of a cantilever clamped at z = 0 under a unit force at s (beam tables)."""
    return z * z * (3 * s - z) / (6 * EJ) if z <= s else s * s * (3 * z - s) / (6 * EJ)


class Model:
    """K, M, p, C of the 2-DOF Ritz model, and its natural frequencies."""

    def __init__(self, c: dict = CARRIAGE):
        l, a, EJ = c["l"], c["a"], c["EJ"]
        flex = np.array([[_deflection(a, a, EJ), _deflection(a, l, EJ)],
                         [_deflection(l, a, EJ), _deflection(l, l, EJ)]])
        self.K = np.linalg.inv(flex)
        # shapes: U(z) = [δ(z, a), δ(z, l)]·F with the forces F = K·U, i.e. N(z) = [δ(z,a), δ(z,l)]·K
        shape = lambda z: np.array([_deflection(z, a, EJ), _deflection(z, l, EJ)]) @ self.K
        integral = lambda f: quad(f, 0.0, l, points=[a], epsabs=0.0, epsrel=1e-13, limit=200)[0]
        beam = np.array([[integral(lambda z, i=i, j=j: shape(z)[i] * shape(z)[j]) for j in range(2)]
                         for i in range(2)])
        rot = np.array([[1.0, -1.0], [-1.0, 1.0]]) * c["J_c"] / (l - a) ** 2
        self.M = c["m_n"] / l * beam + np.diag([0.0, c["m_k"]]) + rot
        self.p = c["m_n"] / l * np.array([integral(lambda z, i=i: shape(z)[i]) for i in range(2)])
        self.p[1] += c["m_k"]
        w2, phi = eigh(self.K, self.M)           # mass-normalised: φᵀ·M·φ = I
        self.omega = np.sqrt(w2)
        # modal damping ζ in both modes: φᵀ·C·φ = diag(2ζω)  →  C = M·φ·diag(2ζω)·φᵀ·M
        self.C = self.M @ phi @ np.diag(2 * c["zeta"] * self.omega) @ phi.T @ self.M


def table_acceleration(phi, omega, d: dict = DRIVE):
    """The drive's a(φ) at constant shaft speed: one stitch length per revolution during the
    window, cycloidal: x = s·(u − sin(2πu)/(2π)), u = (φ − φ_start)/(2π·window) in [0, 1]."""
    span = 2 * math.pi * d["window"]
    u = ((phi - d["phi_start"]) % (2 * math.pi)) / span
    moving = u < 1.0
    return np.where(moving, d["stitch_length"] * 2 * math.pi * np.sin(2 * math.pi * u) / span ** 2,
                    0.0) * omega ** 2


def response(model: Model, omega: float = OMEGA, revolutions: int = REVOLUTIONS,
             steps: int = STEPS_PER_REVOLUTION, d: dict = DRIVE, method: str = "DOP853",
             rtol: float = RTOL, atol: float = ATOL):
    """(t, U) at the scenario's communication points t_k = k·T/steps, from rest (the static
    deflection under a(0) = 0), and the largest |U2| of the continuous solution."""
    minv = np.linalg.inv(model.M)

    def rhs(t, x):
        u, v = x[:2], x[2:]
        a = float(table_acceleration(omega * t, omega, d))
        return np.concatenate([v, minv @ (-model.p * a - model.C @ v - model.K @ u)])

    period = 2 * math.pi / omega
    # pieces between the window's ends, where da/dt jumps
    edges = sorted({k * period + off for k in range(revolutions + 1)
                    for off in (d["phi_start"] / omega, (d["phi_start"] / omega + d["window"] * period))
                    if k * period + off <= revolutions * period} | {0.0, revolutions * period})
    t_samples = np.arange(revolutions * steps + 1) * (period / steps)
    U = np.empty((2, len(t_samples)))
    x = np.zeros(4)
    peak_u2 = 0.0
    for t0, t1 in zip(edges[:-1], edges[1:]):
        if t1 - t0 < 1e-15:
            continue
        sol = solve_ivp(rhs, (t0, t1), x, method=method, rtol=rtol, atol=atol, dense_output=True)
        if not sol.success:
            raise RuntimeError(sol.message)
        x = sol.y[:, -1]
        inside = (t_samples >= t0) & (t_samples <= t1)
        U[:, inside] = sol.sol(t_samples[inside])[:2]
        fine = sol.sol(np.linspace(t0, t1, 400))[1]
        peak_u2 = max(peak_u2, float(np.abs(fine).max()))
    return t_samples, U, peak_u2


def table_jerk(phi, omega, d: dict = DRIVE):
    """da/dt of the cycloidal law at constant shaft speed (0 at rest)."""
    span = 2 * math.pi * d["window"]
    u = ((phi - d["phi_start"]) % (2 * math.pi)) / span
    return np.where(u < 1.0, d["stitch_length"] * (2 * math.pi) ** 2 * np.cos(2 * math.pi * u)
                    / span ** 3, 0.0) * omega ** 3


def response_stepwise_input(model: Model, omega: float = OMEGA, revolutions: int = REVOLUTIONS,
                            steps: int = STEPS_PER_REVOLUTION, d: dict = DRIVE):
    """U at the communication points when, as in the co-simulation (Jacobi), the carriage sees
    over each step the input a(t_k) + da/dt(t_k)·(t − t_k) from the drive's outputs at the step's
    start. Solved exactly by the matrix exponential of the system augmented with the input's
    two states (scipy.linalg.expm), not by sewfmu's modal formulas. This separates the coupling
    error (the linearised input) from everything else."""
    from scipy.linalg import expm

    minv = np.linalg.inv(model.M)
    h = 2 * math.pi / omega / steps
    A = np.zeros((6, 6))                  # state (U, U̇, a, da/dt)
    A[0:2, 2:4] = np.eye(2)
    A[2:4, 0:2] = -minv @ model.K
    A[2:4, 2:4] = -minv @ model.C
    A[2:4, 4] = -minv @ model.p
    A[4, 5] = 1.0
    step = expm(A * h)
    t = np.arange(revolutions * steps + 1) * h
    a, jerk = table_acceleration(omega * t, omega, d), table_jerk(omega * t, omega, d)
    U = np.empty((2, len(t)))
    x = np.zeros(4)
    U[:, 0] = x[:2]
    for k in range(len(t) - 1):
        x = step[:4] @ np.concatenate([x, [a[k], jerk[k]]])
        U[:, k + 1] = x[:2]
    return t, U


UNITS = {"omega1": "rad/s", "omega2": "rad/s", "stitch_rate_per_min": "1/min",
         "peak_abs_U2_last_stitch_um": "um", "peak_abs_U2_um": "um"}


def reference(method: str = "DOP853", rtol: float = RTOL, atol: float = ATOL) -> tuple[dict, dict]:
    """(figures, notes) of carriage_startstop. The peaks are read, as the figures are defined,
    at the run's communication points (every 1° of crank); the last stitch is the last whole
    revolution, both ends included."""
    model = Model()
    t, U, peak_continuous = response(model, method=method, rtol=rtol, atol=atol)
    last = t >= t[-1] - 2 * math.pi / OMEGA - 1e-12
    u2 = np.abs(U[1])
    figures = {"omega1": float(model.omega[0]), "omega2": float(model.omega[1]),
               "stitch_rate_per_min": OMEGA * 60 / (2 * math.pi),
               "peak_abs_U2_last_stitch_um": float(u2[last].max() * 1e6),
               "peak_abs_U2_um": float(u2.max() * 1e6)}
    # the co-simulation's input model (linear over each step from a and da/dt at its start), for
    # the size of the coupling error alone
    t_s, U_s = response_stepwise_input(model)
    notes = {"peak_abs_U2_continuous_um": peak_continuous * 1e6,
             "with_stepwise_linear_input": {
                 "peak_abs_U2_last_stitch_um": float(np.abs(U_s[1][last]).max() * 1e6),
                 "peak_abs_U2_um": float(np.abs(U_s[1]).max() * 1e6)},
             "K": model.K.tolist(), "M": model.M.tolist(), "p": model.p.tolist()}
    return figures, notes
