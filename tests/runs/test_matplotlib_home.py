"""Nothing written outside the folders named: matplotlib, drawing sewfmu's pictures, keeps its
configuration folder and font cache in sewfmu's cache (files/matplotlib_home.py), never in the
user's home; a user's own MPLCONFIGDIR is kept, and their matplotlibrc still read. A home that
is an empty folder stays empty, in this process and in a fresh one that draws; matplotlib
alone, in the same fresh process without sewfmu, does write there (what the tests rule out)."""
import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest

from sewfmu.scenarios.files import matplotlib_home

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def empty_home(tmp_path, monkeypatch):
    """HOME an empty folder, no MPLCONFIGDIR or XDG folders, the cache in a folder beside it;
    matplotlib as if not loaded yet (this process may have loaded it for other tests)."""
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    for name in ("MPLCONFIGDIR", "MATPLOTLIBRC", "XDG_CONFIG_HOME", "XDG_CACHE_HOME"):
        monkeypatch.setenv(name, "")        # recorded: what the test sets is undone after it
        monkeypatch.delenv(name)
    monkeypatch.setenv("SEWFMU_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delitem(sys.modules, "matplotlib", raising=False)
    return home


def test_matplotlib_is_pointed_at_sewfmus_cache_before_it_loads(empty_home, tmp_path):
    folder = matplotlib_home.keep_out_of_home()
    assert folder == tmp_path / "cache" / "sewfmu-fmu-cache" / "matplotlib" and folder.is_dir()
    assert os.environ["MPLCONFIGDIR"] == str(folder)
    assert "MATPLOTLIBRC" not in os.environ and not list(empty_home.iterdir())


def test_a_users_own_setting_and_rc_are_kept(empty_home, tmp_path, monkeypatch):
    monkeypatch.setenv("MPLCONFIGDIR", str(tmp_path / "theirs"))
    assert matplotlib_home.keep_out_of_home() is None
    assert os.environ["MPLCONFIGDIR"] == str(tmp_path / "theirs")
    monkeypatch.delenv("MPLCONFIGDIR")
    rc = empty_home / ".config" / "matplotlib" / "matplotlibrc"
    rc.parent.mkdir(parents=True)
    rc.write_text("lines.linewidth: 3\n")
    matplotlib_home.keep_out_of_home()
    assert os.environ["MATPLOTLIBRC"] == str(rc)        # read, as matplotlib would have
    assert os.environ["MPLCONFIGDIR"] != str(rc.parent)


def test_with_the_cache_off_a_temporary_folder_outside_home(empty_home, monkeypatch):
    monkeypatch.setenv("SEWFMU_CACHE_DIR", "")
    folder = matplotlib_home.keep_out_of_home()
    assert folder.is_dir() and empty_home not in folder.parents
    assert folder.name.startswith(f"sewfmu-matplotlib-{os.getpid()}-")


DRAW = """
import sys
from pathlib import Path
if sys.argv[1] == "sewfmu":
    from sewfmu.scenarios.design.plots import sensitivity_bars
    sensitivity_bars(Path(sys.argv[2]), "F2_peak", "N", "morris",
                     [{"parameter": "punch.F10", "mu_star": 1.0, "mu_star_conf": 0.1,
                       "sigma": 0.2}])
else:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    plt.figure().savefig(sys.argv[2])
"""


@pytest.mark.slow
@pytest.mark.parametrize("who", ["sewfmu", "matplotlib alone"])
def test_a_fresh_process_that_draws_leaves_an_empty_home_empty(who, tmp_path):
    home = tmp_path / "home"
    home.mkdir()
    env = {k: v for k, v in os.environ.items()
           if k not in ("MPLCONFIGDIR", "MATPLOTLIBRC", "XDG_CONFIG_HOME", "XDG_CACHE_HOME")}
    env.update(HOME=str(home), SEWFMU_CACHE_DIR=str(tmp_path / "cache"))
    subprocess.run([sys.executable, "-c", DRAW, who.split()[0], str(tmp_path / "bars.png")],
                   env=env, cwd=tmp_path, check=True, timeout=120)
    assert (tmp_path / "bars.png").stat().st_size > 1000
    written = sorted(str(p.relative_to(home)) for p in home.rglob("*"))
    if who == "sewfmu":
        assert written == []
        assert list((tmp_path / "cache" / "sewfmu-fmu-cache" / "matplotlib").glob("fontlist*"))
    else:                       # what the test rules out: the check can fail
        assert ".cache/matplotlib" in written or ".config/matplotlib" in written, written


@pytest.mark.slow
def test_sewfmu_run_with_plots_leaves_an_empty_home_empty(tmp_path, fmu_dir):
    home = tmp_path / "home"
    home.mkdir()
    env = {k: v for k, v in os.environ.items()
           if k not in ("MPLCONFIGDIR", "MATPLOTLIBRC", "XDG_CONFIG_HOME", "XDG_CACHE_HOME")}
    env.update(HOME=str(home), SEWFMU_CACHE_DIR=str(tmp_path / "cache"),
               SEWFMU_FMU_DIR=str(fmu_dir))
    sewfmu_command = str(Path(sys.executable).with_name("sewfmu"))
    done = subprocess.run([sewfmu_command, "run", "punch_drive", "--set",
                           "experiment.revolutions=2", "--plot", "--out", str(tmp_path / "D")],
                          env=env, cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "D" / "punch_drive.png").exists()
    assert sorted(home.rglob("*")) == []


@pytest.mark.slow
def test_only_the_one_module_loads_matplotlib_itself():
    """Every picture goes through matplotlib_home.pyplot(): a module that imported matplotlib
    or its pyplot itself could load it before MPLCONFIGDIR is set (a submodule, such as
    matplotlib.patches, is imported where pyplot() was called first)."""
    loading = []
    for folder in ("scenarios", "sewfmu"):
        for path in (REPO / folder).rglob("*.py"):
            if path.name == "matplotlib_home.py":
                continue
            for node in ast.walk(ast.parse(path.read_text())):
                names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                    [node.module] if isinstance(node, ast.ImportFrom) and node.module else []
                if any(n in ("matplotlib", "matplotlib.pyplot") for n in names):
                    loading.append(f"{path.relative_to(REPO)}:{node.lineno}")
    assert not loading, loading
