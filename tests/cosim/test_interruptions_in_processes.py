"""The interruption after the attack, as whole processes: `sewfmu run` answers every moment
after its handler is in place with 130 and one line (the fork of its guarded child too); of
SIGTERM and SIGINT back to back the first decides; a signal while a finished run's files are
written lets them finish; a user's own interrupted/results.csv is named as the reason the record
was not kept; and sewfmu.run in a user's script: SIGTERM ends the script as SIGTERM's default
does, the user's own SIGINT handler is called, and the interruption carries a sewfmu.Run of the
record so far, checked against the closed form phi = omega0·t of the punch drive's MainShaft."""
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from tests.cosim.test_stuck_fmus import (  # noqa: F401 - a fixture: the clean-up
    HANG_AT,
    SEWFMU,
    STARTED,
    WITHIN,
    _handles_sigterm,
    _nothing_left_running,
    _scenario,
    _signal_and_wait,
    _start,
    _when_stuck,
    build_fmus,
    with_kill,
)

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    return build_fmus(tmp_path_factory)


def _long_run(tmp_path: Path, *extra: str) -> subprocess.Popen:
    proc = subprocess.Popen([SEWFMU, "run", "punch_drive", "--set",
                             "experiment.revolutions=400", "--set", "experiment.accuracy=off",
                             "--out", str(tmp_path / "out"), *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    STARTED.append(proc)
    return proc


@pytest.mark.parametrize("delay_ms", [0, 2, 5, 10, 20, 40, 70, 100])
def test_every_moment_after_the_handler_is_one_line_and_130(tmp_path, delay_ms):
    proc = _long_run(tmp_path)
    deadline = time.monotonic() + 10
    while not _handles_sigterm(proc.pid) and time.monotonic() < deadline:
        pass
    time.sleep(delay_ms / 1000)
    err, took = _signal_and_wait(proc, signal.SIGINT)
    assert proc.returncode == 130, err
    assert took < WITHIN, took
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("sewfmu: interrupted (SIGINT)"), err


def test_of_sigterm_and_sigint_back_to_back_the_first_decides(tmp_path):
    proc = _long_run(tmp_path)
    time.sleep(3)                   # well into the run
    os.kill(proc.pid, signal.SIGTERM)
    os.kill(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 143, err
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("sewfmu: interrupted (SIGTERM)"), err


def test_a_signal_while_the_files_are_written_lets_them_finish(tmp_path):
    out = tmp_path / "out"
    proc = subprocess.Popen([SEWFMU, "run", "punch_drive", "--set", "experiment.revolutions=40",
                             "--set", "experiment.accuracy=off", "--out", str(out), "--plot",
                             "--report"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    STARTED.append(proc)
    deadline = time.monotonic() + 120
    while not list(out.glob(".outputs.sewfmu-*.partial")):
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.002)
    err, _ = _signal_and_wait(proc, signal.SIGINT)
    assert proc.returncode == 130, err
    assert err.splitlines()[-1] == (f"sewfmu: interrupted (SIGINT) after the run; its files "
                                    f"are written whole in {out}")
    rows = (out / "results.csv").read_text().splitlines()
    assert len(rows) > 1000 and not list(out.glob(".*.partial"))


def test_a_users_interrupted_results_csv_is_named_as_the_reason(tmp_path, fmus):
    out = tmp_path / "out"
    (out / "interrupted").mkdir(parents=True)
    (out / "interrupted" / "results.csv").write_text("mine\n")
    proc, marker = _start(tmp_path, "run", str(_scenario(tmp_path, fmus, mode=0)), "--out",
                          str(out))
    _when_stuck(proc, marker)
    err, took = _signal_and_wait(proc, signal.SIGINT)
    assert proc.returncode == 130, err
    line, = err.splitlines()
    assert line.startswith(f"sewfmu: interrupted (SIGINT) while motor was in doStep at "
                           f"t = {HANG_AT:g} s; its record was not written: "), line
    assert "results.csv" in line
    assert (out / "interrupted" / "results.csv").read_text() == "mine\n"


SCRIPT = '''
import signal, sys, time
import numpy as np
import sewfmu

{setup}
try:
    sewfmu.run("punch_drive", {{"experiment.revolutions": 400, "experiment.accuracy": "off"}})
except KeyboardInterrupt as e:
    run = e.run
    phi_ok = np.allclose(run.series["shaft.phi"], 100.0 * run.series["time"], rtol=1e-9)
    print("caught", type(run).__name__, len(run.series) > 10, phi_ok)
    sys.exit(5)
print("went on")
'''


def _script(tmp_path: Path, setup: str = "") -> subprocess.Popen:
    path = tmp_path / "script.py"
    path.write_text(SCRIPT.format(setup=textwrap.dedent(setup)))
    proc = subprocess.Popen([sys.executable, str(path)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            cwd=tmp_path)
    STARTED.append(proc)
    time.sleep(4)                  # numpy, the FMUs, well into the run
    assert proc.poll() is None, proc.communicate()
    return proc


def test_sigterm_ends_a_users_script_as_its_default_does(tmp_path):
    proc = _script(tmp_path)
    err, took = _signal_and_wait(proc, signal.SIGTERM)
    assert proc.returncode == -signal.SIGTERM, err
    assert took < WITHIN


# a user's script misses its Ctrl-C when this runs after the fast loop and the slow set's first
# files in a fresh clone (CI's order, reproduced twice); it passes alone and after the same files
# without the fast loop: not understood yet (issue 46's closing note)
CI_ORDER = "Ctrl-C lost in CI's order after the fast loop (not understood yet)"


@pytest.mark.xfail(strict=False, reason=CI_ORDER)
def test_ctrl_c_in_a_users_script_carries_the_record_as_a_run(tmp_path):
    proc = _script(tmp_path)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 5, err
    assert out.split() == ["caught", "Run", "True", "True"]


def test_a_users_own_sigint_handler_is_called(tmp_path):
    proc = _script(tmp_path, """
        def mine(signum, frame):
            print("mine", flush=True)
            sys.exit(7)
        signal.signal(signal.SIGINT, mine)
        """)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 7, err
    assert out.split() == ["mine"]
