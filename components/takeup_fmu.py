"""FMU TakeupLinkage: the thread take-up four-bar and the path of its eye E."""
from __future__ import annotations

import math

from .linkage_slave import LinkageSlave
from .ports import Port
from .takeup import TakeupLinkage, TakeupParams

SPEED = 5000 * 2 * math.pi / 60          # the paper's 5000 rpm, in rad/s


class TakeupLinkageSlave(LinkageSlave):
    """Thread take-up four-bar: shaft motion to the path, velocity and acceleration of the eye E."""

    model_name = "TakeupLinkage"
    params_class = TakeupParams
    model_class = TakeupLinkage
    speed = SPEED
    experiment = (2 * math.pi / SPEED, 2e-5)      # one revolution, 0.6° per step
    outputs = (
        Port("E_z", "m", "take-up eye E, Z", feedthrough=True, source="E.x"),
        Port("E_x", "m", "take-up eye E, X", feedthrough=True, source="E.y"),
        Port("E_vz", "m/s", "velocity of E, Z", feedthrough=True, source="E.vx"),
        Port("E_vx", "m/s", "velocity of E, X", feedthrough=True, source="E.vy"),
        Port("E_az", "m/s2", "acceleration of E, Z", feedthrough=True, source="E.ax"),
        Port("E_ax", "m/s2", "acceleration of E, X", feedthrough=True, source="E.ay"),
        Port("phi_BC", "rad", "coupler angle (direction B -> C, from +Z)", feedthrough=True,
             source="phi_BC.value"),
        Port("phi_CD", "rad", "rocker angle (direction D -> C, from +Z)", feedthrough=True,
             source="phi_CD.value"),
    )
