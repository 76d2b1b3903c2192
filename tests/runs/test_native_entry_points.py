"""Every way a scenario is run takes the native FMUs with experiment.fmus = "native": a run, a
sweep (its worker processes too), compare, a design study, export-ssp and export-fmu (the
page's runs are sewfmu.run's: tests/cosim/test_native_fmus.py offers it the setting). The FMU
folder holds only native FMUs (stand-ins: Python FMUs copied into fmus/native/ with the native
version stamped in, tests/cosim/test_native_fmus.py), so a command that took the Python FMUs
would build them beside: none may be there afterwards."""
import pickle
import zipfile

import pytest

import sewfmu
from sewfmu.cli import main
from sewfmu.scenarios.fmu_build import up_to_date
from sewfmu.scenarios.fmu_build.build import build_fmu
from sewfmu.scenarios.fmu_build.native_current import native_fmu_dir, native_version
from sewfmu.scenarios.runs.sweep import settings_of
from tests.cosim.test_native_fmus import stand_in

PUNCH = ("MainShaft", "PunchLinkage", "PunchContact")
NATIVE = {"experiment.fmus": "native", "experiment.revolutions": 1, "experiment.accuracy": "off"}


@pytest.fixture(scope="module")
def python_fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("python_fmus")
    return [build_fmu(name, folder) for name in PUNCH]


@pytest.fixture
def fmu_dir_is(python_fmus, tmp_path, monkeypatch):
    """A folder of FMUs with the punch drive's native stand-ins only (current for the C sources
    as they are now, and held so in this process), as SEWFMU_FMU_DIR."""
    base = tmp_path / "native_only"
    now = native_version()
    monkeypatch.setattr(up_to_date, "native_version", lambda: now)
    for python in python_fmus:
        stand_in(python, native_fmu_dir(2, base), now)
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(base))
    yield base
    assert sorted(p.relative_to(base).as_posix() for p in base.rglob("*.fmu")) == sorted(
        f"native/{name}.fmu" for name in PUNCH), "a command built FMUs of its own"


def test_run_and_its_summary(fmu_dir_is, tmp_path):
    run = sewfmu.run("punch_drive", set=NATIVE, out=tmp_path / "out")
    folder = native_fmu_dir(2, fmu_dir_is)
    assert run.provenance["fmu_files"] == {n: str((folder / f"{n}.fmu").resolve()) for n in PUNCH}
    assert run.provenance["experiment"]["fmus"] == "native"
    assert '"fmus": "native"' in (tmp_path / "out" / "summary.json").read_text()


def test_sweep_in_worker_processes(fmu_dir_is):
    # (the workers fork from a server that keeps the SEWFMU_FMU_DIR it started with: in a session
    # whose earlier sweep started it, they find their native FMUs there)
    sweep = sewfmu.sweep("punch_drive", grid={"shaft.omega0": [200.0, 250.0]}, set=NATIVE,
                         workers=2)
    assert [r["status"] for r in sweep.rows] == ["ok", "ok"]


@pytest.mark.slow
def test_compare(fmu_dir_is):
    rows = sewfmu.compare("punch_drive", set=NATIVE)
    assert rows["wall_time_s"]["cosim"] > 0


def test_optimize(fmu_dir_is):
    found = sewfmu.optimize("punch_drive", {"shaft.omega0": (200.0, 300.0)},
                            minimize="F2_peak", set=NATIVE, max_evaluations=3, workers=1)
    assert len(found.evaluations) >= 1


def test_export_ssp_carries_the_native_fmus(fmu_dir_is, tmp_path):
    ssp = tmp_path / "p.ssp"
    assert main(["export-ssp", "punch_drive", "-o", str(ssp), "--set", "experiment.fmus=native"]) \
        == 0
    folder = native_fmu_dir(2, fmu_dir_is)
    with zipfile.ZipFile(ssp) as archive:
        for name in PUNCH:
            assert archive.read(f"resources/{name}.fmu") == (folder / f"{name}.fmu").read_bytes()


def test_export_fmu_refuses_a_native_container_with_python_inside(fmu_dir_is, tmp_path, capsys):
    """The stand-ins carry Python: a container of native FMUs must need none, so it is refused
    in one line, before anything is written."""
    out = tmp_path / "p.fmu"
    assert main(["export-fmu", "punch_drive", "-o", str(out), "--set",
                 "experiment.fmus=native"]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "needs no Python" in err and "carries Python" in err
    assert not out.exists()


def test_a_sweep_point_on_native_fmus_is_not_one_on_python_fmus(fmu_dir_is, python_fmus):
    """A sweep resumed in the same folder with the other build runs its points again: the
    build is in a point's identity (the experiment's keys and the FMUs' versions), and the
    scenario the workers receive carries it."""
    native = sewfmu.load("punch_drive", set=NATIVE)
    python = sewfmu.load("punch_drive", set={**NATIVE, "experiment.fmus": "python"})
    assert pickle.loads(pickle.dumps(native)).fmus == "native"
    folder = native_fmu_dir(2, fmu_dir_is)
    native_paths = {p.stem: folder / p.name for p in python_fmus}
    python_paths = {p.stem: p for p in python_fmus}
    assert settings_of(native, native_paths) != settings_of(python, python_paths)
    assert settings_of(native, python_paths) != settings_of(python, python_paths)
