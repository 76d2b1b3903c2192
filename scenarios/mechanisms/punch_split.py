"""The punch drive split at the fabric (PunchBody + Fabric): the same figures and plots as the
punch drive's, read from the body (y) and the fabric (F2, contact, its peak hold)."""
import math

import numpy as np

from sewfmu.scenarios.mechanisms import punch
from sewfmu.scenarios.mechanisms.base import RegressionCase


def body_inputs(t) -> dict:
    """The six-bar's excitation at ω = 200 s⁻¹ and a fabric force pulse of 25 N (a half sine)
    in the middle of each revolution."""
    pulse = np.clip(np.sin(400.0 * t - 1.0), 0.0, None)
    rate = np.where(pulse > 0.0, 400.0 * np.cos(400.0 * t - 1.0), 0.0)
    return {**punch.excitation(t), "F2": 25.0 * pulse, "F2_dot": 25.0 * rate}


def fabric_inputs(t) -> dict:
    """A punch oscillating 2 mm about 0.5 mm below the surface at 80 Hz: in and out of contact."""
    w = 2 * math.pi * 80.0
    return {"y": 2e-3 * np.cos(w * t) - 0.5e-3, "y_dot": -2e-3 * w * np.sin(w * t),
            "y_ddot": -2e-3 * w * w * np.cos(w * t)}


class PunchSplit(punch.PunchDrive):
    """The punch drive split at the fabric: the punch's figures, plots and drawing, read from the
    body (y) and the fabric (F2, contact, its peak hold)."""
    name = "punch_split"
    roles = {"shaft": "MainShaft", "linkage": "PunchLinkage", "body": "PunchBody",
             "fabric": "Fabric"}
    regression = {"PunchBody": RegressionCase(4 * math.pi / 200, 2.5e-4, body_inputs),
                  "Fabric": RegressionCase(0.025, 1e-4, fabric_inputs)}

    @staticmethod
    def monolithic_figures(scenario, rtol: float | None = None) -> tuple[dict, float]:
        """The same physics as the punch drive's: body and fabric together make the punch."""
        return punch.monolithic_figures(scenario, rtol, punch_roles=("body", "fabric"))


MECHANISM = PunchSplit()
