"""What the native FMUs refuse with an Error status (fmpy raises FMICallException), each with
its reason through the logger as "<instance> (<Model>): <reason>": an unknown value reference,
a value outside its declared range, NaN or infinity, a write to an output, a parameter set
after initialization, a garbled serialized state; and the instance is left as it was."""
from __future__ import annotations

import math
import struct

import pytest
from fmpy.fmi1 import FMICallException

from tests.native.fmpy_native import ERROR, Instance

VERSIONS = [2, pytest.param(3, marks=pytest.mark.slow)]


@pytest.fixture(params=VERSIONS, ids=lambda fmi: f"fmi{fmi}")
def shaft(request, native_fmu):
    fmi = request.param
    inst = Instance(native_fmu("MainShaft", fmi), fmi, name="shaft1")
    yield inst
    inst.free()


def _refused(inst: Instance, call, *args, reason: str) -> None:
    """The call raises with fmi2Error/fmi3Error, and the last log line gives the reason."""
    with pytest.raises(FMICallException) as caught:
        call(*args)
    assert caught.value.status == ERROR
    status, line = inst.lines[-1]
    assert status == ERROR
    assert line.startswith(f"shaft1 ({inst.md.modelName}): "), line
    assert reason in line, line


def _get(inst, vrs):
    return (inst.fmu.getReal if inst.fmi == 2 else inst.fmu.getFloat64)(vrs)


def _set(inst, vrs, values):
    return (inst.fmu.setReal if inst.fmi == 2 else inst.fmu.setFloat64)(vrs, values)


def test_an_unknown_value_reference_is_refused(shaft):
    _refused(shaft, _get, shaft, [999], reason="no such variable (value reference 999)")
    _refused(shaft, _set, shaft, [999], [1.0], reason="no such variable (value reference 999,")
    integer = shaft.fmu.getInteger if shaft.fmi == 2 else shaft.fmu.getInt32
    _refused(shaft, integer, [shaft.vr["omega0"]], reason="no such variable")


def test_a_value_outside_its_range_is_refused_and_not_taken(shaft):
    vr = shaft.vr["omega0"]
    _refused(shaft, _set, shaft, [vr], [5000.0], reason="outside its range [0, 2000] rad/s")
    _refused(shaft, _set, shaft, [vr], [-1.0], reason="outside its range")
    assert _get(shaft, [vr]) == [100.0]


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_nan_or_infinity_is_refused(shaft, value):
    _refused(shaft, _set, shaft, [shaft.vr["ramp_time"]], [value], reason="not a finite number")
    assert _get(shaft, [shaft.vr["ramp_time"]]) == [0.0]


def test_a_set_is_all_or_nothing(shaft):
    vrs = [shaft.vr["omega0"], shaft.vr["ramp_time"]]
    _refused(shaft, _set, shaft, vrs, [50.0, -3.0], reason="ramp_time")
    assert _get(shaft, vrs) == [100.0, 0.0]


def test_setting_an_output_is_refused(shaft):
    _refused(shaft, _set, shaft, [shaft.vr["phi"]], [1.0], reason="phi is an output")


def test_a_parameter_set_after_initialization_is_refused(shaft):
    shaft.start()
    _refused(shaft, _set, shaft, [shaft.vr["omega0"]], [50.0],
             reason="parameter omega0 is fixed: it cannot change after exitInitializationMode")
    shaft.fmu.doStep(0.0, 1e-3)
    assert shaft.outputs(["phi", "omega"]) == [100.0 * 1e-3, 100.0]


def test_a_bad_parameter_makes_exit_initialization_an_error_and_every_step_refused(shaft):
    _set(shaft, [shaft.vr["omega0"]], [0.0])       # within [0, 2000], but the model needs > 0
    if shaft.fmi == 2:
        shaft.fmu.setupExperiment(startTime=0.0)
        shaft.fmu.enterInitializationMode()
    else:
        shaft.fmu.enterInitializationMode(startTime=0.0)
    _refused(shaft, shaft.fmu.exitInitializationMode, reason="parameter omega0: must be > 0")
    _refused(shaft, shaft.fmu.doStep, 0.0, 1e-3, reason="refused: parameter omega0")


def test_a_step_out_of_time_is_refused(shaft):
    shaft.start()
    _refused(shaft, shaft.fmu.doStep, 0.5, 1e-3, reason="the last one ended at t = 0 s")
    _refused(shaft, shaft.fmu.doStep, 0.0, -1e-3, reason="the step size must be positive")


@pytest.mark.parametrize("damage", ["flip", "truncate", "foreign", "empty"])
def test_a_garbled_state_is_refused(shaft, damage):
    shaft.start()
    shaft.fmu.doStep(0.0, 1e-3)
    fmi2 = shaft.fmi == 2
    state = (shaft.fmu.getFMUstate if fmi2 else shaft.fmu.getFMUState)()
    data = bytearray((shaft.fmu.serializeFMUstate if fmi2 else shaft.fmu.serializeFMUState)(
        state))
    if damage == "flip":
        data[len(data) // 2] ^= 0x10
    elif damage == "truncate":
        data = data[:-9]
    elif damage == "foreign":
        data = bytearray(b'{"params": {}, "inputs": {}}')      # a Python FMU's kind of state
    else:
        data = bytearray()
    deserialize = shaft.fmu.deSerializeFMUstate if fmi2 else shaft.fmu.deserializeFMUState
    _refused(shaft, deserialize, bytes(data), reason="not a state of this FMU")
    shaft.fmu.doStep(1e-3, 1e-3)                 # the instance goes on where it was
    assert shaft.outputs(["phi"]) == [100.0 * 2e-3]


def test_a_step_the_instance_cannot_take_before_initialization_is_refused(shaft):
    _refused(shaft, shaft.fmu.doStep, 0.0, 1e-3, reason="called before exitInitializationMode")


def test_outputs_read_before_initialization_are_the_models(shaft):
    _set(shaft, [shaft.vr["omega0"]], [50.0])
    assert shaft.outputs(["phi", "omega", "epsilon"]) == [0.0, 50.0, 0.0]


@pytest.fixture(params=VERSIONS, ids=lambda fmi: f"fmi{fmi}")
def punch(request, native_fmu):
    fmi = request.param
    inst = Instance(native_fmu("PunchContact", fmi), fmi, name="shaft1")
    yield inst
    inst.free()


@pytest.mark.slow
def test_integer_and_boolean_variables_are_refused_as_the_reals_are(punch):
    fmi2 = punch.fmi == 2
    set_int = punch.fmu.setInteger if fmi2 else punch.fmu.setInt32
    get_int = punch.fmu.getInteger if fmi2 else punch.fmu.getInt32
    vr = punch.vr["compression_only"]
    assert list(get_int([vr])) == [0]
    _refused(punch, set_int, [vr], [2], reason="outside its range [0, 1]")
    set_int([vr], [1])
    assert list(get_int([vr])) == [1]
    _refused(punch, _set, punch, [vr], [1.0], reason="compression_only is not a Real")
    _refused(punch, punch.fmu.setBoolean, [punch.vr["contact"]], [True],
             reason="contact is an output")
    assert list(punch.fmu.getBoolean([punch.vr["contact"]])) == [False]
    _refused(punch, punch.fmu.getBoolean, [punch.vr["y"]], reason="no such variable")
    get_string = punch.fmu.getString
    _refused(punch, get_string, [vr], reason="no such variable")
    punch.start()
    _refused(punch, set_int, [vr], [0], reason="parameter compression_only is fixed")


@pytest.mark.slow
def test_an_input_outside_its_range_is_refused_and_the_step_goes_on(punch):
    punch.start()
    xi = punch.vr["xi"]
    _refused(punch, _set, punch, [xi], [5.0], reason="input xi = 5 m is outside its range")
    # in the Python FMU's words: where a run is, and what such a value usually is
    _refused(punch, _set, punch, [xi], [5.0], reason="(set at t = 0 s: a co-simulation that "
                                                     "diverges, or a value in another unit)")
    _refused(punch, _set, punch, [xi], [math.nan], reason="not a finite number")
    punch.fmu.doStep(0.0, 1e-5)
    assert all(math.isfinite(x) for x in punch.outputs(["y", "y_dot"]))


@pytest.mark.slow
def test_fmi3s_time_is_read_and_never_set(native_fmu):
    inst = Instance(native_fmu("MainShaft", 3), 3, name="shaft1")
    try:
        inst.start(0.5)
        inst.fmu.doStep(0.5, 1e-3)
        assert list(inst.fmu.getFloat64([0])) == [0.5 + 1e-3]
        _refused(inst, _set, inst, [0], [1.0], reason="time is the independent variable")
    finally:
        inst.free()


def _fnv1a(data: bytes) -> int:
    h = 14695981039346656037
    for byte in data:
        h = ((h ^ byte) * 1099511628211) % 2 ** 64
    return h


def _payload_at(data: bytes) -> int:
    """Where the payload of a serialized state begins (native/runtime/sew_state.c's layout:
    magic, model name, token, payload size, payload, checksum)."""
    at = 8
    for _ in range(2):
        at += 4 + struct.unpack_from("<I", data, at)[0]
    return at + 4


@pytest.mark.parametrize("forgery", ["parameter out of range", "time not finite", "mode",
                                     "reason too long"])
def test_a_forged_state_with_a_good_checksum_is_refused(shaft, forgery):
    shaft.start()
    shaft.fmu.doStep(0.0, 1e-3)
    fmi2 = shaft.fmi == 2
    state = (shaft.fmu.getFMUstate if fmi2 else shaft.fmu.getFMUState)()
    data = bytearray((shaft.fmu.serializeFMUstate if fmi2 else shaft.fmu.serializeFMUState)(
        state))
    at = _payload_at(data)                     # phase, initialized, time, elapsed, values...
    if forgery == "parameter out of range":
        struct.pack_into("<d", data, at + 18, 5000.0)          # omega0
        reason = "omega0 = 5000 is outside its declared range"
    elif forgery == "time not finite":
        struct.pack_into("<d", data, at + 2, math.nan)
        reason = "its time is not a finite number"
    elif forgery == "mode":
        data[at] = 7
        reason = "its mode is not one of this FMU's"
    else:
        struct.pack_into("<H", data, at + 18 + 8 * 2, 5000)    # after MainShaft's 2 values
        reason = "garbled"
    struct.pack_into("<Q", data, len(data) - 8, _fnv1a(bytes(data[:-8])))
    deserialize = shaft.fmu.deSerializeFMUstate if fmi2 else shaft.fmu.deserializeFMUState
    _refused(shaft, deserialize, bytes(data), reason=reason)
