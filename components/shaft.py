"""The machine's main shaft: the one input that drives every mechanism.

The shaft turns at omega0 after an optional smooth start (a cycloidal speed ramp of duration
ramp_time, zero acceleration at both ends of the ramp). Its angle is cumulative (not wrapped), so
one stitch is one revolution of 2π.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .parameters import NONNEGATIVE, parameter, validate


@dataclass(frozen=True)
class ShaftParams:
    omega0: float = parameter(100.0, "rad/s", "shaft speed (after the start ramp)")
    ramp_time: float = parameter(0.0, "s", "duration of the smooth start from rest; 0: no ramp",
                                 NONNEGATIVE)


class MainShaft:
    """Shaft angle, speed and acceleration as closed-form functions of time."""

    def __init__(self, params: ShaftParams = ShaftParams()):
        validate(params)
        self.p = params

    def state(self, t: float) -> tuple[float, float, float]:
        """(phi, omega, epsilon) at time t >= 0."""
        w, tr = self.p.omega0, self.p.ramp_time
        if t >= tr:
            # the ramp covers omega0*tr/2 of angle (mean speed omega0/2)
            return w * (t - 0.5 * tr), w, 0.0
        u = t / tr
        two_pi_u = 2.0 * math.pi * u
        omega = w * (u - math.sin(two_pi_u) / (2.0 * math.pi))
        phi = w * tr * (0.5 * u * u + (math.cos(two_pi_u) - 1.0) / (4.0 * math.pi ** 2))
        epsilon = w / tr * (1.0 - math.cos(two_pi_u))
        return phi, omega, epsilon

    def time_of_angle(self, phi: float) -> float:
        """The time at which the shaft has turned through `phi` (inverse of state()[0])."""
        w, tr = self.p.omega0, self.p.ramp_time
        if phi >= 0.5 * w * tr:
            return phi / w + 0.5 * tr
        lo, hi = 0.0, tr            # phi(t) is increasing on the ramp: bisect
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if self.state(mid)[0] < phi:
                lo = mid
            else:
                hi = mid
        return 0.5 * (lo + hi)
