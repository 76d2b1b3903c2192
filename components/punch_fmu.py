"""FMUs PunchLinkage and PunchContact: the punch drive of the ultrasonic sewing machine."""
from __future__ import annotations

import math

from .fmi_base import LinkageSlave, Port, SewSlave, fields_of
from .punch_contact import PunchContact, PunchContactParams, PunchState
from .punch_linkage import PunchLinkage, PunchLinkageParams

SETUP_SPEED = 100.0         # rad/s: the punch drive's default shaft speed (the paper's first case)


class PunchLinkageSlave(LinkageSlave):
    """Six-bar punch drive (or the required displacement function): shaft motion to punch lift."""

    model_name = "PunchLinkage"
    params_class = PunchLinkageParams
    model_class = PunchLinkage
    speed = SETUP_SPEED
    experiment = (2 * math.pi / SETUP_SPEED, 2.5e-4)         # one revolution
    outputs = (
        Port("xi", "m", "kinematic excitation of the punch: xi0 - psi", feedthrough=True),
        Port("xi_dot", "m/s", "d(xi)/dt", feedthrough=True),
        Port("xi_ddot", "m/s2", "d2(xi)/dt2", feedthrough=True),
        Port("psi", "m", "displacement of the slider below its highest point", feedthrough=True),
    )



class PunchContactSlave(SewSlave):
    """Punch body with unilateral fabric contact, driven by the linkage through spring 11."""

    model_name = "PunchContact"
    params_class = PunchContactParams
    model_class = PunchContact
    # the excitation the default linkage gives at the setup position (φ = 0, slider at its top)
    # at the default speed: a host that starts with the start values starts the punch at rest
    inputs = (
        Port("xi", "m", "kinematic excitation (slider side of spring 11)", start=4.5e-3),
        Port("xi_dot", "m/s", "d(xi)/dt"),
        Port("xi_ddot", "m/s2", "d2(xi)/dt2", start=-44.87389667388663),
    )
    # run alone, the inputs extrapolate the slider's deceleration at its top: the punch follows
    # it down, lands on the fabric (after about 14 ms) and presses into it
    experiment = (0.02, 1e-4)
    taylor_inputs = (("xi", "xi_dot", "xi_ddot"),)
    outputs = (
        Port("y", "m", "punch height above the fabric (< 0: pressing into it)"),
        Port("y_dot", "m/s", "punch velocity"),
        Port("y_ddot", "m/s2", "punch acceleration", feedthrough=True),
        Port("F1", "N", "force of the closing spring 6"),
        Port("F2", "N", "force of the fabric on the punch (>= 0)"),
        Port("F3", "N", "force of spring 11", feedthrough=True),
        Port("Delta", "m", "deformation of spring 11: xi - y", feedthrough=True),
        Port("contact", "1", "punch presses on the fabric (F2 > 0)", kind="Boolean"),
        Port("F2_max", "N", "largest F2 during the last communication step (catches the impact "
                            "at landing, which falls between communication points)"),
    )

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._state: PunchState | None = None

    def _state_now(self) -> PunchState:
        # before initialization ends, the punch rests on its excitation (setup position)
        if self._state is None:
            return self.model().initial_state(self._inputs["xi"], self._inputs["xi_dot"],
                                              self._inputs["xi_ddot"])
        return self._state

    def initialize(self, model):
        self._state = model.initial_state(self._inputs["xi"], self._inputs["xi_dot"],
                                          self._inputs["xi_ddot"])

    def advance(self, model, t, h):
        # Taylor polynomial of the excitation about the start of this step
        u = self.extrapolated_inputs(self._elapsed)
        self._state = model.step(self._state_now(), u["xi"], u["xi_dot"], 0.5 * u["xi_ddot"], h)

    def current_outputs(self):
        u = self.extrapolated_inputs(self._elapsed)
        o = self.model().outputs(self._state_now(), u["xi"], u["xi_dot"], u["xi_ddot"])
        return fields_of(o)

    def save_internal(self):
        return {} if self._state is None else fields_of(self._state)

    def restore_internal(self, saved):
        self._state = PunchState(**saved) if saved else None
