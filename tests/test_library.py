"""sewfmu as a Python library: one package, installed plainly, beside a user's own modules."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import sewfmu

pytestmark = [pytest.mark.slow]

REPO = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def plain_install(tmp_path_factory):
    """`pip install .` (not editable) of a copy of the repository into a folder of its own."""
    tmp = tmp_path_factory.mktemp("install")
    source = tmp / "source"               # a copy: setuptools builds in the source tree
    shutil.copytree(REPO, source, ignore=shutil.ignore_patterns(
        ".venv", ".git", "fmus", "results", "build", "*.egg-info", "__pycache__"))
    target = tmp / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                    "--target", str(target), str(source)],
                   check=True, capture_output=True, timeout=600)
    return target


def _in_a_user_folder(target: Path, work: Path, *args, code: str | None = None):
    """Run Python in `work`, a folder holding the user's own components.py and scenarios.py,
    with only the plain install on the path (no repository, no editable install)."""
    work.mkdir(exist_ok=True)
    (work / "components.py").write_text("raise ImportError('the user\\'s own components.py')\n")
    (work / "scenarios.py").write_text("WHO = 'the user\\'s own scenarios.py'\n")
    env = {**os.environ, "PYTHONPATH": str(target)}
    env.pop("SEWFMU_FMU_DIR", None)
    command = [sys.executable, "-c", code] if code else [sys.executable, *args]
    return subprocess.run(command, cwd=work, env=env, capture_output=True, text=True,
                          timeout=600)


def test_only_sewfmu_lands_at_the_top_of_site_packages(plain_install):
    tops = sorted(p.name for p in plain_install.iterdir() if p.name != "bin")
    assert [t for t in tops if not t.endswith(".dist-info")] == ["sewfmu"], tops
    # every package of the source tree is installed (a package missing from pyproject's list
    # would import here from nowhere)
    ours = sorted(str(p.parent.relative_to(REPO)).replace("/", ".")
                  for top in ("components", "scenarios") for p in (REPO / top).rglob("__init__.py"))
    installed = sorted(str(p.parent.relative_to(plain_install / "sewfmu")).replace("/", ".")
                       for top in ("components", "scenarios")
                       for p in (plain_install / "sewfmu" / top).rglob("__init__.py"))
    assert installed == ours
    assert (plain_install / "sewfmu" / "scenarios" / "references" / "regression_references" / "PunchContact"
            / "PunchContact_ref.csv").exists()
    assert (plain_install / "sewfmu" / "scenarios" / "catalogue" / "punch_drive.toml").exists()


def test_the_api_gives_the_figures_of_the_command_line_beside_a_users_own_modules(
        plain_install, tmp_path):
    """The issue's check: from a folder with its own components.py and scenarios.py,
    sewfmu.run gives what `sewfmu run --set` gives, and the time series."""
    work = tmp_path / "notebooks"
    cli = _in_a_user_folder(plain_install, work, "-m", "sewfmu", "run", "punch_drive",
                            "--set", "shaft.omega0=300", "--out", "cli")
    assert cli.returncode == 0, cli.stderr[-2000:]
    api = _in_a_user_folder(plain_install, work, code=(
        "import json, sewfmu, scenarios\n"
        "assert scenarios.WHO.startswith('the user')\n"
        "r = sewfmu.run('punch_drive', set={'shaft.omega0': 300.0})\n"
        "print(json.dumps({'summary': {k: v for k, v in r.summary.items() if k != 'provenance'},"
        " 'time': r.series['time'].tolist(), 'F2': r.series['punch.F2'].tolist(),"
        " 'unit': r.units['punch.F2'], 'file': sewfmu.__file__}))\n"))
    assert api.returncode == 0, api.stderr[-2000:]
    got = json.loads(api.stdout)
    assert got["file"].startswith(str(plain_install))
    written = json.loads((work / "cli" / "summary.json").read_text())
    for key in ("contact_onset_deg", "contact_loss_deg", "F2_peak", "F2_weld_mean", "n_contacts",
                "step", "stop_time"):
        assert got["summary"][key] == written[key], key
    table = np.genfromtxt(work / "cli" / "results.csv", delimiter=",", names=True)
    assert np.array_equal(np.array(got["time"]), table["time_s"])
    assert np.array_equal(np.array(got["F2"]), table["punchF2_N"])
    assert got["unit"] == "N"


def test_version_from_one_place(plain_install, tmp_path):
    proc = _in_a_user_folder(plain_install, tmp_path / "w", "-m", "sewfmu", "--version")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"sewfmu {sewfmu.__version__}"
    meta = next(plain_install.glob("sewfmu-*.dist-info")) / "METADATA"
    assert f"Version: {sewfmu.__version__}" in meta.read_text()
    from sewfmu.scenarios.fmu_build.build import VERSION
    assert VERSION == sewfmu.__version__
    # nowhere else: pyproject reads it from sewfmu/_version.py
    assert "version =" not in (REPO / "pyproject.toml").read_text().split("[project]")[1] \
        .split("[")[0].replace("dynamic", "")


def test_references_work_from_a_plain_install_in_any_folder(plain_install, tmp_path):
    proc = _in_a_user_folder(plain_install, tmp_path / "w", "-m", "sewfmu", "references")
    assert proc.returncode == 0, proc.stderr[-2000:]
    from sewfmu.components.registry import FMUS
    assert f"all {len(FMUS)} FMI 2.0 FMUs match their references" in proc.stdout


@pytest.mark.parametrize("name", sewfmu.catalogue())
def test_show_prints_a_scenario_that_loads_back_unchanged(name, tmp_path):
    """`sewfmu show NAME > mine.toml`: the file is the same scenario (instances, parameters,
    connections, experiment, compare, sweep), under the new file's name."""
    from sewfmu.cli import main
    from sewfmu.scenarios.format.experiment import experiment_of

    out = tmp_path / "mine.toml"
    import contextlib
    import io
    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        assert main(["show", name]) == 0
    out.write_text(buffer.getvalue(), encoding="utf-8")
    mine, theirs = sewfmu.load(out), sewfmu.load(name)
    assert mine.name == "mine"
    for attribute in ("description", "analysis", "roles", "record", "compare", "sweep"):
        assert getattr(mine, attribute) == getattr(theirs, attribute), attribute
    assert {n: (i.fmu, i.parameters) for n, i in mine.instances.items()} == \
        {n: (i.fmu, i.parameters) for n, i in theirs.instances.items()}
    assert [str(c) for c in mine.connections] == [str(c) for c in theirs.connections]
    assert experiment_of(mine) == experiment_of(theirs)


def test_show_refuses_what_it_cannot_show(tmp_path):
    with pytest.raises(sewfmu.ScenarioError, match="did you mean 'punch_drive'"):
        sewfmu.show("punch_drve")


def test_the_api_refuses_bad_arguments_in_one_line():
    with pytest.raises(sewfmu.ScenarioError, match="set: expected a dict"):
        sewfmu.load("punch_drive", set=["shaft.omega0=3"])
    with pytest.raises(sewfmu.ScenarioError, match="did you mean 'omega0'"):
        sewfmu.load("punch_drive", set={"shaft.omega": 3.0})
    with pytest.raises(sewfmu.ScenarioError, match="give out= a folder"):
        sewfmu.run("punch_drive", plot=True)
    with pytest.raises(sewfmu.ScenarioError, match="a catalogue name, a path or a Scenario"):
        sewfmu.run(42)
    with pytest.raises(sewfmu.ScenarioError, match="FMI version"):
        sewfmu.build(fmi=4)
    with pytest.raises(sewfmu.ScenarioError, match="did you mean 'MainShaft'"):
        sewfmu.build(names=["MainShat"])


def test_a_loaded_scenario_is_not_changed_by_running_it_with_set(fmu_paths):
    sc = sewfmu.load("punch_drive", set={"experiment.revolutions": 2})
    r = sewfmu.run(sc, set={"shaft.omega0": "1910 rpm"})
    assert sc.instances["shaft"].parameters["omega0"] == 100.0
    assert r.provenance["instances"]["shaft"]["parameters"]["omega0"]["value"] == \
        pytest.approx(200.0, rel=1e-3)
    frame = pytest.importorskip("pandas") and r.to_pandas()
    assert frame.index.name == "time" and list(frame["punch.F2"]) == list(r.series["punch.F2"])


def test_the_catalogue_is_listed_and_the_old_name_still_answers_for_a_release():
    """sewfmu.catalogue() is every TOML of the catalogue's folder; sewfmu.scenarios is the
    internal package again (what `import sewfmu.scenarios as s` gives), and calling it, as
    earlier releases did, gives the same list with a DeprecationWarning."""
    import importlib
    import types

    from sewfmu.scenarios.format import loader

    folder = Path(loader.__file__).resolve().parents[1] / "catalogue"
    names = sewfmu.catalogue()
    assert names == sorted(p.stem for p in folder.glob("*.toml")) and "punch_drive" in names
    package = importlib.import_module("sewfmu.scenarios")
    assert sewfmu.scenarios is package and isinstance(package, types.ModuleType)
    assert hasattr(package, "__path__")
    with pytest.warns(DeprecationWarning, match="sewfmu.catalogue"):
        assert sewfmu.scenarios() == names
