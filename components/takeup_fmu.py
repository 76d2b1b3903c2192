"""FMU TakeupLinkage: the thread take-up four-bar and the path of its eye E."""
from __future__ import annotations

import math

from .fmi_base import SHAFT_TAYLOR, Port, SewSlave, shaft_inputs
from .takeup import TakeupLinkage, TakeupParams

SPEED = 5000 * 2 * math.pi / 60          # the paper's 5000 rpm, in rad/s


class TakeupLinkageSlave(SewSlave):
    """Thread take-up four-bar: shaft motion to the path, velocity and acceleration of the eye E."""

    model_name = "TakeupLinkage"
    params_class = TakeupParams
    inputs = shaft_inputs(SPEED)
    experiment = (2 * math.pi / SPEED, 2e-5)      # one revolution, 0.6° per step
    taylor_inputs = SHAFT_TAYLOR
    outputs = (
        Port("E_z", "m", "take-up eye E, Z", feedthrough=True),
        Port("E_x", "m", "take-up eye E, X", feedthrough=True),
        Port("E_vz", "m/s", "velocity of E, Z", feedthrough=True),
        Port("E_vx", "m/s", "velocity of E, X", feedthrough=True),
        Port("E_az", "m/s2", "acceleration of E, Z", feedthrough=True),
        Port("E_ax", "m/s2", "acceleration of E, X", feedthrough=True),
        Port("phi_BC", "rad", "coupler angle (direction B -> C, from +Z)", feedthrough=True),
        Port("phi_CD", "rad", "rocker angle (direction D -> C, from +Z)", feedthrough=True),
    )

    def build_model(self, params):
        return TakeupLinkage(params)

    def current_outputs(self):
        u = self.extrapolated_inputs(self._elapsed)
        m = self.model().motion(u["phi"], u["omega"], u["epsilon"])
        e = m.E
        return {"E_z": e.x, "E_x": e.y, "E_vz": e.vx, "E_vx": e.vy, "E_az": e.ax, "E_ax": e.ay,
                "phi_BC": m.phi_BC.value, "phi_CD": m.phi_CD.value}
