"""Carriage of a sewing semi-automat's coordinate device: a 2-DOF modal model (MECHANISMS.md §2).

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

import numpy as np

from .oscillator import DampedOscillator
from .parameters import FRACTION, NONNEGATIVE, ParameterError, parameter, validate

_GAUSS_POINTS = 8            # per segment; the shapes are cubic pieces: exact for ∫ N·Nᵀ


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


def unit_deflection(z, s, EJ):
    """Deflection at z of a cantilever clamped at 0 under a unit force at s, and its second
    derivative (curvature)."""
    z = np.asarray(z, dtype=float)
    inner = z <= s
    w = np.where(inner, z * z * (3 * s - z), s * s * (3 * z - s)) / (6 * EJ)
    w2 = np.where(inner, (s - z), 0.0) / EJ
    return w, w2


def flexibility(p: CarriageParams) -> np.ndarray:
    """The cantilever's flexibility matrix at z = a and z = l (closed form)."""
    a, l, EJ = p.a, p.l, p.EJ
    f_al = a * a * (3 * l - a) / (6 * EJ)
    return np.array([[a ** 3 / (3 * EJ), f_al], [f_al, l ** 3 / (3 * EJ)]])


class CarriageModal:
    """Mass, stiffness, load vector, modes, and the exact step of the base-excited carriage."""

    def __init__(self, params: CarriageParams = CarriageParams()):
        validate(params)
        if not params.a < params.l:
            raise ParameterError("a", f"must lie on the cantilever, 0 < a < l = {params.l} m, "
                                      f"got {params.a}")
        self.p = params
        self.K = np.linalg.inv(flexibility(params))
        self.M, self.load = self._mass_and_load()
        # modes: K·φ = ω²·M·φ, mass-normalized (Φᵀ·M·Φ = I)
        lam, phi = _generalized_eigh(self.K, self.M)
        self.omega = np.sqrt(lam)
        self.modes = phi
        self.modal_load = phi.T @ self.load           # γ_i = φ_iᵀ·p

    # --- Ritz shapes ---------------------------------------------------------------------------
    def shapes(self, z):
        """N1(z), N2(z) and their second derivatives, arrays of shape (2, len(z))."""
        p = self.p
        wa, wa2 = unit_deflection(z, p.a, p.EJ)
        wl, wl2 = unit_deflection(z, p.l, p.EJ)
        return self.K.T @ np.vstack([wa, wl]), self.K.T @ np.vstack([wa2, wl2])

    def _quadrature(self):
        """Gauss points and weights on [0, a] and [a, l] (the shapes are cubic on each)."""
        x, w = np.polynomial.legendre.leggauss(_GAUSS_POINTS)
        zs, ws = [], []
        for lo, hi in ((0.0, self.p.a), (self.p.a, self.p.l)):
            zs.append(0.5 * (hi - lo) * x + 0.5 * (hi + lo))
            ws.append(0.5 * (hi - lo) * w)
        return np.concatenate(zs), np.concatenate(ws)

    def _mass_and_load(self):
        p = self.p
        z, w = self._quadrature()
        n, _ = self.shapes(z)
        beam = p.m_n / p.l * (n * w) @ n.T
        e1, e2 = np.array([1.0, 0.0]), np.array([0.0, 1.0])
        tilt = (e2 - e1) / (p.l - p.a)
        M = beam + p.m_k * np.outer(e2, e2) + p.J_c * np.outer(tilt, tilt)
        load = p.m_n / p.l * (n * w).sum(axis=1) + p.m_k * e2
        return M, load

    def energy_stiffness(self) -> np.ndarray:
        """EJ·∫ N''·N''ᵀ dz: the stiffness from the strain energy of the shapes (equals K)."""
        z, w = self._quadrature()
        _, n2 = self.shapes(z)
        return self.p.EJ * (n2 * w) @ n2.T

    # --- base-excited motion -------------------------------------------------------------------
    def static_deflection(self, a_base: float) -> np.ndarray:
        """U under a constant base acceleration: K·U = −p·a."""
        return -np.linalg.solve(self.K, self.load) * a_base

    def step(self, q: np.ndarray, dq: np.ndarray, a0: float, a1: float, h: float):
        """Modal coordinates q, q' after h under a(τ) = a0 + a1·τ: each mode exactly."""
        q_new, dq_new = np.empty(2), np.empty(2)
        for i in range(2):
            w = self.omega[i]
            g = -self.modal_load[i]
            mode = DampedOscillator(1.0, 2.0 * self.p.zeta * w, w * w, g * a0, g * a1, 0.0,
                                    q[i], dq[i])
            q_new[i], dq_new[i] = mode.state(h)
        return q_new, dq_new

    def physical(self, q: np.ndarray, dq: np.ndarray):
        """U and U' from the modal coordinates."""
        return self.modes @ q, self.modes @ dq


def _generalized_eigh(K, M):
    """Eigenpairs of K·φ = λ·M·φ, ascending, mass-normalized (2×2, via Cholesky of M)."""
    L = np.linalg.cholesky(M)
    Li = np.linalg.inv(L)
    lam, y = np.linalg.eigh(Li @ K @ Li.T)
    return lam, Li.T @ y


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

    def _law(self, phi):
        """Position and its first three derivatives with respect to φ."""
        p = self.p
        span = 2 * math.pi * p.window
        rel = np.asarray(phi, dtype=float) - p.phi_start
        stitch = np.floor(rel / (2 * math.pi))
        u = (rel - 2 * math.pi * stitch) / span
        moving = u < 1.0
        u = np.minimum(u, 1.0)
        c = 2 * math.pi * u
        s = p.stitch_length
        x = s * (stitch + np.where(moving, u - np.sin(c) / (2 * math.pi), 1.0))
        d1 = np.where(moving, s * (1 - np.cos(c)) / span, 0.0)
        d2 = np.where(moving, s * 2 * math.pi * np.sin(c) / span ** 2, 0.0)
        d3 = np.where(moving, s * (2 * math.pi) ** 2 * np.cos(c) / span ** 3, 0.0)
        return x, d1, d2, d3

    def _position(self, phi):
        return float(self._law(phi)[0])

    def motion(self, phi, omega, epsilon):
        """x, v, a, jerk of the table for shaft angle, speed and acceleration (the shaft's
        acceleration is taken as constant over the instant: its derivative does not enter)."""
        x, d1, d2, d3 = self._law(phi)
        v = d1 * omega
        acc = d2 * omega ** 2 + d1 * epsilon
        jerk = d3 * omega ** 3 + 3 * d2 * omega * epsilon
        return x - self.x0, v, acc, jerk
