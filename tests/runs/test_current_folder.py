"""No process sewfmu starts imports from the folder the user is in (sewfmu/processes.py): a
numpy.py, a folder named sewfmu or multiprocessing planted in the current folder is never
imported by a spawned child, a `python -m` child, nor a sweep's workers, and the sweep works.
Before, `sewfmu sweep --workers 2` run from such a folder failed every point with
"'numpy' is not a package" and ran the planted code. The page's jobs:
tests/app/test_app_current_folder.py."""
import multiprocessing
import os
import subprocess
import sys
from pathlib import Path

import pytest

from sewfmu.processes import SAFE_PATH, python_command, safe_path

SEWFMU = Path(sys.executable).with_name("sewfmu")       # the console script, as a user runs it


def plant(folder: Path, marker: Path, names=("numpy", "sewfmu", "multiprocessing")) -> Path:
    """Modules in `folder` that, imported, append their name to `marker`."""
    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        code = f"open({str(marker)!r}, 'a').write({name!r} + '\\n')\n"
        if name == "numpy":
            (folder / "numpy.py").write_text(code)
        else:
            (folder / name).mkdir(exist_ok=True)
            (folder / name / "__init__.py").write_text(code)
    return folder


def test_a_spawned_child_imports_nothing_from_the_current_folder(tmp_path, monkeypatch):
    """multiprocessing's spawn starts `python -c "from multiprocessing.spawn import ..."`: the
    planted multiprocessing/ would be that import, were the current folder on its path."""
    marker = tmp_path / "imported.txt"
    monkeypatch.chdir(plant(tmp_path / "here", marker))
    context = multiprocessing.get_context("spawn")
    child = context.Process(target=os.getpid)
    with safe_path():
        child.start()
    child.join(60)
    assert child.exitcode == 0 and not marker.exists(), marker.read_text()


def test_without_it_the_planted_module_is_what_a_child_imports(tmp_path):
    """The check above can fail: a plain `python -c` in the planted folder runs the plant (as
    `-m` does), the same with python_command's -P does not."""
    marker = tmp_path / "imported.txt"
    here = plant(tmp_path / "here", marker, names=("planted",))
    done = subprocess.run([sys.executable, "-c", "import planted"], cwd=here, capture_output=True,
                          env={k: v for k, v in os.environ.items() if k != SAFE_PATH})
    assert done.returncode == 0 and marker.read_text() == "planted\n"
    marker.unlink()
    done = subprocess.run(python_command("-c", "import planted"), cwd=here, capture_output=True,
                          text=True)
    assert done.returncode == 1 and "No module named 'planted'" in done.stderr
    assert not marker.exists()


def test_the_environment_is_as_it_was_after(monkeypatch):
    monkeypatch.delenv(SAFE_PATH, raising=False)
    with safe_path():
        assert os.environ[SAFE_PATH] == "1"
    assert SAFE_PATH not in os.environ
    monkeypatch.setenv(SAFE_PATH, "yes")
    with safe_path():
        pass
    assert os.environ[SAFE_PATH] == "yes"


@pytest.mark.slow          # a sweep of two points on two workers: about 4 s
@pytest.mark.skipif(not SEWFMU.exists(), reason="no console script sewfmu beside this Python")
def test_a_sweep_in_a_folder_with_a_planted_numpy_and_sewfmu_works(tmp_path):
    marker = tmp_path / "imported.txt"
    here = plant(tmp_path / "here", marker)
    done = subprocess.run([str(SEWFMU), "sweep", "punch_drive", "--grid",
                           "experiment.revolutions=1,2", "--workers", "2", "--quiet",
                           "--out", str(tmp_path / "out")], cwd=here, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert "2 points, 0 failed" in done.stdout, done.stdout
    assert not marker.exists(), marker.read_text()
