"""Shared fixtures: the FMUs built once per test session into a temporary folder, FMI 2.0
(`fmu_paths`) and FMI 3.0 (`fmu3_paths`); `fmus` gives each in turn, for the tests
of the FMUs themselves. The terminal summary says loudly which host tests (other FMI hosts,
fmuCheck) were skipped, and how to run them."""
import atexit
import os
import shutil
import sysconfig
import tempfile
from pathlib import Path

import pytest
from hypothesis import settings

from sewfmu.scenarios.fmu_build.build import build_all, default_fmu_dir

# Property tests draw the same examples on every run ("ci", the default), so that a red CI names a
# real, reproducible failure; HYPOTHESIS_PROFILE=explore draws new ones, many more of them.
settings.register_profile("ci", max_examples=25, derandomize=True, database=None, deadline=None)
settings.register_profile("explore", max_examples=1000, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

# the FMUs the tests build are extracted into a cache of this session's (scenarios/cosim/fmu_cache.py),
# not the user's: every build is a new file, and would stay there for weeks
if "SEWFMU_CACHE_DIR" not in os.environ:
    os.environ["SEWFMU_CACHE_DIR"] = tempfile.mkdtemp(prefix="sewfmu_test_cache_")
    atexit.register(shutil.rmtree, os.environ["SEWFMU_CACHE_DIR"], True)


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fmus")
    build_all(folder)
    return folder


@pytest.fixture(scope="session")
def fmu_paths(fmu_dir):
    return {p.stem: p for p in fmu_dir.glob("*.fmu")}


@pytest.fixture(scope="session")
def fmu3_dir(fmu_dir):
    folder = default_fmu_dir(3, fmu_dir)      # where a run with experiment.fmi = 3 looks
    build_all(folder, fmi=3)
    return folder


@pytest.fixture(scope="session")
def fmu3_paths(fmu3_dir):
    return {p.stem: p for p in fmu3_dir.glob("*.fmu")}


@pytest.fixture(scope="session")
def stdlib_home(tmp_path_factory) -> Path:
    """A Python home that holds the standard library and nothing else (no site-packages): the
    FMUs must run with only that in a host that is not a Python process (fmuCheck, fmusim)."""
    home = tmp_path_factory.mktemp("stdlib_home")
    stdlib = Path(sysconfig.get_paths()["stdlib"])
    target = home / "lib" / stdlib.name
    target.mkdir(parents=True)
    for entry in stdlib.iterdir():
        if entry.name != "site-packages":
            (target / entry.name).symlink_to(entry)
    (target / "site-packages").mkdir()
    return home


@pytest.fixture(params=[2, 3], ids=["fmi2", "fmi3"])
def fmus(request):
    return request.getfixturevalue("fmu_paths" if request.param == 2 else "fmu3_paths")


@pytest.fixture(scope="session", autouse=True)
def _free_test_hosts():
    """Free every test host's FMU instance before the interpreter exits (see fmu_host.py)."""
    yield
    from tests.fmu_host import close_all
    close_all()


FMUCHECK_HOWTO = (
    "To run them: take fmuCheck.linux64 (the Modelica FMU Compliance Checker) from",
    "https://github.com/modelica-tools/FMUComplianceChecker/releases, make it executable, and run",
    "SEWFMU_FMUCHECK=/path/to/fmuCheck.linux64 .venv/bin/pytest -m interop")


def pytest_terminal_summary(terminalreporter):
    """A skipped host test is a check that did not run: say how many, why, and in red."""
    skipped = [r for r in terminalreporter.stats.get("skipped", [])
               if "interop" in r.keywords or "fmucheck" in str(r.longrepr).lower()]
    if not skipped:
        return
    reasons: dict[str, int] = {}
    for report in skipped:
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
        reason = reason.removeprefix("Skipped: ")
        reasons[reason] = reasons.get(reason, 0) + 1
    write = terminalreporter
    write.write_sep("=", f"{len(skipped)} host tests SKIPPED: they did not run", red=True,
                    bold=True)
    for reason, count in sorted(reasons.items(), key=lambda item: -item[1]):
        write.write_line(f"{count:4d} × {reason}", red=True)
    if any("fmucheck" in reason.lower() for reason in reasons):
        given = os.environ.get("SEWFMU_FMUCHECK")
        write.write_line("SEWFMU_FMUCHECK is unset." if given is None else
                         f"SEWFMU_FMUCHECK={given!r} is not an executable file.", red=True)
        for line in FMUCHECK_HOWTO:
            write.write_line(line, red=True)


@pytest.fixture(scope="session")
def design_page(tmp_path_factory, fmu_dir):
    """docs/design.md's Python blocks, in order, run as one script in a fresh process from an
    empty folder (as a user pastes them: `python try.py`), once for every test that reads their
    results: the names they define, as the script left them (pickled at its end)."""
    import pickle
    import re
    import subprocess
    import sys

    page = (Path(__file__).resolve().parent.parent / "docs" / "design.md").read_text("utf-8")
    blocks = re.findall(r"^```python\n(.*?)^```", page, re.M | re.S)
    folder = tmp_path_factory.mktemp("design_page")
    keep = ("\nimport pickle as _pickle\n_kept = {}\n"
            "for _name, _value in list(globals().items()):\n"
            "    try:\n        _pickle.dumps(_value)\n    except Exception:\n        continue\n"
            "    if not _name.startswith('_'):\n        _kept[_name] = _value\n"
            "with open('namespace.pickle', 'wb') as _f:\n    _pickle.dump(_kept, _f)\n")
    (folder / "try.py").write_text("\n".join(blocks) + keep, encoding="utf-8")
    env = {**os.environ, "SEWFMU_FMU_DIR": str(fmu_dir)}
    env.pop("PYTHONPATH", None)
    proc = subprocess.run([sys.executable, "try.py"], cwd=folder, env=env, capture_output=True,
                          text=True, timeout=2400, stdin=subprocess.DEVNULL)
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, \
        f"docs/design.md's examples fail as a script:\n{proc.stdout[-2000:]}\n{proc.stderr[-4000:]}"
    with open(folder / "namespace.pickle", "rb") as f:
        return pickle.load(f)


@pytest.fixture
def fmus_of_this_session(fmu_dir, monkeypatch):
    """Runs find this session's FMUs (no build of their own), and no SEWFMU_MAX_RUNS of the
    caller's environment moves a study's bound."""
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))
    monkeypatch.delenv("SEWFMU_MAX_RUNS", raising=False)


@pytest.fixture
def no_runs(monkeypatch):
    """Any run, sweep point, study evaluation or sample matrix fails the test: what is refused
    before the first run is refused before it."""
    from sewfmu.scenarios.design import evaluations, fit
    from sewfmu.scenarios.runs import sweep

    def ran(*_, **__):
        raise AssertionError("a run (or a point, or the sample matrix) was made before the refusal")

    monkeypatch.setattr(evaluations, "evaluate_point", ran)
    monkeypatch.setattr(fit, "run", ran)
    monkeypatch.setattr(sweep, "_execute", ran)
