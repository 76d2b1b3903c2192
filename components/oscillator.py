"""The exact solution of a damped linear oscillator under polynomial forcing.

    m·y'' + b·y' + c·y = f0 + f1·τ + f2·τ²,   y(0) = y0, y'(0) = v0

Used wherever a piece of motion is linear with constant coefficients between communication points
or switches (the punch between contact switches, each mode of the carriage), so that the step
size is limited by the input's extrapolation, never by stability.
"""
from __future__ import annotations

import cmath
import math


class DampedOscillator:
    """Exact solution of m·y'' + b·y' + c·y = f0 + f1·τ + f2·τ² from (y0, v0) at τ = 0."""

    __slots__ = ("m", "b", "c", "f0", "f1", "f2", "p0", "p1", "p2", "l1", "l2", "k1", "k2",
                 "critical")

    def __init__(self, m, b, c, f0, f1, f2, y0, v0):
        self.m, self.b, self.c, self.f0, self.f1, self.f2 = m, b, c, f0, f1, f2
        # particular solution: a quadratic in τ
        self.p2 = f2 / c
        self.p1 = (f1 - 2.0 * b * self.p2) / c
        self.p0 = (f0 - b * self.p1 - 2.0 * m * self.p2) / c
        e0 = y0 - self.p0
        de0 = v0 - self.p1
        disc = b * b - 4.0 * m * c
        root = cmath.sqrt(disc)
        self.l1 = (-b + root) / (2.0 * m)
        self.l2 = (-b - root) / (2.0 * m)
        self.critical = abs(disc) <= 1e-12 * (b * b + 4.0 * m * c)
        if self.critical:           # repeated root: (k1 + k2·τ)·exp(l1·τ)
            self.l1 = self.l2 = -b / (2.0 * m)
            self.k1, self.k2 = e0, de0 - self.l1 * e0
        else:
            self.k2 = (de0 - self.l1 * e0) / (self.l2 - self.l1)
            self.k1 = e0 - self.k2

    def state(self, tau: float) -> tuple[float, float]:
        """(y, y') at τ."""
        py = self.p0 + tau * (self.p1 + tau * self.p2)
        pv = self.p1 + 2.0 * tau * self.p2
        if self.critical:
            ex = math.exp(self.l1.real * tau)
            e = (self.k1 + self.k2 * tau) * ex
            de = (self.k2 + self.l1.real * (self.k1 + self.k2 * tau)) * ex
            return py + e, pv + de
        x1 = self.k1 * cmath.exp(self.l1 * tau)
        x2 = self.k2 * cmath.exp(self.l2 * tau)
        return py + (x1 + x2).real, pv + (self.l1 * x1 + self.l2 * x2).real

    def accel(self, tau: float, y: float, v: float) -> float:
        return (self.f0 + tau * (self.f1 + tau * self.f2) - self.b * v - self.c * y) / self.m
