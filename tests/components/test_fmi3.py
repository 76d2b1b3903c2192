"""The FMI 3.0 FMUs: built from the same model code as the FMI 2.0 ones, they declare the same
variables and run every catalogue scenario to the same numbers; they match the regression
references; both versions of an FMU run side by side in one process, each its own code. (The
tests of the FMUs themselves, in test_fmus.py and test_fmi_statuses.py, run against both.)"""
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException

from sewfmu.components.punch_linkage import PunchLinkage
from sewfmu.components.registry import FMUS
from sewfmu.scenarios.format.loader import catalogue, load
from sewfmu.scenarios.interop.ssp_export import export
from sewfmu.scenarios.references import regression as references
from sewfmu.scenarios.runs.runner import simulate
from sewfmu.scenarios.runs.variants import variants
from tests.fmu_host import Host
from tests.paths import REPO


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


def _declared(path):
    """Every variable but FMI 3.0's independent `time`, in FMI 2.0's words, by name; the
    outputs' dependencies by name."""
    md = read_model_description(str(path))
    kinds = {"Float64": "Real", "Int32": "Integer"}
    variables = {v.name: (kinds.get(v.type, v.type), v.causality, v.variability, v.unit,
                          v.description, None if v.start is None else float(v.start))
                 for v in md.modelVariables if v.causality != "independent"}
    dependencies = {u.variable.name: sorted(d.name for d in u.dependencies or ())
                    for u in md.outputs}
    initial = sorted(u.variable.name for u in md.initialUnknowns)
    experiment = md.defaultExperiment
    return (variables, dependencies, initial,
            (float(experiment.stopTime), float(experiment.stepSize)))


@pytest.mark.parametrize("name", list(FMUS))
def test_both_versions_declare_the_same_variables_structure_and_experiment(fmu_paths,
                                                                          fmu3_paths, name):
    assert _declared(fmu3_paths[name]) == _declared(fmu_paths[name])
    md = read_model_description(str(fmu3_paths[name]))
    assert md.fmiVersion == "3.0"
    independent = [v for v in md.modelVariables if v.causality == "independent"]
    assert [(v.name, v.unit) for v in independent] == [("time", "s")]
    cs = md.coSimulation
    assert (cs.needsExecutionTool, cs.canGetAndSetFMUstate, cs.canSerializeFMUstate,
            cs.canHandleVariableCommunicationStepSize) == (False, True, True, True)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(FMUS))
def test_every_fmi3_fmu_matches_the_regression_reference(fmu3_paths, name):
    assert references.check(name, fmu3_paths[name]) == []


def _runs() -> list:
    """Every run of the catalogue: each scenario, each [compare] variant."""
    return [pytest.param(scenario, id=f"{name}{'-' + label if label else ''}")
            for name in sorted(catalogue()) if not load(name).study     # studies: computed
            for label, scenario in variants(load(name))]


@pytest.mark.slow
@pytest.mark.parametrize("scenario", _runs())
def test_every_catalogue_run_gives_the_same_numbers_with_fmi3(scenario, fmu_dir):
    fmi2 = simulate(scenario, fmu_dir)
    scenario.set_value("experiment.fmi", 3)
    fmi3 = simulate(scenario, fmu_dir)
    assert list(fmi3.columns) == list(fmi2.columns)
    assert np.array_equal(fmi3.time, fmi2.time)
    for column in fmi2.columns:                      # bit for bit: the same code, step by step
        assert np.array_equal(fmi3[column], fmi2[column]), column
    assert fmi3.coupling == fmi2.coupling            # the adaptive master's steps included


@pytest.mark.slow
def test_an_fmi3_system_exported_to_ssp_runs_from_the_file(tmp_path, fmu_dir):
    scenario = load("punch_split")
    scenario.set_value("experiment.fmi", 3)
    ssp = export(scenario, tmp_path / "split3.ssp")
    with zipfile.ZipFile(ssp) as zf:
        (tmp_path / "PunchBody.fmu").write_bytes(zf.read("resources/PunchBody.fmu"))
    assert read_model_description(str(tmp_path / "PunchBody.fmu")).fmiVersion == "3.0"
    back = simulate(load(str(ssp)))
    original = simulate(scenario, fmu_dir)
    assert list(back.columns) == list(original.columns)
    for column in original.columns:
        assert np.array_equal(back[column], original[column]), column


def test_the_start_time_is_the_first_step_s_communication_point(fmu3_paths):
    """pythonfmu3's binary does not pass fmi3EnterInitializationMode's start time on: the first
    doStep's communication point is the start (FMI 3.0 has the first step begin there); the
    steps after it must follow on."""
    host = Host(fmu3_paths["PunchLinkage"], "late")
    host.set(phi=0.3, omega=100.0, epsilon=0.0)
    host.fmu.exitInitializationMode()
    for k in range(3):
        host.fmu.doStep(5.0 + k * 1e-3, 1e-3)
    assert host.get("xi") == pytest.approx(PunchLinkage().motion(0.3 + 0.3, 100.0, 0.0).xi,
                                           rel=1e-12)
    with pytest.raises(FMICallException, match="discard"):
        host.fmu.doStep(4.0, 1e-3)
    assert "the last one ended at t = 5.003" in host.log.lines[-1]


_SIDE_BY_SIDE = """
import sys
sys.path.insert(0, sys.argv[1])
from pathlib import Path
from sewfmu.scenarios.cosim.fmi_calls import LogCollector
from sewfmu.scenarios.cosim.instances import open_instance
instances = []
for path in sys.argv[2:]:
    inst = open_instance("fmi", Path(path), LogCollector())
    inst.name = inst.md.fmiVersion
    inst.real_out = ["phi"]
    inst.prepare(); inst.instantiate(); inst.enter_initialization(1.0)
    inst.set_parameter(inst.variables["omega0"], 40.0)
    inst.exit_initialization()
    instances.append(inst)
for k in range(10):
    for inst in instances:
        inst.do_step(k * 0.01, 0.01)
for inst in instances:
    inst.read_outputs()
    print(inst.name, type(inst.fmu).__name__, inst.out_buf[0])
    inst.release()
print(sorted(m for m in sys.modules if m.startswith("sewfmu") and "MainShaft" in m))
"""


@pytest.mark.slow
def test_both_versions_of_an_fmu_run_side_by_side_each_its_own_code(fmu_paths, fmu3_paths,
                                                                    tmp_path):
    """The FMI 2.0 and 3.0 FMUs of one model, code of one hash, loaded into one process: each
    imports its own script and package (a shared module name would hand the FMI 3.0 binary the
    FMI 2.0 class, which answers its first call with Fatal)."""
    proc = subprocess.run([sys.executable, "-c", _SIDE_BY_SIDE, str(REPO),
                           str(fmu_paths["MainShaft"]), str(fmu3_paths["MainShaft"])],
                          capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = proc.stdout.strip().splitlines()
    assert lines[0].split()[:2] == ["2.0", "FMU2Slave"]
    assert lines[1].split()[:2] == ["3.0", "FMU3Slave"]
    assert float(lines[0].split()[2]) == float(lines[1].split()[2]) == pytest.approx(4.0)
    scripts = eval(lines[2])                        # noqa: S307 - our own printed list
    assert len(scripts) == 2 and {s.split("_")[0] for s in scripts} == {"sewfmu", "sewfmu3"}


@pytest.mark.slow
def test_sewfmu_build_fmi3_writes_into_the_fmi3_folder(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "sewfmu", "build", "--fmi", "3",
                           "--dest", str(tmp_path)], capture_output=True, text=True,
                          timeout=300, cwd=REPO)
    assert proc.returncode == 0, proc.stderr
    built = sorted(p.name for p in (tmp_path / "fmi3").glob("*.fmu"))
    assert built == sorted(f"{name}.fmu" for name in FMUS)
    assert not list(tmp_path.glob("*.fmu"))          # the FMI 2.0 ones are not touched


@pytest.mark.parametrize("value", ["4", "true", "2.5", "\"3\""])
def test_another_fmi_version_is_one_clear_line(capsys, tmp_path, value):
    from sewfmu.cli import main
    assert main(["run", "punch_drive", "--set", f"experiment.fmi={value}",
                 "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "experiment.fmi" in err and "2 or 3" in err, err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("logging_on", [True, False])
def test_an_fmi3_fmu_logs_only_with_logging_on(fmu3_paths, logging_on):
    """FMI 3.0: with loggingOn = false the FMU calls no logMessage at all; on, a bad parameter
    is logged at Error with its reason; either way every doStep is refused (Discard)."""
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave

    path = fmu3_paths["PunchContact"]
    md = read_model_description(str(path))
    messages = []
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="punch")
    fmu.instantiate(loggingOn=logging_on,
                    logMessage=lambda env, status, category, text: messages.append((status, text)))
    mass = next(v.valueReference for v in md.modelVariables if v.name == "m")
    fmu.enterInitializationMode()
    fmu.setFloat64([mass], [-1.0])
    fmu.exitInitializationMode()
    with pytest.raises(FMICallException, match="discard"):
        fmu.doStep(0.0, 1e-3)
    fmu.terminate()
    fmu.fmi3FreeInstance(fmu.component)              # the library stays loaded (pythonfmu3)
    if logging_on:
        assert messages and messages[0][0] == 3 and b"parameter m: must be > 0 kg" in messages[0][1]
    else:
        assert messages == []
