"""The runtime against the Python slave, call for call: a native FMU and its Python FMU, both in
fmpy, given the same random input histories (each step a random choice of which inputs the host
sets: values alone, rates alone, all, none), give the same outputs bit for bit at every step and
the same step statuses. This holds the held rates (a rate not set since its value was acts as
zero) and the Taylor extrapolation inside a step to slave.py's arithmetic."""
from __future__ import annotations

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from sewfmu.scenarios.fmu_build.native import MODEL_FILES, MODELS
from tests.native.fmpy_native import Instance

# the FMUs with inputs (MainShaft has none)
WITH_INPUTS = [n for n in MODEL_FILES if n != "MainShaft"]


def _step(inst: Instance, t: float, h: float) -> int:
    try:
        inst.fmu.doStep(t, h)
    except FMICallException as err:
        return err.status
    return 0


def _read(inst: Instance, reals, booleans) -> list:
    values = inst.outputs(reals)
    if booleans:
        values += [bool(b) for b in inst.fmu.getBoolean([inst.vr[n] for n in booleans])]
    return values


@pytest.mark.slow
@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("name", WITH_INPUTS)
@pytest.mark.parametrize("seed", [1, 2])
def test_random_input_histories_give_the_python_fmus_outputs(native_fmu, name, fmi, seed):
    if not all((MODELS / f).is_file() for f in MODEL_FILES[name]):
        pytest.skip(f"{name}: native/models/ lacks one of {', '.join(MODEL_FILES[name])}")
    native_path = native_fmu(name, fmi)
    python_path = native_path.parent.parent / f"python{fmi}" / native_path.name
    native, python = Instance(native_path, fmi, name="n"), Instance(python_path, fmi, name="p")
    md = native.md
    inputs = [v for v in md.modelVariables if v.causality == "input"]
    reals = [v.name for v in md.modelVariables
             if v.causality == "output" and v.type in ("Real", "Float64")]
    booleans = [v.name for v in md.modelVariables
                if v.causality == "output" and v.type == "Boolean"]
    rng = np.random.default_rng(seed)
    start = {v.name: float(v.start) for v in inputs}
    # a random walk from the start values, in each input's own scale (an unbounded one, the
    # cumulative shaft angle, by whole radians: sums of terms of unlike size round unlike)
    scale = {v.name: 1.0 if v.max is None else
             max(abs(start[v.name]), 1e-3 * float(v.max)) * 0.05 for v in inputs}
    value = dict(start)
    h = float(md.defaultExperiment.stepSize)
    t = 0.0
    try:
        for inst in (native, python):
            inst.start()
        assert _read(native, reals, booleans) == _read(python, reals, booleans)
        for k in range(200):
            everything = rng.random() < 0.5       # a host that sets all, or a random few
            chosen = [v.name for v in inputs if everything or rng.random() < 0.5]
            for n in chosen:
                value[n] += scale[n] * rng.standard_normal()
                for inst in (native, python):
                    inst.set_real(n, value[n])
            # outputs read between the sets and the step: the held inputs, not extrapolated
            assert _read(native, reals, booleans) == _read(python, reals, booleans), (k, chosen)
            step = h * (0.5 + rng.random())     # variable communication steps
            statuses = _step(native, t, step), _step(python, t, step)
            assert statuses[0] == statuses[1], (k, statuses, native.lines[-1:],
                                                python.lines[-1:])
            if statuses[0]:
                break
            t += step
            assert _read(native, reals, booleans) == _read(python, reals, booleans), (k, chosen)
    finally:
        native.free()
        python.free()


@pytest.mark.slow
@pytest.mark.parametrize("fmi", [2, 3])
def test_a_step_the_model_cannot_take_is_discarded_as_by_the_python_fmu(native_fmu, fmi):
    native_path = native_fmu("PunchContact", fmi)
    python_path = native_path.parent.parent / f"python{fmi}" / native_path.name
    native, python = Instance(native_path, fmi, name="n"), Instance(python_path, fmi, name="p")
    outputs = ["y", "y_dot", "F2", "F2_max"]
    try:
        for inst in (native, python):
            inst.start()
            inst.fmu.doStep(0.0, 1e-4)
        # far too long for the switch search (StepTooLong): Discard, the instance as it was
        assert _step(native, 1e-4, 100.0) == _step(python, 1e-4, 100.0) == 2
        status, line = native.lines[-1]
        assert status == 2 and "discarded: a step of 100 s needs" in line, line
        assert line.split("discarded: ")[1] == python.lines[-1][1].split("discarded: ")[1]
        for inst in (native, python):
            inst.fmu.doStep(1e-4, 1e-4)
        assert native.outputs(outputs) == python.outputs(outputs)
    finally:
        native.free()
        python.free()
