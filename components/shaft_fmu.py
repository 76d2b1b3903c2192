"""FMU MainShaft: the shaft angle, speed and acceleration that drive every mechanism."""
from __future__ import annotations

import math

from .ports import Port
from .shaft import MainShaft, ShaftParams
from .slave import SewSlave


class MainShaftSlave(SewSlave):
    """Main shaft of the sewing machine: constant speed after an optional smooth start."""

    model_name = "MainShaft"
    params_class = ShaftParams
    model_class = MainShaft
    experiment = (2 * math.pi / 100.0, 2.5e-4)    # one revolution at the default speed
    outputs = (
        Port("phi", "rad", "shaft angle, cumulative (one stitch = 2π)"),
        Port("omega", "rad/s", "shaft speed"),
        Port("epsilon", "rad/s2", "shaft angular acceleration"),
    )

    def current_outputs(self):
        phi, omega, epsilon = self.model().state(self._time)
        return {"phi": phi, "omega": omega, "epsilon": epsilon}

    def output_row(self):
        return self.model().state(self._time)        # (phi, omega, epsilon): the ports' order
