"""The native FMUs in the master (experiment.fmus = "native"): every co-simulated catalogue
scenario gives the Python FMUs' key figures and series (≤ 1e-9 relative), FMI 2.0 and 3.0; a
native FMU's refusal (an input outside its range, fmi2Error at the set) reaches the user as the
Python FMU's Discard does, one line naming the instance, the step and the reason. The native
FMUs are built once per session from this session's Python FMUs (tests/conftest.py)."""
import math

import numpy as np
import pytest

import sewfmu
from sewfmu.scenarios.cosim.master import Master
from sewfmu.scenarios.fmu_build.native_current import native_fmu_dir
from sewfmu.scenarios.fmu_build.up_to_date import fmus_for

RTOL = 1e-9
OFF = {"experiment.accuracy": "off"}        # the figures only: no coarser run beside


def cosimulated() -> list[str]:
    return [name for name in sewfmu.catalogue() if sewfmu.load(name).study is None]


@pytest.fixture(autouse=True)
def _builder():
    """The native builder; each run builds the native FMUs it needs (into FMU_DIR/native/) from
    this session's Python FMUs."""
    pytest.importorskip("sewfmu.scenarios.fmu_build.native")


def _runs(run) -> dict:
    """label -> the Run of each variant (one, or one per value of [compare])."""
    return dict(run.runs) if run.runs else {"": run}


def _same(python, native, where: str) -> None:
    figures = {k: v for k, v in python.figures.items() if k != "wall_time_s"}
    assert set(figures) == {k for k in native.figures if k != "wall_time_s"}, where
    for key, a in figures.items():
        b = native.figures[key]
        if isinstance(a, float) and math.isnan(a):
            assert math.isnan(b), f"{where} {key}: {a} against {b}"
        else:
            assert abs(a - b) <= RTOL * max(abs(a), abs(b)), f"{where} {key}: {a!r} != {b!r}"
    a, b = python.series, native.series
    assert a.dtype.names == b.dtype.names and len(a) == len(b), where
    for column in a.dtype.names:
        x, y = np.asarray(a[column], float), np.asarray(b[column], float)
        scale = max(float(np.max(np.abs(x))), 1e-300)
        worst = float(np.max(np.abs(x - y))) / scale
        assert worst <= RTOL, f"{where} {column}: {worst:.3g} relative to its largest value"


@pytest.mark.slow
@pytest.mark.parametrize("scenario", cosimulated())
def test_a_catalogue_scenario_on_native_fmus_gives_the_python_figures_fmi2(scenario, fmu_dir):
    python = sewfmu.run(scenario, set=OFF, fmu_dir=fmu_dir)
    native = sewfmu.run(scenario, set={**OFF, "experiment.fmus": "native"}, fmu_dir=fmu_dir)
    for label, run in _runs(native).items():
        made = run.provenance
        assert set(made["fmu_builds"].values()) == {"native"}, made["fmu_builds"]
        assert all(path.startswith(str(native_fmu_dir(2, fmu_dir)))
                   for path in made["fmu_files"].values()), made["fmu_files"]
        _same(_runs(python)[label], run, f"{scenario}{label and ' ' + label} (FMI 2.0)")


# FMI 3.0: the scenarios of every native FMU (the runtime and models are FMI 2.0's, checked over
# the whole catalogue above; what differs is the FMI 3.0 glue), to keep CI within its time
FMI3_SCENARIOS = ["punch_drive", "punch_split", "carriage_startstop", "feed", "takeup"]


@pytest.mark.slow
@pytest.mark.parametrize("scenario", FMI3_SCENARIOS)
def test_a_catalogue_scenario_on_native_fmus_gives_the_python_figures_fmi3(scenario, fmu_dir,
                                                                           fmu3_dir):
    fmi3 = {**OFF, "experiment.fmi": 3}
    try:
        python = sewfmu.run(scenario, set=fmi3, fmu_dir=fmu_dir)
    except sewfmu.Error as err:             # not run on FMI 3.0 today: nothing to hold it to
        pytest.skip(f"{scenario} does not run on the FMI 3.0 Python FMUs: {err}")
    native = sewfmu.run(scenario, set={**fmi3, "experiment.fmus": "native"}, fmu_dir=fmu_dir)
    for label, run in _runs(native).items():
        made = run.provenance
        assert set(made["fmu_builds"].values()) == {"native"}, made["fmu_builds"]
        assert set(made["fmi"].values()) == {"3.0"}, made["fmi"]
        _same(_runs(python)[label], run, f"{scenario}{label and ' ' + label} (FMI 3.0)")


# the linkage's angular acceleration input leaves its declared range in the shaft's ramp
# (tests/cosim/test_reliability.py): the Python FMU discards the step, the native one refuses
# the value as it is set
BAD = {"shaft.omega0": 2000.0, "shaft.ramp_time": 2e-4, "experiment.stop_time": 1e-3,
       "experiment.step": 1e-5, **OFF}


@pytest.mark.slow
@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("master", ["jacobi", "gauss-seidel", "iterative", "adaptive"])
def test_a_native_refusal_is_the_python_discards_one_line(master, fmi, fmu_dir, fmu3_dir):
    told = {}
    for kind in ("python", "native"):
        with pytest.raises(sewfmu.Error) as err:
            sewfmu.run("punch_drive", set={**BAD, "experiment.master": master,
                                           "experiment.fmi": fmi, "experiment.fmus": kind},
                       fmu_dir=fmu_dir)
        told[kind] = str(err.value)
    for kind, text in told.items():
        assert "\n" not in text, text
        assert text.startswith("linkage failed during step from t = "), text
        assert "input epsilon = " in text and "is outside its range [-1e+07, 1e+07]" in text, text
    python_t, native_t = (float(told[k].split("from t = ")[1].split(" ")[0]) for k in told)
    # refused when the value is set: at the end of the step that reached it (Jacobi, the
    # iterative master), not at the start of the next step as the Python FMU's doStep does
    assert native_t <= python_t <= native_t + 1e-5 * (1 + 1e-9) or master == "adaptive", told


@pytest.mark.slow
@pytest.mark.parametrize("fmi", [2, 3])
def test_a_parameter_refused_at_its_setter_is_one_line_too(fmi, fmu_dir, fmu3_dir):
    """A NaN parameter past the scenario's checks (a Master given it directly): the Python FMU
    refuses it at exitInitializationMode, the native one at its setter (fmpy raises
    FMICallException on the Error); both one line naming the instance, the phase and why."""

    told = {}
    for kind in ("python", "native"):
        sc = sewfmu.load("punch_drive", set={"experiment.revolutions": 1, "experiment.fmi": fmi,
                                             "experiment.fmus": kind})
        sc.instances["punch"].parameters["m"] = float("nan")
        with pytest.raises(sewfmu.Error) as err:
            Master(sc, fmus_for(sc, fmu_dir)).run()
        told[kind] = str(err.value)
    for text in told.values():
        assert "\n" not in text and text.startswith(
            "punch failed during initialization at t = 0 s: punch (PunchContact): "), text
        assert "parameter m" in text and "nan" in text, text
