"""Closed lever-hinge material feed mechanism of a sewing machine (docs/feed.md).

One crank shaft at A drives two branches. Lift branch: arm A-B, rod 2 (B-C), lever 3 rocking
about D (arms D-C and D-E). Feed branch: arm A-K, rod 8 (K-N), bell crank 7 rocking about G
(arms G-N and G-H). The closing pair, rod 4 (E-F) and the feed-bar lever 5 (H-F), carries the
feed-dog point M on lever 5: its closed path is the feed-dog path.

The paper's printed data cannot be assembled (a 28 mm crank with 225 mm rods and 28-30 mm
rockers would swing the rockers through about 140°, not the printed 13.7° and 18.4°, and the
rock-shaft positions are missing). The defaults keep every printed length but the crank radii,
chosen to reproduce the printed swings, and place the rock shafts D and G.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .kinematics import LEFT, RIGHT, Angle, Motion, angle, check_assembly, dyad_rrr, link_angle, point_on_link
from .parameters import ANY, parameter, validate


@dataclass(frozen=True)
class FeedParams:
    r_l: float = parameter(3.5781e-3, "m", "lift crank arm A-B")
    r_f: float = parameter(4.4767e-3, "m", "feed crank arm A-K")
    alpha1: float = parameter(math.radians(116.0), "rad", "angle from the lift arm to the feed arm",
                              ANY)
    l2: float = parameter(225.0e-3, "m", "rod 2 (B-C), lift branch")
    l8: float = parameter(225.0e-3, "m", "rod 8 (K-N), feed branch")
    x_D: float = parameter(-58.75e-3, "m", "rock shaft D of lever 3, x", ANY)
    y_D: float = parameter(-219.257e-3, "m", "rock shaft D of lever 3, y", ANY)
    x_G: float = parameter(43.263e-3, "m", "rock shaft G of rocker 7, x", ANY)
    y_G: float = parameter(-222.57e-3, "m", "rock shaft G of rocker 7, y", ANY)
    l3: float = parameter(30.0e-3, "m", "lever 3, arm D-C")
    l3p: float = parameter(30.0e-3, "m", "lever 3, arm D-E (l3')")
    alpha3: float = parameter(math.radians(10.0), "rad", "lever 3: angle from arm D-C to arm D-E",
                              ANY)
    l7: float = parameter(28.0e-3, "m", "rocker 7, arm G-N")
    l7p: float = parameter(28.0e-3, "m", "rocker 7, arm G-H (l7')")
    alpha7: float = parameter(math.radians(11.0), "rad", "rocker 7: arm G-H is at 90° + alpha7 "
                              "from arm G-N", ANY)
    l4: float = parameter(25.0e-3, "m", "rod 4 (E-F)")
    l5: float = parameter(120.0e-3, "m", "feed-bar lever 5 (H-F)")
    l_HM: float = parameter(100.0e-3, "m", "feed-dog point M on lever 5, distance from H")


@dataclass(frozen=True)
class FeedMotion:
    joints: dict[str, Motion]      # A, B, K, C, D, E, N, G, H, F, M
    phi3: Angle
    phi4: Angle
    phi5: Angle
    phi7: Angle
    # transmission angles (rad, in [0, π/2]) of the three dyads, at C, N and F
    mu_C: float
    mu_N: float
    mu_F: float


def transmission_angle(joint: Motion, p: Motion, q: Motion) -> float:
    """Angle between the two links that meet at `joint` (from P and from Q), folded to [0, 90°]:
    90° transmits force best, 0° is the dead position."""
    ax, ay = p.x - joint.x, p.y - joint.y
    bx, by = q.x - joint.x, q.y - joint.y
    cos = (ax * bx + ay * by) / math.sqrt((ax * ax + ay * ay) * (bx * bx + by * by))
    mu = math.acos(min(1.0, max(-1.0, cos)))
    return min(mu, math.pi - mu)


class FeedLinkage:
    """The feed mechanism as crank angle phi1 -> every joint, link angle and the point M."""

    def __init__(self, params: FeedParams = FeedParams()):
        validate(params)
        self.p = params
        check_assembly(self.motion, "feed mechanism", params, "crank angle phi1")

    def motion(self, phi1, omega=0.0, epsilon=0.0) -> FeedMotion:
        p = self.p
        a, d, g = Motion(0.0, 0.0), Motion(p.x_D, p.y_D), Motion(p.x_G, p.y_G)
        crank = angle(phi1, omega, epsilon)
        b = point_on_link(a, p.r_l, crank)
        k = point_on_link(a, p.r_f, crank, offset=p.alpha1)
        c = dyad_rrr(b, p.l2, d, p.l3, RIGHT, name="rod 2 / lever 3")
        n = dyad_rrr(k, p.l8, g, p.l7, LEFT, name="rod 8 / rocker 7")
        phi3, phi7 = link_angle(d, c), link_angle(g, n)
        e = point_on_link(d, p.l3p, phi3, offset=p.alpha3)
        h = point_on_link(g, p.l7p, phi7, offset=math.pi / 2 + p.alpha7)
        f = dyad_rrr(e, p.l4, h, p.l5, LEFT, name="rod 4 / feed-bar lever 5")
        phi4, phi5 = link_angle(e, f), link_angle(h, f)
        m = point_on_link(h, p.l_HM, phi5)
        joints = {"A": a, "B": b, "K": k, "C": c, "D": d, "E": e, "N": n, "G": g, "H": h,
                  "F": f, "M": m}
        return FeedMotion(joints, phi3, phi4, phi5, phi7, transmission_angle(c, b, d),
                          transmission_angle(n, k, g), transmission_angle(f, e, h))
