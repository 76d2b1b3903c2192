"""FMUs CarriageDrive and CarriageModal: the semi-automat's start-stop table and its carriage."""
from __future__ import annotations

import math

from .carriage import CarriageDrive, CarriageDriveParams, CarriageModal, CarriageParams
from .linkage_slave import LinkageSlave
from .ports import Port
from .slave import SewSlave

SPEED = 1600 * 2 * math.pi / 60          # the semi-automat's 1600 stitches/min, in rad/s


class CarriageDriveSlave(LinkageSlave):
    """Start-stop drive of the coordinate device: one cycloidal stitch advance per revolution."""

    model_name = "CarriageDrive"
    params_class = CarriageDriveParams
    model_class = CarriageDrive
    speed = SPEED
    experiment = (3 * 2 * math.pi / SPEED, 1e-4)  # three stitches
    outputs = (
        Port("x", "m", "table position along the motion axis", feedthrough=True),
        Port("v", "m/s", "table velocity", feedthrough=True),
        Port("a", "m/s2", "table acceleration", feedthrough=True),
        Port("jerk", "m/s3", "table jerk", feedthrough=True),
    )


class CarriageModalSlave(SewSlave):
    """Carriage on its guide cantilever: 2-DOF Ritz model under the base acceleration of the drive."""

    model_name = "CarriageModal"
    params_class = CarriageParams
    model_class = CarriageModal
    inputs = (
        Port("a_base", "m/s2", "acceleration of the traverse (the cantilever's root)"),
        Port("a_base_dot", "m/s3", "its rate of change (the drive's jerk)",
             start=17967.066500827565),
    )
    # the start values are the default drive's at φ = 0 (at rest, the transport window opening
    # with the cycloid's jerk); run alone, that jerk is held: the guide's response to a base
    # acceleration growing linearly, over a quarter period of the first mode
    experiment = (0.012, 1e-4)
    taylor_inputs = (("a_base", "a_base_dot"),)
    outputs = (
        Port("U1", "m", "deflection of the guide at section A, relative to the root"),
        Port("U2", "m", "deflection at section B (the tip, under the carriage's centre)"),
        Port("U1_dot", "m/s", "rate of U1"),
        Port("U2_dot", "m/s", "rate of U2"),
    )
    calculated = (
        Port("omega1", "rad/s", "first natural frequency of the Ritz model"),
        Port("omega2", "rad/s", "second natural frequency of the Ritz model"),
    )

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._q = None           # modal coordinates and rates; None until initialized
        self._dq = None

    def initialize(self, model):
        # at rest in the static deflection under the initial base acceleration
        self._q = model.modal(model.static_deflection(self._inputs["a_base"]))
        self._dq = (0.0, 0.0)

    def advance(self, model, t, h):
        u = self.extrapolated_inputs(self._elapsed)
        if self._q is None:
            self.initialize(model)
        self._q, self._dq = model.step(self._q, self._dq, u["a_base"], u["a_base_dot"], h)

    def current_outputs(self):
        model = self.model()
        if self._q is None:
            U, dU = model.static_deflection(self._inputs["a_base"]), (0.0, 0.0)
        else:
            U, dU = model.physical(self._q, self._dq)
        return {"U1": float(U[0]), "U2": float(U[1]), "U1_dot": float(dU[0]),
                "U2_dot": float(dU[1]), "omega1": float(model.omega[0]),
                "omega2": float(model.omega[1])}

    def save_internal(self):
        return {} if self._q is None else {"q": list(self._q), "dq": list(self._dq)}

    def restore_internal(self, saved):
        self._q = tuple(saved["q"]) if saved else None
        self._dq = tuple(saved["dq"]) if saved else None
