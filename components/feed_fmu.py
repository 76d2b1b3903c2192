"""FMU FeedLinkage: the closed lever-hinge feed mechanism and its feed-dog point M."""
from __future__ import annotations

import math

from .feed import FeedLinkage, FeedParams
from .fmi_base import SHAFT_TAYLOR, Port, SewSlave, shaft_inputs


class FeedLinkageSlave(SewSlave):
    """Closed lever-hinge feed mechanism: shaft motion to the feed-dog path (point M)."""

    model_name = "FeedLinkage"
    params_class = FeedParams
    inputs = shaft_inputs(303.5)                  # ω1 of the paper, rad/s
    experiment = (2 * math.pi / 303.5, 5e-5)      # one revolution
    taylor_inputs = SHAFT_TAYLOR
    outputs = (
        Port("phi3", "rad", "lever 3 (direction D -> C), in (-π, π]", feedthrough=True),
        Port("phi4", "rad", "rod 4 (direction E -> F), in (-π, π]", feedthrough=True),
        Port("phi5", "rad", "feed-bar lever 5 (direction H -> F), in (-π, π]", feedthrough=True),
        Port("phi7", "rad", "rocker 7 (direction G -> N), in (-π, π]", feedthrough=True),
        Port("M_x", "m", "feed-dog point M, x", feedthrough=True),
        Port("M_y", "m", "feed-dog point M, y", feedthrough=True),
        Port("M_vx", "m/s", "velocity of M, x", feedthrough=True),
        Port("M_vy", "m/s", "velocity of M, y", feedthrough=True),
        Port("M_ax", "m/s2", "acceleration of M, x", feedthrough=True),
        Port("M_ay", "m/s2", "acceleration of M, y", feedthrough=True),
        Port("mu_C", "rad", "transmission angle of dyad rod 2 / lever 3 at C (0 to π/2)",
             feedthrough=True),
        Port("mu_N", "rad", "transmission angle of dyad rod 8 / rocker 7 at N (0 to π/2)",
             feedthrough=True),
        Port("mu_F", "rad", "transmission angle of dyad rod 4 / lever 5 at F (0 to π/2)",
             feedthrough=True),
    )

    def build_model(self, params):
        return FeedLinkage(params)

    def current_outputs(self):
        u = self.extrapolated_inputs(self._elapsed)
        m = self.model().motion(u["phi"], u["omega"], u["epsilon"])
        pt = m.joints["M"]
        return {"phi3": m.phi3.value, "phi4": m.phi4.value, "phi5": m.phi5.value,
                "phi7": m.phi7.value, "M_x": pt.x, "M_y": pt.y, "M_vx": pt.vx, "M_vy": pt.vy,
                "M_ax": pt.ax, "M_ay": pt.ay, "mu_C": float(m.mu_C), "mu_N": float(m.mu_N),
                "mu_F": float(m.mu_F)}
