"""Carriage of a sewing semi-automat's coordinate device: a 2-DOF modal model (docs/carriage.md).

While it accelerates, the carriage bears on one guide, a cantilever of length l clamped to the
traverse at z = 0 (bending stiffness EJ, mass m_n spread uniformly). The carriage (mass m_k,
moment of inertia J_c) rests on it at A (z = a) and B (z = l). Generalized coordinates: the
deflections U1 at A and U2 at B. Ritz shapes: the cantilever's static deflection line under point
forces at A and B, written through U1 and U2, so that

    K = F⁻¹   (F: the cantilever's flexibility matrix at a and l, closed form)
    M = m_k·e2·e2ᵀ + J_c/(l − a)²·(e2 − e1)(e2 − e1)ᵀ + (m_n/l)·∫ N·Nᵀ dz

The paper prints ω1 = 180.2 and ω2 = 6184 rad/s for the defaults. Its own model does not give
them: ω1 follows only with M halved (the factor 2 of d/dt ∂T/∂U̇ dropped), and no reading gives
ω2. This module computes the frequencies from the model and never uses the printed numbers.

Base excitation (not in the paper, needed for co-simulation): the drive accelerates the traverse
root with a(t). Relative to it,  M·Ü + C·U̇ + K·U = −p·a(t)  with p_i = (m_n/l)·∫ N_i dz + m_k·δ_i2
(the virtual work of the inertia of a rigid base motion; p ≠ M·(1, 1)ᵀ because the Ritz shapes
with U1 = U2 = 1 are not a rigid translation). C comes from the modal damping ratio zeta. Each
mode is integrated exactly for an input that varies linearly over the step.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from .oscillator import DampedOscillator
from .parameters import FRACTION, NONNEGATIVE, ParameterError, parameter, validate

Vector = tuple[float, float]
Matrix = tuple[Vector, Vector]          # rows


@dataclass(frozen=True)
class CarriageParams:
    l: float = parameter(0.515, "m", "length of the guide cantilever (carriage section B at z = l)")
    a: float = parameter(0.22, "m", "section A of the carriage on the cantilever (0 < a < l)")
    EJ: float = parameter(2604.0, "N.m2", "bending stiffness of the guide")
    m_n: float = parameter(1.0, "kg", "mass of the guide, spread uniformly")
    m_k: float = parameter(2.5, "kg", "mass of the carriage with cassette and work")
    J_c: float = parameter(0.1178, "kg.m2", "moment of inertia of the carriage about its centre")
    zeta: float = parameter(0.02, "1", "modal damping ratio of both modes (not in the paper)",
                            NONNEGATIVE)


def unit_deflection(z: float, s: float, EJ: float) -> tuple[float, float]:
    """Deflection at z of a cantilever clamped at 0 under a unit force at s, and its second
    derivative (curvature)."""
    if z <= s:
        return z * z * (3 * s - z) / (6 * EJ), (s - z) / EJ
    return s * s * (3 * z - s) / (6 * EJ), 0.0


def flexibility(p: CarriageParams) -> Matrix:
    """The cantilever's flexibility matrix at z = a and z = l (closed form)."""
    a, l, EJ = p.a, p.l, p.EJ
    f_al = a * a * (3 * l - a) / (6 * EJ)
    return ((a ** 3 / (3 * EJ), f_al), (f_al, l ** 3 / (3 * EJ)))


def _inverse(A: Matrix) -> Matrix:
    det = A[0][0] * A[1][1] - A[0][1] * A[1][0]
    return ((A[1][1] / det, -A[0][1] / det), (-A[1][0] / det, A[0][0] / det))


def _times(A: Matrix, x: Vector) -> Vector:
    return (A[0][0] * x[0] + A[0][1] * x[1], A[1][0] * x[0] + A[1][1] * x[1])


def _gauss_points(lo: float, hi: float):
    """4-point Gauss–Legendre nodes and weights on [lo, hi] (closed form): exact up to degree 7,
    and the products of the cubic shapes are of degree 6."""
    half, mid = 0.5 * (hi - lo), 0.5 * (hi + lo)
    for x, w in _GAUSS_4:
        yield mid + half * x, half * w


_GAUSS_4 = tuple((sign * math.sqrt(3 / 7 + k * 2 / 7 * math.sqrt(6 / 5)),
                  (18 - k * math.sqrt(30)) / 36) for k in (-1, 1) for sign in (-1, 1))


class CarriageModal:
    """Mass, stiffness, load vector, modes, and the exact step of the base-excited carriage.

    Matrices are tuples of rows, vectors tuples: 2×2 closed forms, standard library only (this
    code runs inside the FMU)."""

    def __init__(self, params: CarriageParams = CarriageParams()):
        validate(params)
        if not params.a < params.l:
            raise ParameterError("a", f"must lie on the cantilever, 0 < a < l = {params.l} m, "
                                      f"got {params.a}")
        self.p = params
        self.F = flexibility(params)
        self.K = _inverse(self.F)
        self.M, self.load = self._mass_and_load()
        # modes: K·φ = ω²·M·φ, mass-normalized (Φᵀ·M·Φ = I); columns of `modes` are the φ_i
        lam, self.modes = _generalized_eigen(self.K, self.M)
        self.omega = tuple(math.sqrt(x) for x in lam)
        self.modal_load = tuple(self.modes[0][i] * self.load[0] + self.modes[1][i] * self.load[1]
                                for i in range(2))            # γ_i = φ_iᵀ·p

    # --- Ritz shapes ---------------------------------------------------------------------------
    def shapes(self, z: float) -> tuple[Vector, Vector]:
        """(N1(z), N2(z)) and their second derivatives."""
        p, K = self.p, self.K
        wa, wa2 = unit_deflection(z, p.a, p.EJ)
        wl, wl2 = unit_deflection(z, p.l, p.EJ)
        # N = Kᵀ·(w_a, w_l): the deflection line through U1 at a and U2 at l
        return ((K[0][0] * wa + K[1][0] * wl, K[0][1] * wa + K[1][1] * wl),
                (K[0][0] * wa2 + K[1][0] * wl2, K[0][1] * wa2 + K[1][1] * wl2))

    def _quadrature(self):
        """Gauss points and weights on [0, a] and [a, l] (the shapes are cubic on each)."""
        return [*_gauss_points(0.0, self.p.a), *_gauss_points(self.p.a, self.p.l)]

    def _mass_and_load(self) -> tuple[Matrix, Vector]:
        p = self.p
        beam = [[0.0, 0.0], [0.0, 0.0]]
        integral = [0.0, 0.0]
        for z, w in self._quadrature():
            n, _ = self.shapes(z)
            for i in range(2):
                integral[i] += w * n[i]
                for j in range(2):
                    beam[i][j] += w * n[i] * n[j]
        rho = p.m_n / p.l
        tilt = p.J_c / (p.l - p.a) ** 2          # J_c·((U2 − U1)/(l − a))²: the carriage's tilt
        M = ((rho * beam[0][0] + tilt, rho * beam[0][1] - tilt),
             (rho * beam[1][0] - tilt, rho * beam[1][1] + tilt + p.m_k))
        load = (rho * integral[0], rho * integral[1] + p.m_k)
        return M, load

    # --- base-excited motion -------------------------------------------------------------------
    def static_deflection(self, a_base: float) -> Vector:
        """U under a constant base acceleration: K·U = −p·a, so U = −F·p·a."""
        u = _times(self.F, self.load)
        return (-u[0] * a_base, -u[1] * a_base)

    def modal(self, U: Vector) -> Vector:
        """Modal coordinates of the deflections U: q = Φᵀ·M·U (Φ is mass-normalized)."""
        mu = _times(self.M, U)
        return tuple(self.modes[0][i] * mu[0] + self.modes[1][i] * mu[1] for i in range(2))

    def step(self, q: Vector, dq: Vector, a0: float, a1: float, h: float) -> tuple[Vector, Vector]:
        """Modal coordinates q, q' after h under a(τ) = a0 + a1·τ: each mode exactly."""
        new = []
        for i in range(2):
            w = self.omega[i]
            g = -self.modal_load[i]
            mode = DampedOscillator(1.0, 2.0 * self.p.zeta * w, w * w, g * a0, g * a1, 0.0,
                                    q[i], dq[i])
            new.append(mode.state(h))
        return (new[0][0], new[1][0]), (new[0][1], new[1][1])

    def physical(self, q: Vector, dq: Vector) -> tuple[Vector, Vector]:
        """U and U' from the modal coordinates."""
        return _times(self.modes, q), _times(self.modes, dq)


def _generalized_eigen(K: Matrix, M: Matrix) -> tuple[Vector, Matrix]:
    """Eigenpairs of K·φ = λ·M·φ (K, M symmetric, M positive definite), λ ascending, φ
    mass-normalized and its largest component positive; closed form: det(K − λ·M) = 0 is a
    quadratic in λ."""
    a = M[0][0] * M[1][1] - M[0][1] ** 2
    b = -(K[0][0] * M[1][1] + K[1][1] * M[0][0] - 2.0 * K[0][1] * M[0][1])
    c = K[0][0] * K[1][1] - K[0][1] ** 2
    root = math.sqrt(max(b * b - 4.0 * a * c, 0.0))
    # the larger root without cancellation, the smaller from the product of the roots
    big = (-b + root) / (2.0 * a)
    lams = (c / (a * big), big)
    vectors = []
    for lam in lams:
        r0 = (K[0][0] - lam * M[0][0], K[0][1] - lam * M[0][1])
        r1 = (K[1][0] - lam * M[1][0], K[1][1] - lam * M[1][1])
        row = r0 if math.hypot(*r0) >= math.hypot(*r1) else r1
        v = (-row[1], row[0])                         # orthogonal to the better-conditioned row
        norm = math.sqrt(v[0] * (M[0][0] * v[0] + M[0][1] * v[1])
                         + v[1] * (M[1][0] * v[0] + M[1][1] * v[1]))
        sign = 1.0 if max(v, key=abs) > 0 else -1.0
        vectors.append((sign * v[0] / norm, sign * v[1] / norm))
    modes = ((vectors[0][0], vectors[1][0]), (vectors[0][1], vectors[1][1]))
    return lams, modes


class TableMotion(NamedTuple):
    """The table's position, velocity, acceleration and jerk along the motion axis."""
    x: float
    v: float
    a: float
    jerk: float


# --- the start-stop drive -----------------------------------------------------------------------
@dataclass(frozen=True)
class CarriageDriveParams:
    stitch_length: float = parameter(3.0e-3, "m", "advance of the table per stitch")
    window: float = parameter(0.5, "1", "transport window: fraction of the shaft revolution "
                              "during which the table moves", FRACTION)
    phi_start: float = parameter(0.0, "rad", "shaft angle at which each transport window begins",
                                 NONNEGATIVE)


class CarriageDrive:
    """Stitch-synchronized start-stop table motion: in each revolution the table advances one
    stitch length during the transport window, with a cycloidal law (zero velocity and
    acceleration at both ends), and rests otherwise. x = 0 at φ = 0."""

    def __init__(self, params: CarriageDriveParams = CarriageDriveParams()):
        validate(params)
        self.p = params
        self.x0 = self._position(0.0)

    def _law(self, phi: float) -> tuple[float, float, float, float]:
        """Position and its first three derivatives with respect to φ."""
        p = self.p
        span = 2 * math.pi * p.window
        rel = phi - p.phi_start
        stitch = math.floor(rel / (2 * math.pi))
        u = (rel - 2 * math.pi * stitch) / span
        s = p.stitch_length
        if u >= 1.0:                  # at rest after this stitch's transport window
            return s * (stitch + 1.0), 0.0, 0.0, 0.0
        c = 2 * math.pi * u
        x = s * (stitch + u - math.sin(c) / (2 * math.pi))
        d1 = s * (1 - math.cos(c)) / span
        d2 = s * 2 * math.pi * math.sin(c) / span ** 2
        d3 = s * (2 * math.pi) ** 2 * math.cos(c) / span ** 3
        return x, d1, d2, d3

    def _position(self, phi: float) -> float:
        return self._law(phi)[0]

    def motion(self, phi: float, omega: float, epsilon: float) -> "TableMotion":
        """x, v, a, jerk of the table for shaft angle, speed and acceleration (the shaft's
        acceleration is taken as constant over the instant: its derivative does not enter)."""
        x, d1, d2, d3 = self._law(phi)
        v = d1 * omega
        acc = d2 * omega ** 2 + d1 * epsilon
        jerk = d3 * omega ** 3 + 3 * d2 * omega * epsilon
        return TableMotion(x - self.x0, v, acc, jerk)
