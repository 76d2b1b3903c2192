"""The way out that a stuck FMU's own signal handling cannot block, and the lines a user's
script gets: a C FMU that sets SIGINT and SIGTERM to SIG_IGN in doStep and then spins (the
`sewfmu` process the shell waits for forwards the signal, sees it never reached the child's
Python, and SIGKILLs the child after guardian.IGNORED_GRACE with one line); SIGTERM to a user's
script whose Python FMU sleeps in doStep (the watchdog thread ends it: one line, status 143, no
guardian line after); step_timeout in a user's script (the watchdog's line only: the guardian
does not claim the interpreter lock is held, and the next Ctrl-C ends it through the watchdog,
not by SIGKILL). The FMUs are tests/cosim/test_stuck_fmus.py's."""
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from sewfmu.scenarios.cosim.guardian import WHY_IGNORED
from tests import foreign_fmus
from tests.cosim.test_stuck_fmus import (  # noqa: F401 - a fixture: the clean-up
    HANG_AT,
    SPINNING,
    SPINNING_STEP,
    STARTED,
    WITHIN,
    _nothing_left_running,
    _scenario,
    _signal_and_wait,
    _start,
    _when_stuck,
    build_fmus,
    with_kill,
)

pytestmark = pytest.mark.slow

# SPINNING, but the FMU first ignores both signals (as a C library that "protects" its loop)
IGNORING = SPINNING.replace("for (;;);", "{ signal(SIGINT, SIG_IGN); signal(SIGTERM, SIG_IGN); "
                            "for (;;); }")


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    found = build_fmus(tmp_path_factory)
    if shutil.which("gcc"):
        folder = tmp_path_factory.mktemp("ignoring")
        saved = foreign_fmus.GAIN_C
        assert SPINNING_STEP in saved
        foreign_fmus.GAIN_C = "#include <signal.h>\n" + saved.replace(SPINNING_STEP, IGNORING)
        try:
            found["spin"] = foreign_fmus.build_gain(folder)     # _scenario's spin=True
        finally:
            foreign_fmus.GAIN_C = saved
    else:
        found["spin"] = None
    return found


def _spinning(pid: int) -> bool:
    """Whether some process of the session spins (the C loop has begun: no marker file)."""
    from tests.processes import processes_in  # the test helper: only where a C FMU runs

    for p in processes_in("session", pid):
        try:
            fields = Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if fields[0] == "R" and int(fields[11]) > 20:         # utime, clock ticks
            return True
    return False


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_ends_a_run_whose_c_fmu_ignores_it(tmp_path, fmus, sig):
    if fmus["spin"] is None:
        pytest.skip("no gcc to compile the C FMU")
    out = tmp_path / "out"
    proc, _ = _start(tmp_path, "run", str(_scenario(tmp_path, fmus, spin=True)), "--out",
                     str(out))
    deadline = time.monotonic() + 120
    while not _spinning(proc.pid):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "the FMU never started spinning"
        time.sleep(0.1)
    time.sleep(0.3)
    err, took = _signal_and_wait(proc, sig)
    name = signal.Signals(sig).name
    assert proc.returncode == 128 + sig, err
    assert took < WITHIN, took
    assert err.splitlines() == [f"sewfmu: interrupted ({name}) while motor was in doStep at "
                                f"t = {HANG_AT:g} s; {WHY_IGNORED}"]


def _script(tmp_path: Path, fmus: dict, *sets: str) -> tuple[subprocess.Popen, Path, Path]:
    """`python -c "import sewfmu; sewfmu.run(...)"` with the Python FMU asleep in doStep; its
    stderr goes to a file (read while it runs)."""
    scenario = _scenario(tmp_path, fmus, mode=0)
    marker = tmp_path / "hanging"
    marker.mkdir()
    errfile = tmp_path / "stderr.txt"
    code = f"import sewfmu; sewfmu.run({str(scenario)!r}, {dict(sets)!r})"
    with open(errfile, "w") as err:
        proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.DEVNULL,
                                stderr=err, env={**os.environ, "HANG_MARKER": str(marker)},
                                start_new_session=True)
    STARTED.append(proc)
    return proc, marker, errfile


def test_sigterm_ends_a_users_script_stuck_in_a_sleeping_fmu_with_one_line(tmp_path, fmus):
    proc, marker, errfile = _script(tmp_path, fmus)
    _when_stuck(proc, marker)
    sent = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(timeout=30)
    finally:
        with_kill(proc)
    took = time.monotonic() - sent
    assert proc.returncode == 128 + signal.SIGTERM
    assert took < WITHIN, took
    lines = errfile.read_text().splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith(f"sewfmu: interrupted (SIGTERM) while motor was in doStep at "
                               f"t = {HANG_AT:g} s"), lines


def test_step_timeout_in_a_users_script_gets_the_watchdogs_line_only(tmp_path, fmus):
    proc, marker, errfile = _script(tmp_path, fmus, ("experiment.step_timeout", 0.3))
    _when_stuck(proc, marker, settle=0.0)
    time.sleep(0.3 + 2.5)           # the guardian's own limit (step_timeout + 1.1 s) is past
    lines = errfile.read_text().splitlines()
    assert len(lines) == 1, lines
    assert "experiment.step_timeout = 0.3 s in doStep" in lines[0], lines
    assert "interpreter lock" not in lines[0], lines
    assert proc.poll() is None                  # a user's process: a Ctrl-C ends it
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout=30)
    finally:
        with_kill(proc)
    lines = errfile.read_text().splitlines()
    assert proc.returncode == 128 + signal.SIGINT, lines      # the watchdog's end, not SIGKILL
    assert not any("interpreter lock" in line for line in lines), lines
