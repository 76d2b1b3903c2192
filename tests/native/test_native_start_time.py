"""A start time the model cannot start at is refused with the reason: MainShaft's model is a
closed form of the time since the shaft started at t = 0 (components/shaft.py: state(t) for
t >= 0; before 0 the Python model fails and its FMU gives NaN rows), so the native MainShaft
refuses a negative start time in fmi2SetupExperiment and fmi3EnterInitializationMode, naming
it. A model that takes its time from its inputs (PunchContact, the linkages) starts at any
time, as its Python FMU does."""
from __future__ import annotations

import pytest
from fmpy.fmi1 import FMICallException

from sewfmu.components.shaft import MainShaft, ShaftParams
from tests.native.fmpy_native import ERROR, Instance

VERSIONS = [2, pytest.param(3, marks=pytest.mark.slow)]


def test_the_python_shaft_model_has_no_motion_before_zero():
    # the independent measure: the Python model at t < 0 (no ramp, the default: it divides by
    # the ramp time; with a ramp it runs the ramp's formula backwards, no motion of the shaft)
    with pytest.raises(ZeroDivisionError):
        MainShaft(ShaftParams()).state(-1.0)


@pytest.mark.parametrize("fmi", VERSIONS, ids=lambda f: f"fmi{f}")
def test_main_shaft_refuses_a_negative_start_time_naming_it(native_fmu, fmi):
    inst = Instance(native_fmu("MainShaft", fmi), fmi, name="shaft1")
    with pytest.raises(FMICallException) as caught:
        inst.start(-1.0)
    assert caught.value.status == ERROR
    status, line = inst.lines[-1]
    call = "fmi2SetupExperiment" if fmi == 2 else "fmi3EnterInitializationMode"
    assert status == ERROR and line.startswith(f"shaft1 (MainShaft): {call}: start time -1 s "
                                               f"refused"), line
    assert "t >= 0" in line and "too large" not in line, line
    inst.free()
    # at 0 and later it runs, with the Python model's numbers
    inst = Instance(native_fmu("MainShaft", fmi), fmi, name="shaft2")
    inst.start(0.5)
    assert inst.outputs(["phi", "omega", "epsilon"]) == list(MainShaft(ShaftParams()).state(0.5))
    inst.free()


@pytest.mark.parametrize("fmi", VERSIONS, ids=lambda f: f"fmi{f}")
def test_a_model_of_inputs_starts_at_a_negative_time(native_fmu, fmi):
    inst = Instance(native_fmu("PunchContact", fmi), fmi, name="punch1")
    inst.start(-1.0)
    inst.fmu.doStep(-1.0, 1e-4)
    assert inst.lines == []
    inst.free()
