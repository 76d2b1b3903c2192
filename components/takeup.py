"""Thread take-up four-bar of an industrial sewing machine (docs/takeup.md).

Crank AB turns with the main shaft, coupler BC drives rocker CD about the frame pivot D, and the
take-up eye E, a point of the coupler triangle BCE, traces the "willow-leaf" path that feeds and
pulls back the thread each stitch. Frame: A = (0, 0), coordinates (Z, X), the crank angle θ = φ
measured from +Z.

The paper's printed formula for E uses φ_CD + ∠CBE; that makes the triangle BCE change shape
with the crank angle. The coupler angle is the right one: φ_BE = φ_BC + ∠CBE.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .kinematics import LEFT, Angle, Motion, angle, check_assembly, dyad_rrr, link_angle, point_on_link
from .parameters import ANY, parameter, validate


@dataclass(frozen=True)
class TakeupParams:
    L_AB: float = parameter(11.0e-3, "m", "crank AB")
    L_BC: float = parameter(32.0e-3, "m", "coupler BC")
    L_CD: float = parameter(24.0e-3, "m", "rocker CD (set by the eccentric pin: the thread amount)")
    L_BE: float = parameter(65.0e-3, "m", "coupler side BE, to the take-up eye E")
    angle_CBE: float = parameter(math.radians(70.0), "rad", "angle of the coupler triangle at B, "
                                 "from BC to BE (counter-clockwise)", ANY)
    z_D: float = parameter(26.0e-3, "m", "rocker pivot D, Z", ANY)
    x_D: float = parameter(-20.0e-3, "m", "rocker pivot D, X", ANY)


@dataclass(frozen=True)
class TakeupMotion:
    """Joints B, C, E and the link angles (rad) with their rates and accelerations."""
    B: Motion
    C: Motion
    E: Motion
    phi_BC: Angle
    phi_CD: Angle


class TakeupLinkage:
    """The four-bar as θ -> positions, velocities and accelerations (analytic)."""

    def __init__(self, params: TakeupParams = TakeupParams()):
        validate(params)
        self.p = params
        check_assembly(self.motion, "thread take-up four-bar", params, "crank angle theta")

    def motion(self, theta, omega=0.0, epsilon=0.0) -> TakeupMotion:
        """The linkage at crank angle theta (rad, from +Z), crank speed omega, acceleration epsilon."""
        p = self.p
        b = point_on_link(Motion(0.0, 0.0), p.L_AB, angle(theta, omega, epsilon))
        d = Motion(p.z_D, p.x_D)
        # the "+" root of the paper's closed form: C on the left of B -> D (larger Z)
        c = dyad_rrr(b, p.L_BC, d, p.L_CD, LEFT, name="coupler BC / rocker CD")
        phi_bc = link_angle(b, c)
        e = point_on_link(b, p.L_BE, phi_bc, offset=p.angle_CBE)
        return TakeupMotion(b, c, e, phi_bc, link_angle(d, c))
