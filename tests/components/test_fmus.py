"""The FMUs as FMI components: validation, the co-simulation contract, parameter and input
checks, state save and restore, and running from the .fmu file alone."""
import json
import math
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from sewfmu.components.carriage import CarriageDrive
from sewfmu.components.punch_contact import GRAVITY, PunchContactParams
from sewfmu.components.punch_linkage import PunchLinkage
from sewfmu.components.punch_split import PunchBody
from sewfmu.components.registry import FMUS
from sewfmu.components.shaft import MainShaft
from tests.fmu_host import Host
from tests.paths import REPO


def test_every_fmu_passes_fmpy_validate(fmus):
    assert set(fmus) == set(FMUS)
    for name, path in fmus.items():
        assert validate_fmu(str(path)) == [], name


def test_every_variable_has_a_unit_and_a_description(fmus):
    for path in fmus.values():
        md = Host(path).md
        for v in md.modelVariables:
            assert v.description, v.name
            if v.type == "Real":
                assert v.unit, v.name


def test_outputs_declare_their_dependency_on_inputs(fmus):
    md = Host(fmus["PunchContact"]).md
    deps = {u.variable.name: [d.name for d in u.dependencies] for u in md.outputs}
    assert deps["y"] == [] and deps["F2"] == []              # state only
    assert deps["F3"] == ["xi", "xi_dot", "xi_ddot"]          # direct feedthrough
    md = Host(fmus["PunchLinkage"]).md
    assert all(len(u.dependencies) == 3 for u in md.outputs)


# --- the co-simulation contract -----------------------------------------------------------------
def test_outputs_after_initialization_follow_the_inputs_set_during_it(fmus):
    link = Host(fmus["PunchLinkage"])
    link.set(phi=1.0, omega=120.0, epsilon=50.0)
    link.fmu.exitInitializationMode()
    e = PunchLinkage().motion(1.0, 120.0, 50.0)
    assert link.get("xi", "xi_dot", "xi_ddot") == pytest.approx([e.xi, e.xi_dot, e.xi_ddot],
                                                                rel=1e-12)
    # direct feedthrough: new inputs, same instant, new outputs (no step)
    link.set(phi=2.0)
    assert link.get("xi") == pytest.approx(PunchLinkage().motion(2.0, 120.0, 50.0).xi)
    punch = Host(fmus["PunchContact"])
    punch.set(xi=3.7e-3, xi_dot=0.0, xi_ddot=0.0)
    punch.fmu.exitInitializationMode()
    assert punch.get("y", "y_dot", "Delta", "contact") == [3.7e-3, 0.0, 0.0, False]


def test_outputs_after_a_step_are_values_at_its_end(fmus):
    """The linkage extrapolates its inputs over the step (Taylor): after doStep(t, h) its outputs
    are the excitation at t + h even if the host does not set new inputs (libcosim, ecos)."""
    link = Host(fmus["PunchLinkage"])
    link.set(phi=0.5, omega=100.0, epsilon=400.0)
    link.fmu.exitInitializationMode()
    h = 1e-3
    link.fmu.doStep(0.0, h)
    e = PunchLinkage().motion(0.5 + 100.0 * h + 0.5 * 400.0 * h * h, 100.0 + 400.0 * h, 400.0)
    assert link.get("xi", "xi_dot") == pytest.approx([e.xi, e.xi_dot], rel=1e-12)
    shaft = Host(fmus["MainShaft"])
    shaft.set(omega0=80.0)
    shaft.fmu.exitInitializationMode()
    shaft.fmu.doStep(0.0, 0.25)
    assert shaft.get("phi", "omega") == pytest.approx([20.0, 80.0])


# --- bad parameters and inputs -----------------------------------------------------------------
@pytest.mark.parametrize("fmu, values, words", [
    ("PunchContact", {"m": -1.0}, ["parameter m", "> 0"]),
    ("PunchContact", {"c1": float("nan")}, ["parameter c1", "finite"]),
    ("PunchContact", {"compression_only": 3}, ["parameter compression_only"]),
    ("MainShaft", {"omega0": 0.0}, ["parameter omega0"]),
    ("PunchLinkage", {"L_AB": 29.0e-3}, ["cannot be assembled", "crank angle alpha ="]),
])
def test_bad_parameters_are_named_at_initialization_and_every_step_is_discarded(fmus, fmu,
                                                                                 values, words):
    """pythonfmu could fail exitInitializationMode only with fmi2Fatal (after which a host may
    not even free the instance): the FMU logs an fmi2Error line naming the parameter there, and
    refuses every doStep with fmi2Discard; the instance stays healthy and is freed."""
    host = Host(fmus[fmu])
    host.set(**values)
    host.fmu.exitInitializationMode()
    errors = [line for line in host.log.lines if line.startswith("[ERROR]")]
    assert errors, host.log_text()
    for word in words:
        assert word in errors[0]
    for _ in range(2):
        with pytest.raises(FMICallException, match="discard"):
            host.fmu.doStep(0.0, 1e-3)
    assert all(word in host.log.lines[-1] for word in words), host.log.lines[-1]
    assert not host.failed
    host.close()                                   # terminate and free: no crash


@pytest.mark.parametrize("bad", [float("nan"), float("inf")])
def test_nan_or_infinite_inputs_are_refused_by_do_step(fmus, bad):
    punch = Host(fmus["PunchContact"])
    punch.set(xi=4e-3, xi_ddot=0.0)
    punch.fmu.exitInitializationMode()
    punch.fmu.doStep(0.0, 1e-4)
    punch.set(xi_dot=bad)
    with pytest.raises(FMICallException):
        punch.fmu.doStep(1e-4, 1e-4)
    assert "input xi_dot" in punch.log_text()


# --- state -----------------------------------------------------------------------------------
def _punch_chain(fmu_paths):
    shaft, link, punch = (Host(fmu_paths[n], n) for n in ("MainShaft", "PunchLinkage",
                                                          "PunchContact"))
    shaft.set(omega0=150.0)
    shaft.fmu.exitInitializationMode()
    link.set(**dict(zip(("phi", "omega", "epsilon"), shaft.get("phi", "omega", "epsilon"))))
    link.fmu.exitInitializationMode()
    punch.set(**dict(zip(("xi", "xi_dot", "xi_ddot"), link.get("xi", "xi_dot", "xi_ddot"))))
    punch.fmu.exitInitializationMode()
    return shaft, link, punch


def _jacobi_steps(chain, t0, n, h):
    shaft, link, punch = chain
    out = []
    for k in range(n):
        t = t0 + k * h
        for unit in chain:
            unit.fmu.doStep(t, h)
        link.set(**dict(zip(("phi", "omega", "epsilon"), shaft.get("phi", "omega", "epsilon"))))
        punch.set(**dict(zip(("xi", "xi_dot", "xi_ddot"), link.get("xi", "xi_dot", "xi_ddot"))))
        out.append(tuple(punch.get("y", "y_dot", "F2", "F3", "F2_max", "contact")))
    return out


@pytest.mark.parametrize("serialize", [False, True])
def test_restored_state_repeats_the_steps_bit_for_bit(fmus, serialize):
    chain = _punch_chain(fmus)
    h = 2e-4
    _jacobi_steps(chain, 0.0, 60, h)                  # into the contact phase (φ ≈ 103°)
    states = [u.fmu.getFMUstate() for u in chain]
    if serialize:
        blobs = [u.fmu.serializeFMUstate(s) for u, s in zip(chain, states)]
    first = _jacobi_steps(chain, 60 * h, 80, h)
    assert any(row[-1] for row in first) and not all(row[-1] for row in first)  # a landing
    if serialize:
        states = [u.fmu.deSerializeFMUstate(b) for u, b in zip(chain, blobs)]
    for unit, state in zip(chain, states):
        unit.fmu.setFMUstate(state)
    second = _jacobi_steps(chain, 60 * h, 80, h)
    assert first == second                            # exactly, not approximately


# --- the FMU runs the code it carries ----------------------------------------------------------
_ALONE = r'''
import importlib.abc, json, sys
repo, path, spec = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])

class NoRepository(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in ("components", "scenarios", "tests"):
            raise ImportError("the repository is not on this path: " + name)
        return None

sys.meta_path.insert(0, NoRepository())
sys.path[:] = [p for p in sys.path
            if p and not (p.startswith(repo) and not p.startswith(sys.prefix))]
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
md = read_model_description(path)
vr = {v.name: v.valueReference for v in md.modelVariables}
unzip = str(extract(path))
fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip,
                modelIdentifier=md.coSimulation.modelIdentifier, instanceName="alone")
fmu.instantiate()
fmu.setupExperiment(startTime=0.0)
fmu.enterInitializationMode()
for name, value in spec["set"].items():
    fmu.setReal([vr[name]], [value])
fmu.exitInitializationMode()
for k in range(spec["steps"]):
    fmu.doStep(k * spec["h"], spec["h"])
out = dict(zip(spec["get"], fmu.getReal([vr[n] for n in spec["get"]])))
carried = sorted({m.__file__ for n, m in sys.modules.items()
                  if n.startswith("sewfmu_") and getattr(m, "__file__", None)})
fmu.terminate()
fmu.fmi2FreeInstance(fmu.component)
print(json.dumps({"out": out, "unzip": unzip, "modules": carried}))
'''


def _run_alone(tmp_path, fmu_path, spec):
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    proc = subprocess.run([sys.executable, "-c", _ALONE, str(REPO), str(fmu_path),
                           json.dumps(spec)], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, (fmu_path.name, proc.stderr)
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result["modules"], "no sewfmu module was loaded from the FMU"
    for module_file in result["modules"]:
        assert module_file.startswith(result["unzip"]), module_file
    return result["out"]


@pytest.mark.slow
def test_each_fmu_runs_from_its_file_alone_in_a_fresh_process(fmu_paths, tmp_path):
    out = _run_alone(tmp_path, fmu_paths["MainShaft"],
                     {"set": {"omega0": 40.0}, "steps": 10, "h": 0.01, "get": ["phi"]})
    assert out["phi"] == pytest.approx(4.0, rel=1e-12)
    out = _run_alone(tmp_path, fmu_paths["PunchLinkage"],
                     {"set": {"phi": 0.0, "omega": 0.0}, "steps": 1, "h": 0.01,
                      "get": ["xi", "psi"]})
    assert out == pytest.approx({"xi": 4.5e-3, "psi": 0.0}, abs=1e-15)   # the setup position
    # the punch settles under a still slider where the forces balance (closed form)
    p = PunchContactParams()
    xi = 2.0e-3
    out = _run_alone(tmp_path, fmu_paths["PunchContact"],
                     {"set": {"xi": xi, "xi_ddot": 0.0}, "steps": 400, "h": 1e-3, "get": ["y"]})
    assert out["y"] == pytest.approx((-p.F10 + p.c3 * xi - p.m * GRAVITY) / (p.c1 + p.c3),
                                     abs=1e-12)


def test_instances_in_one_process_are_independent(fmus):
    """Two punches with different springs, stepped interleaved, each end where a punch alone
    ends: nothing is shared between instances."""
    def punch(c3):
        host = Host(fmus["PunchContact"], f"punch_c3_{c3:g}")
        host.set(c3=c3, xi=2e-3, xi_ddot=0.0)
        host.fmu.exitInitializationMode()
        return host

    a, b = punch(5e4), punch(2e5)
    for k in range(300):
        a.fmu.doStep(k * 1e-3, 1e-3)
        b.fmu.doStep(k * 1e-3, 1e-3)
    alone = punch(5e4)
    for k in range(300):
        alone.fmu.doStep(k * 1e-3, 1e-3)
    assert a.get("y") == alone.get("y")
    assert b.get("y") != a.get("y")


def test_ensure_built_rebuilds_only_what_is_missing_or_stale(fmu_dir, tmp_path):
    import shutil

    from sewfmu.scenarios.fmu_build.up_to_date import ensure_built

    target = tmp_path / "fmus"
    shutil.copytree(fmu_dir, target)
    before = {p.name: p.stat().st_mtime_ns for p in target.glob("*.fmu")}
    ensure_built(["MainShaft", "PunchContact"], target)
    assert {p.name: p.stat().st_mtime_ns for p in target.glob("*.fmu")} == before
    (target / "MainShaft.fmu").write_bytes(b"not a zip")        # broken: rebuilt
    ensure_built(["MainShaft"], target)
    assert validate_fmu(str(target / "MainShaft.fmu")) == []


def test_a_run_leaves_the_host_path_alone_and_builds_still_carry_binaries(fmu_paths, tmp_path):
    """pythonfmu prepends each instance's resources folder to sys.path; the master puts it back,
    or the FMU's embedded pythonfmu (without binaries) would serve later builds."""
    import zipfile

    from sewfmu.scenarios.cosim.master import run
    from sewfmu.scenarios.fmu_build.build import build_fmu
    from sewfmu.scenarios.format.loader import load

    before = list(sys.path)
    sc = load("punch_drive")
    sc.revolutions = 1
    run(sc, fmu_paths)
    assert sys.path == before
    path = build_fmu("MainShaft", tmp_path)
    assert "binaries/linux64/MainShaft.so" in zipfile.ZipFile(path).namelist()


@pytest.mark.slow
@pytest.mark.parametrize("fmi, binary", [(2, "binaries/linux64/MainShaft.so"),
                                         (3, "binaries/x86_64-linux/MainShaft.so")])
def test_building_after_running_in_a_fresh_process_still_carries_binaries(fmu_dir, fmu3_dir,
                                                                          tmp_path, fmi, binary):
    """The first FMU a process loads must not leave its embedded pythonfmu or pythonfmu3 (no
    binaries) in sys.modules for the builder: run punch_drive, then build, in one fresh
    process."""
    folder = fmu3_dir if fmi == 3 else fmu_dir
    code = (f"import zipfile\n"
            f"from pathlib import Path\n"
            f"from sewfmu.scenarios.format.loader import load\n"
            f"from sewfmu.scenarios.cosim.master import run\n"
            f"from sewfmu.scenarios.fmu_build.build import build_fmu\n"
            f"sc = load('punch_drive'); sc.revolutions = 1\n"
            f"run(sc, {{p.stem: p for p in Path({str(folder)!r}).glob('*.fmu')}})\n"
            f"path = build_fmu('MainShaft', Path({str(tmp_path)!r}), fmi={fmi})\n"
            f"print({binary!r} in zipfile.ZipFile(path).namelist())\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, cwd=REPO)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().splitlines()[-1] == "True"


# --- at home in any FMI tool --------------------------------------------------------------------
_STDLIB_ONLY = """
import sys
sys.path.insert(0, sys.argv[1])
module = open(sys.argv[1] + "/slavemodule.txt").read().strip()
script = __import__(module)
slave = getattr(script, sys.argv[2])(instance_name="probe", resources=sys.argv[1])
slave.enter_initialization_mode()
slave.exit_initialization_mode()
result = slave.do_step(0.0, 1e-4)             # FMI 3.0: a step result with a status
assert getattr(result, "status", not result) == 0, slave.log_queue
assert "numpy" not in sys.modules
print("ok")
"""


@pytest.mark.parametrize("name", list(FMUS))
def test_the_code_an_fmu_carries_runs_on_the_standard_library_alone(fmus, tmp_path, name):
    """python -S -I: no site-packages, no environment: only the FMU's resources folder."""
    with zipfile.ZipFile(fmus[name]) as zf:
        zf.extractall(tmp_path)
    proc = subprocess.run([sys.executable, "-S", "-I", "-c", _STDLIB_ONLY,
                           str(tmp_path / "resources"), name], capture_output=True, text=True,
                          timeout=120, cwd=tmp_path)
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr[-2000:]


def test_model_description_declares_no_execution_tool_and_a_default_experiment(fmus):
    for name, path in fmus.items():
        md = read_model_description(str(path))
        assert md.coSimulation.needsExecutionTool is False, name
        assert md.defaultExperiment is not None, name
        assert float(md.defaultExperiment.stopTime) > 0 < float(md.defaultExperiment.stepSize), name


def _starts(path):
    return {v.name: float(v.start) for v in read_model_description(str(path)).modelVariables
            if v.causality == "input"}


def test_input_start_values_are_the_default_setup(fmus):
    """A host that starts the connections at the start values starts at rest: each input's start
    value is what its default source gives at t = 0 (computed here from the models)."""
    shaft = MainShaft().state(0.0)
    for linkage, speed in (("PunchLinkage", shaft[1]), ("FeedLinkage", 303.5),
                           ("TakeupLinkage", 5000 * 2 * math.pi / 60),
                           ("CarriageDrive", 1600 * 2 * math.pi / 60)):
        assert _starts(fmus[linkage]) == pytest.approx(
            {"phi": 0.0, "omega": speed, "epsilon": 0.0}), linkage
    e = PunchLinkage().motion(*shaft)
    assert _starts(fmus["PunchContact"]) == pytest.approx(
        {"xi": e.xi, "xi_dot": e.xi_dot, "xi_ddot": e.xi_ddot}, rel=1e-12, abs=1e-12)
    # split at the fabric: the body as PunchContact, no fabric force yet; the fabric sees the
    # punch at rest at the top, accelerated down by spring 6 (the body's own y'' at t = 0)
    assert _starts(fmus["PunchBody"]) == pytest.approx(
        {"xi": e.xi, "xi_dot": e.xi_dot, "xi_ddot": e.xi_ddot, "F2": 0.0, "F2_dot": 0.0},
        rel=1e-12, abs=1e-12)
    body = PunchBody()
    at_rest = body.outputs(body.initial_state(e.xi, e.xi_dot, e.xi_ddot), e.xi, e.xi_dot,
                           e.xi_ddot)
    assert _starts(fmus["Fabric"]) == pytest.approx(
        {"y": at_rest.y, "y_dot": at_rest.y_dot, "y_ddot": at_rest.y_ddot}, rel=1e-12, abs=1e-12)
    omega = 1600 * 2 * math.pi / 60
    _, _, a, jerk = CarriageDrive().motion(0.0, omega, 0.0)
    assert _starts(fmus["CarriageModal"]) == pytest.approx(
        {"a_base": a, "a_base_dot": jerk}, rel=1e-12)


def test_each_fmu_says_what_a_host_needs_and_how_its_sources_build(fmus):
    """documentation/index.html (FMI's place for it): libpython, a Python home, every parameter;
    an FMI 3.0 FMU that ships sources describes their build (sources/buildDescription.xml,
    valid against the standard's schema)."""
    import fmpy
    from lxml import etree

    schema = etree.XMLSchema(etree.parse(str(Path(fmpy.__file__).parent / "schema" / "fmi3" /
                                             "fmi3BuildDescription.xsd")))
    for name, path in fmus.items():
        with zipfile.ZipFile(path) as archive:
            page = archive.read("documentation/index.html").decode("utf-8")
            assert "libpython" in page and "PYTHONHOME" in page and "3.10 to 3.13" in page, name
            md = read_model_description(str(path))
            for v in md.modelVariables:
                if v.causality == "parameter":
                    assert f"<code>{v.name}</code>" in page, (name, v.name)
            sources = [n for n in archive.namelist() if n.startswith("sources/")]
            if md.fmiVersion.startswith("3") and sources:
                description = etree.fromstring(archive.read("sources/buildDescription.xml"))
                assert schema.validate(description), schema.error_log
                listed = {f.get("name") for f in description.iter("SourceFile")}
                assert listed == {n[len("sources/"):] for n in sources if n.endswith(".cpp")}


def test_in_a_python_host_the_fmu_has_its_library_release_pythonfmu_state_at_exit(fmu_paths):
    """A host that is a Python process and knows nothing of sewfmu (plain fmpy): the FMU itself
    registers, once per library, the release of pythonfmu's interpreter state at Python's exit
    (components/pythonfmu_quirks.py), and the process exits cleanly."""
    probe = ("import sys\nfrom fmpy import simulate_fmu\n"
             "for _ in range(3):\n    simulate_fmu(sys.argv[1])\n"
             "quirks = [m for n, m in sys.modules.items() if n.endswith('.pythonfmu_quirks')]\n"
             "print(sorted(len(q._RELEASED_AT_EXIT) for q in quirks))\n")
    proc = subprocess.run([sys.executable, "-c", probe, str(fmu_paths["MainShaft"])],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    # fmpy extracts the FMU anew for each run: three libraries, each registered once
    assert proc.stdout.strip().splitlines()[-1] == "[3]", proc.stdout
