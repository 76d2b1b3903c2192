"""Punch drive of the ultrasonic sewing machine: the six-bar linkage that lifts the punch.

Crank O1A turns with the main shaft, coupler AB rocks the bell-crank B-O2-C, and rod CD drives the
slider D along the vertical line x = x_D (docs/punch_drive.md). The slider's fall from its highest
point is the displacement function psi(phi) >= 0; the punch's kinematic excitation is
xi = xi0 - psi, its height above the fabric when it follows the slider.

The crank turns clockwise as the shaft angle phi grows: alpha = alpha0 - phi, where alpha0 is the
crank angle of the slider's top (found at construction), so phi = 0 is the setup position.

A second mode replaces the linkage by the paper's "required displacement function": a cycloidal
descent to psi_m, a dwell, a cycloidal return and rest at the top.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import NamedTuple

try:   # written into an FMU by `sewfmu build`: {repr(parameters): _top_of(parameters)}
    from .assembly_table import BUILT_TOPS
except ImportError:      # the model code outside an FMU: each parameter set checked when used
    BUILT_TOPS: dict[str, tuple[float, float]] = {}
from .kinematics import (
    RIGHT,
    Motion,
    angle,
    check_assembly,
    crank_turn,
    dyad_rrp,
    dyad_rrr,
    link_angle,
    point_on_link,
)
from .parameters import ANY, CHOICE, NONNEGATIVE, ParameterError, parameter, validate

SIX_BAR = 0
REQUIRED_DISPLACEMENT = 1

# the assembly check samples the whole crank turn this finely (0.1°)
_ASSEMBLY_SAMPLES = 3600
_O1 = Motion(0.0, 0.0)       # the crank pivot, at rest at the origin (immutable: made once)


@dataclass(frozen=True)
class PunchLinkageParams:
    mode: int = parameter(SIX_BAR, "1", "0: six-bar linkage, 1: required displacement function",
                          CHOICE, choices=(SIX_BAR, REQUIRED_DISPLACEMENT))
    L_O1A: float = parameter(6.0e-3, "m", "crank O1A")
    L_AB: float = parameter(39.0e-3, "m", "coupler AB")
    L_O2B: float = parameter(10.0e-3, "m", "rocker arm O2B")
    L_O2C: float = parameter(7.1e-3, "m", "bell-crank arm O2C, rigid with the rocker")
    angle_BO2C: float = parameter(math.radians(110.0), "rad",
                                  "angle from arm O2B clockwise to arm O2C")
    L_CD: float = parameter(65.0e-3, "m", "connecting rod CD to the slider")
    x_O2: float = parameter(0.0, "m", "rocker pivot O2, x", ANY)
    y_O2: float = parameter(40.0e-3, "m", "rocker pivot O2, y (crank pivot O1 at the origin)", ANY)
    x_D: float = parameter(0.0, "m", "the slider D moves on the vertical line x = x_D", ANY)
    xi0: float = parameter(4.5e-3, "m", "maximum lift of the punch above the fabric", NONNEGATIVE)
    psi_m: float = parameter(5.0e-3, "m", "required displacement: depth of the descent")
    phi_descent: float = parameter(math.radians(150.0), "rad", "required displacement: descent angle")
    phi_dwell: float = parameter(math.radians(60.0), "rad", "required displacement: dwell angle at psi_m",
                                 NONNEGATIVE)
    phi_return: float = parameter(math.radians(150.0), "rad", "required displacement: return angle")


# a named tuple rather than a frozen dataclass (immutable all the same): made at every step of
# the FMU, and a tuple is made several times faster
class Excitation(NamedTuple):
    """psi and xi with their time derivatives."""
    psi: float
    xi: float
    xi_dot: float
    xi_ddot: float


class PunchLinkage:
    """Six-bar punch drive, or the required displacement function, as phi -> xi(phi)."""

    def __init__(self, params: PunchLinkageParams = PunchLinkageParams()):
        validate(params)
        self.p = params
        if params.mode == SIX_BAR:
            self.alpha0, self.y_top = _top_of(params)
        else:
            if params.phi_descent + params.phi_dwell + params.phi_return > 2 * math.pi + 1e-12:
                raise ParameterError("phi_return", "phi_descent + phi_dwell + phi_return must not "
                                                   "exceed one revolution (2π rad)")
            self.alpha0 = 0.0
            self.y_top = 0.0

    # --- six-bar -----------------------------------------------------------------------------
    def joints(self, alpha, alpha_rate=0.0, alpha_accel=0.0) -> dict[str, Motion]:
        """Motion of every joint (O1, A, O2, B, C, D) for crank angle alpha (CCW from +x)."""
        return dict(zip(("O1", "A", "O2", "B", "C", "D"),
                        self._chain(alpha, alpha_rate, alpha_accel)))

    def _chain(self, alpha, alpha_rate, alpha_accel) -> tuple[Motion, ...]:
        p = self.p
        o1 = _O1
        o2 = Motion(p.x_O2, p.y_O2)
        a = point_on_link(o1, p.L_O1A, angle(alpha, alpha_rate, alpha_accel))
        # B on the +x side of A -> O2, i.e. on the right of that (upward) line
        b = dyad_rrr(a, p.L_AB, o2, p.L_O2B, RIGHT, name="coupler AB / rocker O2B")
        rocker = link_angle(o2, b)
        c = point_on_link(o2, p.L_O2C, rocker, offset=-p.angle_BO2C)
        # D below C on the vertical line x = x_D
        d = dyad_rrp(c, p.L_CD, (p.x_D, 0.0), math.pi / 2, -1, name="rod CD / slider line")
        return o1, a, o2, b, c, d

    def slider(self, alpha, alpha_rate, alpha_accel) -> Motion:
        """Motion of the slider D for crank angle alpha (CCW from +x) and its derivatives (the
        FMU's every step: the joints without their dict)."""
        return self._chain(alpha, alpha_rate, alpha_accel)[5]

    def _top(self) -> tuple[float, float]:
        """(crank angle, slider height) of the slider's highest point, after checking that the
        six-bar assembles over the whole turn (AssemblyError naming the crank angle if not)."""
        heights = check_assembly(lambda alpha: self.slider(alpha, 0.0, 0.0).y, "punch six-bar",
                                 self.p, "crank angle alpha", _ASSEMBLY_SAMPLES)
        alpha0 = self._crank_angle_of_top(heights)
        return alpha0, self.slider(alpha0, 0.0, 0.0).y

    def _crank_angle_of_top(self, heights: list[float]) -> float:
        """Crank angle of the slider's highest point: where dY_D/dalpha changes sign + to -
        (`heights`: the slider's Y_D at the crank angles of the assembly check)."""
        alpha = crank_turn(_ASSEMBLY_SAMPLES)
        k = max(range(len(heights)), key=heights.__getitem__)
        lo, hi = alpha[k] - 2 * math.pi / _ASSEMBLY_SAMPLES, alpha[k] + 2 * math.pi / _ASSEMBLY_SAMPLES

        def slope(a: float) -> float:      # dY_D/dalpha, analytic (crank rate 1)
            return self.slider(float(a), 1.0, 0.0).vy

        for _ in range(60):                # bisection on the slope: robust and exact enough
            mid = 0.5 * (lo + hi)
            if slope(mid) > 0:
                lo = mid
            else:
                hi = mid
        return 0.5 * (lo + hi) % (2 * math.pi)

    # --- required displacement -----------------------------------------------------------------
    def _required(self, phi: float) -> tuple[float, float, float]:
        """psi and its first two derivatives with respect to phi."""
        p = self.p
        th = phi % (2 * math.pi)
        descent_end = p.phi_descent
        dwell_end = descent_end + p.phi_dwell
        return_end = dwell_end + p.phi_return
        if th < descent_end:
            start, width, sign = 0.0, p.phi_descent, +1.0
        elif th < dwell_end:
            return p.psi_m, 0.0, 0.0
        elif th < return_end:
            start, width, sign = dwell_end, p.phi_return, -1.0
        else:
            return 0.0, 0.0, 0.0                                   # at rest at the top
        u = (th - start) / width
        s = u - math.sin(2 * math.pi * u) / (2 * math.pi)          # cycloidal law
        psi = p.psi_m * (s if sign > 0 else 1.0 - s)
        d1 = sign * p.psi_m * (1.0 - math.cos(2 * math.pi * u)) / width
        d2 = sign * p.psi_m * 2 * math.pi * math.sin(2 * math.pi * u) / width ** 2
        return psi, d1, d2

    # --- the excitation of the punch -------------------------------------------------------------
    def motion(self, phi: float, omega: float, epsilon: float) -> Excitation:
        """psi, xi, dxi/dt, d2xi/dt2 for shaft angle phi (rad), speed omega, acceleration epsilon."""
        if self.p.mode == SIX_BAR:
            d = self.slider(self.alpha0 - phi, -omega, -epsilon)
            psi = self.y_top - d.y
            return Excitation(psi, self.p.xi0 - psi, d.vy, d.ay)
        psi, d1, d2 = self._required(phi)
        # xi = xi0 - psi(phi): chain rule with phi' = omega, phi'' = epsilon
        return Excitation(psi, self.p.xi0 - psi, -d1 * omega, -(d2 * omega ** 2 + d1 * epsilon))


@functools.lru_cache(maxsize=64)
def _top_of(params: PunchLinkageParams) -> tuple[float, float]:
    """PunchLinkage._top for these parameters, worked out once per parameter set in a process
    (3600 crank angles, about 36 ms): the instances of a sweep's points, the monolithic solution
    and the plots share it. A pure function of frozen parameters, so instances stay independent;
    a failure is not kept (each instance reports it). In an FMU, the default parameters' was
    worked out (and so checked) when it was built: BUILT_TOPS."""
    known = BUILT_TOPS.get(repr(params))
    if known is not None:
        return known
    bare = object.__new__(PunchLinkage)     # its kinematics need nothing but the parameters
    bare.p = params
    return bare._top()
