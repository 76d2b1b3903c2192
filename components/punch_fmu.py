"""FMUs of the punch drive of the ultrasonic sewing machine: PunchLinkage and PunchContact, and the
punch split at the fabric, PunchBody and Fabric."""
from __future__ import annotations

import math
from operator import attrgetter

from .linkage_slave import LinkageSlave
from .ports import Port
from .punch_contact import GRAVITY, PunchContact, PunchContactParams, PunchState
from .punch_linkage import PunchLinkage, PunchLinkageParams
from .punch_split import Fabric, FabricParams, PunchBody, PunchBodyParams
from .slave import SewSlave, fields_of

_SETUP_HEIGHT = PunchLinkageParams().xi0    # the punch at the top of the setup position
_BODY = PunchBodyParams()                    # the defaults the Fabric's start values assume
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
    # run alone, the inputs extrapolate the slider's acceleration at its top: the punch follows
    # it down; the default experiment ends just before it lands (about 14 ms), since the
    # extrapolated slider would go on accelerating (0.6 m/s at landing, 190 N by 20 ms) where
    # the real one turns back
    experiment = (0.0135, 1e-4)
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
                            "at landing, which falls between communication points)",
             discrete=True),
    )

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._state: PunchState | None = None
        # the model's outputs (a frozen dataclass) read as the row of the ports, in their order
        self._row_of = attrgetter(*self._row_names)

    def _state_now(self) -> PunchState:
        # before initialization ends, the punch rests on its excitation (setup position)
        if self._state is None:
            u = self.held_inputs()
            return self.model().initial_state(u["xi"], u["xi_dot"], u["xi_ddot"])
        return self._state

    def initialize(self, model):
        u = self.held_inputs()
        self._state = model.initial_state(u["xi"], u["xi_dot"], u["xi_ddot"])

    def advance(self, model, t, h):
        # Taylor polynomial of the excitation about the start of this step
        u = self.extrapolated_inputs(self._elapsed)
        self._state = model.step(self._state_now(), u["xi"], u["xi_dot"], 0.5 * u["xi_ddot"], h)

    def current_outputs(self):
        u = self.extrapolated_inputs(self._elapsed)
        o = self.model().outputs(self._state_now(), u["xi"], u["xi_dot"], u["xi_ddot"])
        return fields_of(o)

    def output_row(self):
        u = self.extrapolated_inputs(self._elapsed)
        return self._row_of(self.model().outputs(self._state_now(), u["xi"], u["xi_dot"],
                                                 u["xi_ddot"]))

    def save_internal(self):
        return {} if self._state is None else fields_of(self._state)

    def restore_internal(self, saved):
        self._state = PunchState(**saved) if saved else None

    # a PunchState is immutable: the state before a step is the object itself
    def snapshot(self):
        return self._state

    def restore_snapshot(self, snapshot):
        self._state = snapshot

    def state_is_finite(self):
        s = self._state
        return s is None or math.isfinite(s.y + s.y_dot + s.F2_max)


class PunchBodySlave(PunchContactSlave):
    """Punch body without the fabric: driven by the linkage through spring 11, pressed by the
    fabric's force F2 (an input)."""

    model_name = "PunchBody"
    params_class = PunchBodyParams
    model_class = PunchBody
    inputs = (
        *PunchContactSlave.inputs,
        Port("F2", "N", "force of the fabric on the punch (>= 0)"),
        Port("F2_dot", "N/s", "its rate: F2 is extrapolated linearly within a step"),
    )
    taylor_inputs = (("xi", "xi_dot", "xi_ddot"), ("F2", "F2_dot"))
    outputs = tuple(p for p in PunchContactSlave.outputs
                    if p.name not in ("F2", "contact", "F2_max"))
    # y'' follows the fabric's force at once
    outputs = tuple(Port(p.name, p.unit, p.description, feedthrough=True) if p.name == "y_ddot"
                    else p for p in outputs)

    def initialize(self, model):
        u = self.held_inputs()
        self._state = model.initial_state(u["xi"], u["xi_dot"], u["xi_ddot"], u["F2"])

    def advance(self, model, t, h):
        u = self.extrapolated_inputs(self._elapsed)
        self._state = model.step(self._state_now(), u["xi"], u["xi_dot"], 0.5 * u["xi_ddot"], h,
                                 u["F2"], u["F2_dot"])

    def current_outputs(self):
        u = self.extrapolated_inputs(self._elapsed)
        o = self.model().outputs(self._state_now(), u["xi"], u["xi_dot"], u["xi_ddot"], u["F2"])
        return fields_of(o)

    def output_row(self):
        u = self.extrapolated_inputs(self._elapsed)
        return self._row_of(self.model().outputs(self._state_now(), u["xi"], u["xi_dot"],
                                                 u["xi_ddot"], u["F2"]))


class FabricSlave(SewSlave):
    """The welded material: elastic-dissipative, unilateral, non-retaining contact with the punch."""

    model_name = "Fabric"
    params_class = FabricParams
    model_class = Fabric
    # the punch at the setup position: at rest at the top (y = xi0, spring 11 unloaded),
    # accelerated down by spring 6 (the default PunchBody's initial y''), so that a host that
    # starts the connections at their start values starts at rest. Run alone, the inputs
    # extrapolate that fall: the default experiment ends just before the punch lands (4.4 ms),
    # since without the body that decelerates it the punch would press on through the fabric
    # (1.4 kN by 10 ms, far outside what a weld sees)
    inputs = (
        Port("y", "m", "punch height above the fabric (< 0: pressing into it)",
             start=_SETUP_HEIGHT),
        Port("y_dot", "m/s", "punch velocity"),
        Port("y_ddot", "m/s2", "punch acceleration: the punch's motion is extrapolated within a "
                               "step to locate contact inside it",
             start=(_BODY.F30 - _BODY.F10 - _BODY.c1 * _SETUP_HEIGHT) / _BODY.m - GRAVITY),
    )
    taylor_inputs = (("y", "y_dot", "y_ddot"),)
    experiment = (4.3e-3, 5e-5)
    outputs = (
        Port("F2", "N", "force of the fabric on the punch (>= 0)", feedthrough=True),
        Port("F2_dot", "N/s", "rate of F2 (0 out of contact)", feedthrough=True),
        Port("contact", "1", "the punch presses on the fabric (F2 > 0)", kind="Boolean",
             feedthrough=True),
        Port("F2_max", "N", "largest F2 during the last communication step (the impact at "
                            "landing falls between communication points)", feedthrough=True,
             discrete=True),
        Port("t_switch", "s", "time of the last contact switch (on or off) located inside the "
                              "last step; -1 if the last step had none", discrete=True),
    )

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._F2_max = 0.0
        self._t_switch = -1.0

    def initialize(self, model):
        self._F2_max, self._t_switch = 0.0, -1.0

    def advance(self, model, t, h):
        u = self.extrapolated_inputs(self._elapsed)
        seen = model.step(u["y"], u["y_dot"], u["y_ddot"], h)
        self._F2_max = seen.F2_max
        self._t_switch = t + seen.switches[-1][0] if seen.switches else -1.0

    def current_outputs(self):
        return dict(zip(self._row_names, self.output_row()))

    def output_row(self):
        u = self.extrapolated_inputs(self._elapsed)
        fabric = self.model()
        f2 = fabric.force(u["y"], u["y_dot"])
        # F2, F2_dot, contact, F2_max, t_switch
        return (f2, fabric.force_rate(u["y"], u["y_dot"], u["y_ddot"]), f2 > 0.0,
                max(self._F2_max, f2), self._t_switch)

    def save_internal(self):
        return {"F2_max": self._F2_max, "t_switch": self._t_switch}

    def restore_internal(self, saved):
        self._F2_max, self._t_switch = saved["F2_max"], saved["t_switch"]

    def snapshot(self):
        return self._F2_max, self._t_switch

    def restore_snapshot(self, snapshot):
        self._F2_max, self._t_switch = snapshot

    def state_is_finite(self):
        return math.isfinite(self._F2_max + self._t_switch)
