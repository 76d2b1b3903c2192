"""FMU FeedLinkage: the closed lever-hinge feed mechanism and its feed-dog point M."""
from __future__ import annotations

import math

from .feed import FeedLinkage, FeedParams
from .linkage_slave import LinkageSlave
from .ports import Port


def _out(name: str, unit: str, description: str, source: str) -> Port:
    return Port(name, unit, description, feedthrough=True, source=source)


class FeedLinkageSlave(LinkageSlave):
    """Closed lever-hinge feed mechanism: shaft motion to the feed-dog path (point M)."""

    model_name = "FeedLinkage"
    params_class = FeedParams
    model_class = FeedLinkage
    speed = 303.5                                 # ω1 of the paper, rad/s
    experiment = (2 * math.pi / 303.5, 5e-5)      # one revolution
    outputs = (
        _out("phi3", "rad", "lever 3 (direction D -> C), in (-π, π]", "phi3.value"),
        _out("phi4", "rad", "rod 4 (direction E -> F), in (-π, π]", "phi4.value"),
        _out("phi5", "rad", "feed-bar lever 5 (direction H -> F), in (-π, π]", "phi5.value"),
        _out("phi7", "rad", "rocker 7 (direction G -> N), in (-π, π]", "phi7.value"),
        _out("M_x", "m", "feed-dog point M, x", "joints.M.x"),
        _out("M_y", "m", "feed-dog point M, y", "joints.M.y"),
        _out("M_vx", "m/s", "velocity of M, x", "joints.M.vx"),
        _out("M_vy", "m/s", "velocity of M, y", "joints.M.vy"),
        _out("M_ax", "m/s2", "acceleration of M, x", "joints.M.ax"),
        _out("M_ay", "m/s2", "acceleration of M, y", "joints.M.ay"),
        _out("mu_C", "rad", "transmission angle of dyad rod 2 / lever 3 at C (0 to π/2)", "mu_C"),
        _out("mu_N", "rad", "transmission angle of dyad rod 8 / rocker 7 at N (0 to π/2)", "mu_N"),
        _out("mu_F", "rad", "transmission angle of dyad rod 4 / lever 5 at F (0 to π/2)", "mu_F"),
    )
