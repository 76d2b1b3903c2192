"""After a discarded step a native FMU answers fmi2GetBooleanStatus(fmi2Terminated) with true,
as the Python FMU does (pythonfmu's binary sets it at a Discard), so that a host which asks
(fmpy's simulate_fmu, fmusim) ends the run instead of retrying the same step without end; FMI
3.0's doStep says terminateSimulation = false at a Discard, as the Python FMU's (pythonfmu3),
and fmpy stops there on the status."""
from __future__ import annotations

import subprocess
import sys

import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2LastSuccessfulTime, fmi2Terminated

from tests.native.fmpy_native import Instance

DISCARD = 2
# a step of 1000 s: far more switch searches than PunchContact takes in one step (Discard)
RUN = ("from fmpy import simulate_fmu\n"
       "import sys\n"
       "try:\n"
       "    rows = simulate_fmu(sys.argv[1], stop_time=1e4, output_interval=1e3)\n"
       "    print('rows', len(rows))\n"
       "except Exception as err:\n"
       "    print('raised', err)\n")


def _simulate(fmu) -> str:
    done = subprocess.run([sys.executable, "-c", RUN, str(fmu)], capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 0, done.stderr[-2000:]
    # fmpy prints the FMU's log lines: the discarded step's once, not once per retry
    lines = done.stdout.strip().splitlines()
    assert len(lines) <= 3, lines[:5]
    return lines[-1]


def test_fmi2_terminated_is_true_after_a_discard_and_false_after_a_step(native_fmu):
    inst = Instance(native_fmu("PunchContact", 2), 2, name="punch1")
    inst.start()
    assert not inst.fmu.getBooleanStatus(fmi2Terminated)
    with pytest.raises(FMICallException) as caught:
        inst.fmu.doStep(0.0, 1000.0)
    assert caught.value.status == DISCARD
    assert inst.fmu.getBooleanStatus(fmi2Terminated)
    assert inst.fmu.getRealStatus(fmi2LastSuccessfulTime) == 0.0   # the step was not taken
    inst.fmu.doStep(0.0, 1e-4)           # a master that retries shorter goes on
    assert not inst.fmu.getBooleanStatus(fmi2Terminated)
    inst.free()


def test_fmpy_ends_a_run_at_a_discard_as_with_the_python_fmu(native_fmu, tmp_path):
    # the Python FMU of the same name (built beside the native one) as the measure
    native = native_fmu("PunchContact", 2)
    python = native.parent.parent / "python2" / "PunchContact.fmu"
    assert python.is_file()
    said = _simulate(native)
    assert said.startswith("rows ") and said == _simulate(python), said


@pytest.mark.slow
def test_fmi3_a_discard_ends_fmpys_run_as_with_the_python_fmu(native_fmu):
    native = native_fmu("PunchContact", 3)
    python = native.parent.parent / "python3" / "PunchContact.fmu"
    said = _simulate(native)
    assert said.startswith("raised ") and "discard" in said, said
    assert _simulate(python).startswith("raised "), said
