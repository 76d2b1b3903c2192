"""experiment.fmus = "native": the setting read and refused as every experiment key is (the
scenario file, --set, the API's set=, a Scenario built in Python), a run that takes its FMUs from
fmus/native/ (its provenance says so), the native FMUs' up-to-date check (their C sources and the
Python FMU they mirror), and a native FMU's Error status told as a Python FMU's Discard is.

Fast: the run's plumbing is tried on a stand-in, a Python FMU copied into the native folder with
the native version stamped in (no C compiler needed); the native FMUs themselves are
tests/cosim/test_native_runs.py's."""
import re
import zipfile
from pathlib import Path

import pytest

import sewfmu
from sewfmu.app.values import changed_values, command_line, inputs_of, scenario_toml
from sewfmu.cli import main
from sewfmu.scenarios.cosim.fmi_calls import CosimError, Status
from sewfmu.scenarios.cosim.master import Master
from sewfmu.scenarios.fmu_build import native_current, up_to_date
from sewfmu.scenarios.fmu_build.build import build_fmu
from sewfmu.scenarios.fmu_build.native_current import (
    build_of,
    native_fmu_dir,
    native_sources_hash,
    native_version,
)
from sewfmu.scenarios.fmu_build.sources import default_fmu_dir, fmu_version
from sewfmu.scenarios.format.experiment import EXPERIMENT_KEYS, experiment_of
from sewfmu.scenarios.format.parse import from_dict
from sewfmu.scenarios.format.scenario import Instance, Scenario
from sewfmu.scenarios.format.values import ScenarioError
from tests.fake_fmu import FakeInstance, Integrator, fake_scenario

ACCEPTED = "'python' or 'native'"


def stand_in(python_fmu: Path, folder: Path, version: str | None = None) -> Path:
    """A copy of a Python FMU in `folder` whose modelDescription carries `version` (default: the
    version a native FMU built now carries): what the run's plumbing sees of a native FMU."""
    folder.mkdir(parents=True, exist_ok=True)
    target = folder / python_fmu.name
    version = native_version() if version is None else version
    with zipfile.ZipFile(python_fmu) as source, zipfile.ZipFile(target, "w") as copy:
        for item in source.infolist():
            data = source.read(item)
            if item.filename == "modelDescription.xml":
                data = re.sub(rb'(<fmiModelDescription[^>]*?\sversion=")[^"]*"',
                              lambda m: m.group(1) + version.encode() + b'"', data, count=1)
            copy.writestr(item, data)
    return target


@pytest.fixture(scope="module")
def shaft_python(tmp_path_factory):
    base = tmp_path_factory.mktemp("fmus")
    return base, build_fmu("MainShaft", base)


@pytest.fixture
def shaft_fmus(shaft_python, monkeypatch):
    """A folder of FMUs as a run looks for them: the Python MainShaft in it, and a stand-in of
    the native one in its native/ folder, current for the C sources as they are now (held so
    for the test, whatever another session edits in native/ meanwhile)."""
    base, python = shaft_python
    now = native_version()
    monkeypatch.setattr(up_to_date, "native_version", lambda: now)
    return base, python, stand_in(python, native_fmu_dir(2, base), now)


def shaft_only() -> Scenario:
    return Scenario(name="spin", source="spin (Python)", description="", analysis=None,
                    instances={"shaft": Instance("shaft", "MainShaft")}, connections=[],
                    record=None, step=1e-3, master="jacobi", stop_time=0.01, revolutions=None,
                    shaft=None, compare=None, accuracy="off")


# --- the setting ---------------------------------------------------------------------------------
def test_python_is_the_default():
    assert sewfmu.load("punch_drive").fmus == "python"


@pytest.mark.parametrize("value", ["python", "native"])
def test_the_scenario_file_the_command_line_and_the_api_take_it(value):
    data = {"instances": {"shaft": {"fmu": "MainShaft"}},
            "experiment": {"stop_time": 0.01, "step": 1e-3, "fmus": value}}
    assert from_dict(data, "spin", "spin.toml").fmus == value
    assert sewfmu.load("punch_drive", set={"experiment.fmus": value}).fmus == value
    sc = sewfmu.load("punch_drive")
    sc.set_value("experiment.fmus", value)             # --set's own path
    assert sc.fmus == value


@pytest.mark.parametrize("value", ["c", "Native", "", 1, True, 2.0, "python "])
def test_any_other_value_is_refused_in_one_line_naming_what_is_accepted(value):
    data = {"instances": {"shaft": {"fmu": "MainShaft"}},
            "experiment": {"stop_time": 0.01, "step": 1e-3, "fmus": value}}
    with pytest.raises(ScenarioError) as err:
        from_dict(data, "spin", "spin.toml")
    text = str(err.value)
    assert text.startswith("spin.toml: experiment.fmus: ") and ACCEPTED in text, text
    with pytest.raises(ScenarioError) as err:
        sewfmu.load("punch_drive", set={"experiment.fmus": value})
    assert str(err.value).startswith("set experiment.fmus: ") and ACCEPTED in str(err.value)
    assert "\n" not in str(err.value)


def test_a_scenario_built_in_python_is_checked_too():
    sc = shaft_only()
    sc.fmus = "cython"
    with pytest.raises(ScenarioError, match=r"Scenario\.fmus: .*'python' or 'native', got "):
        sewfmu.load(sc)
    sc.fmus = "native"
    assert sewfmu.load(sc).fmus == "native"


@pytest.mark.parametrize("value", ["c", "1", "true"])
def test_the_command_line_refuses_it_in_one_line(capsys, tmp_path, value):
    assert main(["run", "punch_drive", "--set", f"experiment.fmus={value}",
                 "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert "--set experiment.fmus" in err and ACCEPTED in err, err
    assert not (tmp_path / "out").exists()


def test_the_key_is_listed_with_the_others():

    assert "fmus" in EXPERIMENT_KEYS
    assert experiment_of(sewfmu.load("punch_drive", set={"experiment.fmus": "native"})
                         )["fmus"] == "native"


SPIN = """description = "the shaft alone"
[instances.shaft]
fmu = "MainShaft"
[experiment]
stop_time = 0.01
step = 0.001
"""


def test_the_page_offers_it_and_reads_it_as_a_run_does(shaft_fmus, tmp_path, monkeypatch):

    monkeypatch.setenv("SEWFMU_FMU_DIR", str(shaft_fmus[0]))        # the stand-in's folder
    spin = tmp_path / "spin.toml"
    spin.write_text(SPIN)
    rows = {row["name"]: row for row in inputs_of(str(spin))}
    assert rows["experiment.fmus"]["value"] == "python"
    assert rows["experiment.fmus"]["range"] == "python, native"
    assert "experiment.fmus" not in {row["name"] for row in inputs_of("takeup_tolerance")}
    defaults = {name: row["value"] for name, row in rows.items()}
    changed = changed_values(str(spin), {"experiment.fmus": "native"}, defaults)
    assert changed == {"experiment.fmus": "native"}
    assert command_line("spin", changed) == "sewfmu run spin --set experiment.fmus=native"
    assert 'fmus = "native"' in scenario_toml(SPIN, changed)
    with pytest.raises(sewfmu.Error, match=r"experiment\.fmus: .*'python' or 'native'"):
        changed_values(str(spin), {"experiment.fmus": "rust"}, defaults)


# --- where a run takes its FMUs from -------------------------------------------------------------
def test_the_native_folder_is_the_builders():
    native = pytest.importorskip("sewfmu.scenarios.fmu_build.native")
    for fmi in (2, 3):
        assert native.default_native_dir(fmi) == native_fmu_dir(fmi)
        assert native.default_native_dir(fmi, Path("/x/fmus")) == \
            native_fmu_dir(fmi, Path("/x/fmus"))


def test_a_native_run_takes_the_native_folders_fmus_and_its_provenance_says_so(shaft_fmus):
    base, python, native = shaft_fmus
    ran = {}
    for kind, expected in (("native", native), ("python", python)):
        run = sewfmu.run(shaft_only(), set={"experiment.fmus": kind}, fmu_dir=base)
        made = run.provenance
        assert made["experiment"]["fmus"] == kind
        assert made["fmu_files"] == {"MainShaft": str(expected.resolve())}
        assert made["fmus"]["MainShaft"] == fmu_version(expected)
        assert made["fmu_builds"] == {"MainShaft": "python"}       # a stand-in: see stand_in
        ran[kind] = run.series
    # the stand-in is the Python FMU: the same numbers (the native FMUs' own: test_native_runs)
    assert (ran["native"]["shaft.phi"] == ran["python"]["shaft.phi"]).all()


def test_a_python_fmu_is_told_from_a_native_one(shaft_fmus, tmp_path):
    _, python, _ = shaft_fmus
    assert build_of(python) == "python"
    compiled = tmp_path / "C.fmu"
    with zipfile.ZipFile(compiled, "w") as archive:
        archive.writestr("modelDescription.xml", "<fmiModelDescription/>")
        archive.writestr("binaries/linux64/C.so", b"\x7fELF")
        archive.writestr("sources/C.c", "int x;")
    assert build_of(compiled) == "native"
    assert build_of(tmp_path / "missing.fmu") == "unknown"


# --- up to date ----------------------------------------------------------------------------------
def test_the_native_version_follows_the_c_sources(tmp_path):
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "shaft.c").write_text("double f(double x) { return x; }\n")
    (tmp_path / "runtime.h").write_text("#define N 1\n")
    before = native_sources_hash(tmp_path)
    (tmp_path / "notes.txt").write_text("not a source")
    assert native_sources_hash(tmp_path) == before
    (tmp_path / "models" / "shaft.c").write_text("double f(double x) { return -x; }\n")
    changed = native_sources_hash(tmp_path)
    assert changed != before
    (tmp_path / "models" / "shaft.c").rename(tmp_path / "models" / "main_shaft.c")
    assert native_sources_hash(tmp_path) not in (before, changed)      # a name is code too


def test_the_native_version_follows_the_python_fmu_it_mirrors(monkeypatch):
    now = native_version()
    assert now.startswith(up_to_date.current_version() + ".native.")
    monkeypatch.setattr(native_current, "current_version", lambda: "0.2.0+otherpython")
    assert native_version() != now


def test_a_stale_or_missing_native_fmu_is_built_and_a_current_one_is_not(shaft_fmus, tmp_path,
                                                                         monkeypatch):
    _, python, _ = shaft_fmus
    built = []

    def builder(name, dest, fmi, python_dir, left_out=None):
        built.append((name, Path(dest), fmi))
        assert python_dir == default_fmu_dir(fmi, tmp_path)      # made from these Python FMUs
        return stand_in(python, Path(dest))

    monkeypatch.setattr(up_to_date, "_build_native", builder)
    # the C sources as they are now, whatever another session edits meanwhile
    monkeypatch.setattr(up_to_date, "native_version", lambda now=native_version(): now)
    folder = native_fmu_dir(2, tmp_path)
    paths = up_to_date.fmus_for_names(["MainShaft"], tmp_path, kind="native")
    assert built == [("MainShaft", folder, 2)] and paths == {"MainShaft": folder / "MainShaft.fmu"}
    up_to_date.fmus_for_names(["MainShaft"], tmp_path, kind="native")
    assert len(built) == 1                                     # current: not built again
    stand_in(python, folder, version=up_to_date.native_version() + "0")
    up_to_date.fmus_for_names(["MainShaft"], tmp_path, kind="native")
    assert len(built) == 2                                     # other C sources: built again
    stand_in(python, folder, version=up_to_date.current_version())     # the Python FMU's own
    up_to_date.fmus_for_names(["MainShaft"], tmp_path, kind="native")
    assert len(built) == 3
    up_to_date.fmus_for_names(["MainShaft"], tmp_path, fmi=3, kind="native")
    assert built[-1] == ("MainShaft", native_fmu_dir(3, tmp_path), 3)
    # the Python FMUs' folder is another: a native run never takes one of them
    assert python.parent not in (native_fmu_dir(2, tmp_path), native_fmu_dir(3, tmp_path))


# --- an Error status, told as a Discard is -------------------------------------------------------
class RefusingInput(FakeInstance):
    """What a native FMU does with an input outside its declared range: fmi2Error at the set,
    the reason through the logger (a Python FMU takes it and discards the step instead)."""

    def _set_reals(self):
        for vr, value in zip(self.in_vr, self.in_buf):
            if self.by_vr[vr] == "u" and value > 1.45:
                self.log.add(self.name, Status.ERROR,
                             f"input u = {value:g} is outside its range [-1.45, 1.45]")
                return Status.ERROR
        return super()._set_reals()


@pytest.mark.parametrize("master", ["jacobi", "gauss-seidel", "iterative", "adaptive"])
def test_an_input_refused_with_error_is_one_line_naming_instance_time_and_reason(master):
    models = {"a": Integrator(gain=1.0, x0=1.0), "b": Integrator(gain=1.0)}
    made = {}

    def make(declaration, log):
        cls = RefusingInput if declaration.name == "b" else FakeInstance
        made[declaration.name] = cls(declaration.name, models[declaration.name], log)
        return made[declaration.name]

    # a.x = 1 + t reaches b's range's end at t = 0.45: the step that sets it is refused
    sc = fake_scenario(models, ["a.x -> b.u", "a.x_dot -> b.u_dot"], 1.0, 0.1, master,
                       parameters={"a": {"u": 1.0, "u_dot": 0.0}})
    with pytest.raises(CosimError) as err:
        Master(sc, {}, make_instance=make).run()
    text = str(err.value)
    found = re.fullmatch(r"b failed during step from t = ([\d.e-]+) to ([\d.e-]+) s: input u = "
                         r"1\.(?:4[5-9]|5)\d* is outside its range \[-1\.45, 1\.45\]", text)
    assert found, text
    # refused where the value is set: at the end of the step that reaches it (Jacobi), or at
    # the start of the next (Gauss-Seidel sets b's inputs before b steps)
    start, end = map(float, found.groups())
    assert 0.3 < start <= 0.5 and start < end <= start + 0.1 + 1e-12, text
    assert made["a"].calls[-1] == "free" and made["b"].calls[-1] == "free"


@pytest.mark.parametrize("failure, told", [
    (RuntimeError("compiling MainShaft.so for linux failed:\ngcc -std=c99 shaft.c\n"
                  "shaft.c:3:1: error: unknown type name 'ParamInfo'\n  3 | x"),
     "compiling MainShaft.so for linux failed: shaft.c:3:1: error: unknown type name "
     "'ParamInfo'"),
    (FileNotFoundError("native source native/models/shaft.c is missing"),
     "native source native/models/shaft.c is missing")])
def test_a_native_fmu_that_cannot_be_built_is_one_line(monkeypatch, tmp_path, failure, told):
    native = pytest.importorskip("sewfmu.scenarios.fmu_build.native")

    raised = [failure]

    def fails(*args, **kwargs):
        raise raised[0]

    monkeypatch.setattr(native, "build_native_fmu", fails)
    with pytest.raises(ScenarioError) as err:
        up_to_date.fmus_for_names(["MainShaft"], tmp_path, kind="native")
    text = str(err.value)
    assert "\n" not in text and f"the native MainShaft cannot be built ({told})" in text, text
    raised[0] = native.NoCompiler("sewfmu build --native: no compiler for linux: needs gcc")
    with pytest.raises(native.NoCompiler) as err:      # its own line: what to install
        up_to_date.fmus_for_names(["MainShaft"], tmp_path, kind="native")
    assert str(err.value) == str(raised[0])
