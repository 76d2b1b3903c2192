"""An FMU whose code holds Python's interpreter lock for ever (a pythonfmu doStep in
`sum(itertools.repeat(0))`): no thread of the run's process can run, so the guardian process
beside it (scenarios/cosim/guardian.py) ends it. Also: every FMI call under step_timeout (a C FMU
hanging in exitInitializationMode, a Python FMU asleep there), an FMU that ignores SIGINT from its
instantiation on, and a sweep whose main process is killed with -9 while its workers hold the
lock. The FMUs are tests/cosim/test_stuck_fmus.py's."""
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests import foreign_fmus
from tests.cosim.test_stuck_fmus import (  # noqa: F401 - a fixture: the clean-up
    HANG_AT,
    SEWFMU,
    STARTED,
    WITHIN,
    _nothing_left_running,
    _record,
    _scenario,
    _signal_and_wait,
    _start,
    _when_stuck,
    build_fmus,
    with_kill,
)
from tests.processes import processes_in

pytestmark = pytest.mark.slow

@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    return build_fmus(tmp_path_factory)


LOST = ("its code holds Python's interpreter lock, so nothing in that process can answer: "
        "sewfmu killed it (SIGKILL) and the record so far is lost")


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_ends_a_run_whose_fmu_holds_the_interpreter_lock(tmp_path, fmus, sig):
    out = tmp_path / "out"
    proc, marker = _start(tmp_path, "run", str(_scenario(tmp_path, fmus, mode=2)), "--out",
                          str(out))
    _when_stuck(proc, marker)
    err, took = _signal_and_wait(proc, sig)
    name = signal.Signals(sig).name
    assert proc.returncode == 128 + sig, err
    assert took < WITHIN, took
    assert err.splitlines() == [f"sewfmu: interrupted ({name}) while motor was in doStep at "
                                f"t = {HANG_AT:g} s; {LOST}"]
    assert not (out / "interrupted").exists()


def test_step_timeout_ends_a_run_whose_fmu_holds_the_interpreter_lock(tmp_path, fmus):
    proc, _ = _start(tmp_path, "run", str(_scenario(tmp_path, fmus, mode=2)), "--out",
                     str(tmp_path / "out"), "--set", "experiment.step_timeout=0.3")
    try:
        _, err = proc.communicate(timeout=60)
    finally:
        with_kill(proc)
    assert proc.returncode == 1, err
    assert err.splitlines() == [f"sewfmu: error: motor took longer than "
                                f"experiment.step_timeout = 0.3 s in doStep at t = {HANG_AT:g} s; "
                                f"{LOST}"]


def test_kill_9_of_a_sweep_ends_every_worker_holding_the_lock(tmp_path, fmus):
    """kill -9 of the sweep's process: its workers, the forkserver and the resource tracker all
    end within 2 s, though no thread of a worker can run."""
    proc, marker = _start(tmp_path, "sweep", str(_scenario(tmp_path, fmus, mode=2)), "--grid",
                          "motor.hang_at=0.01,0.02,0.03", "--workers", "2", "--quiet",
                          "--out", str(tmp_path / "sweep"))
    _when_stuck(proc, marker, count=2)
    assert len(processes_in("session", proc.pid)) >= 5   # waiter, sweep, 2 workers, server
    sweep = [p for p in processes_in("session", proc.pid) if _parent(p) == proc.pid]
    os.kill(sweep[0], signal.SIGKILL)                    # the sweep's own process
    deadline = time.monotonic() + WITHIN
    while processes_in("session", proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert processes_in("session", proc.pid) == []
    proc.communicate(timeout=10)
    assert proc.returncode == -signal.SIGKILL      # the `sewfmu` process ends as its child did


def _parent(pid: int) -> int:
    try:
        return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])
    except OSError:
        return 0


def test_ctrl_c_ends_a_run_whose_fmu_ignores_sigint(tmp_path, fmus):
    """The FMU sets SIGINT to ignored when it is instantiated: sewfmu's handlers come back."""
    out = tmp_path / "out"
    path = _scenario(tmp_path, fmus, mode=0)
    marker = tmp_path / "hanging"
    marker.mkdir()
    proc = subprocess.Popen([SEWFMU, "run", str(path), "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True,
                            env={**os.environ, "HANG_MARKER": str(marker),
                                 "HANG_IGNORE_SIGINT": "1"})
    STARTED.append(proc)
    _when_stuck(proc, marker)
    err, took = _signal_and_wait(proc, signal.SIGINT)
    assert proc.returncode == 130, err
    assert took < WITHIN, took
    kept = out / "interrupted" / "results.csv"
    assert err.splitlines() == [
        f"sewfmu: interrupted (SIGINT) while motor was in doStep at t = {HANG_AT:g} s; the "
        f"record up to t = {HANG_AT:g} s is in {kept}"]
    _record(kept, round(HANG_AT / 0.0025))


# a C FMU whose exitInitializationMode never returns when its gain k is above 999
EXIT_INIT = "fmi2Status fmi2ExitInitializationMode(fmi2Component c) { return fmi2OK; }"
HANGING_EXIT_INIT = ("fmi2Status fmi2ExitInitializationMode(fmi2Component c)\n"
                     "{ if (((Gain *)c)->k > 999.0) for (;;); return fmi2OK; }")


@pytest.fixture(scope="module")
def hanging_init_fmu(tmp_path_factory):
    if not shutil.which("gcc"):
        pytest.skip("no gcc to compile the C FMU")
    assert EXIT_INIT in foreign_fmus.GAIN_C
    folder = tmp_path_factory.mktemp("init")
    saved, foreign_fmus.GAIN_C = foreign_fmus.GAIN_C, foreign_fmus.GAIN_C.replace(
        EXIT_INIT, HANGING_EXIT_INIT)
    try:
        return foreign_fmus.build_gain(folder)
    finally:
        foreign_fmus.GAIN_C = saved


def _init_scenario(folder: Path, fmu: Path, k: float) -> Path:
    path = folder / f"init_{k:g}.toml"
    path.write_text('description = "an FMU that does not leave initialization"\n\n'
                    '[experiment]\nstop_time = 0.1\nstep = 0.0025\naccuracy = "off"\n'
                    'step_timeout = 0.3\n\n'
                    '[instances.shaft]\nfmu = "MainShaft"\nparameters = { omega0 = 100 }\n\n'
                    f'[instances.motor]\nfmu = "{fmu}"\nparameters = {{ k = {k}, u = 0.0 }}\n')
    return path


def test_step_timeout_covers_initialization(tmp_path, hanging_init_fmu):
    started = time.monotonic()
    proc, _ = _start(tmp_path, "run", str(_init_scenario(tmp_path, hanging_init_fmu, 1000.0)),
                     "--out", str(tmp_path / "out"))
    try:
        _, err = proc.communicate(timeout=60)
    finally:
        with_kill(proc)
    took = time.monotonic() - started
    assert proc.returncode == 1, err
    assert err.splitlines() == ["sewfmu: error: motor took longer than experiment.step_timeout "
                                "= 0.3 s in exitInitializationMode at t = 0 s"]
    assert took < 8, took


def test_a_sweep_point_hanging_in_initialization_fails_and_the_others_go_on(tmp_path,
                                                                            hanging_init_fmu):
    out = tmp_path / "sweep"
    proc, _ = _start(tmp_path, "sweep", str(_init_scenario(tmp_path, hanging_init_fmu, 1.0)),
                     "--grid", "motor.k=1000,2", "--workers", "2", "--quiet", "--out", str(out))
    try:
        printed, err = proc.communicate(timeout=120)
    finally:
        with_kill(proc)
    assert proc.returncode == 0, err
    assert ("failed: motor.k=1000: motor took longer than experiment.step_timeout = 0.3 s in "
            "exitInitializationMode at t = 0 s") in printed
    rows = (out / "sweep.csv").read_text().splitlines()
    assert len(rows) == 3 and ",ok," in rows[2]


def test_a_sweep_point_holding_the_lock_beyond_step_timeout_fails_and_the_others_go_on(
        tmp_path, fmus):
    """The worker's guardian tells the sweep the point's failure (no thread of the worker can)."""
    out = tmp_path / "sweep"
    proc, _ = _start(tmp_path, "sweep", str(_scenario(tmp_path, fmus, mode=2)), "--grid",
                     "motor.hang_at=0.01,5", "--workers", "2", "--quiet", "--out", str(out),
                     "--set", "experiment.step_timeout=0.3")
    try:
        printed, err = proc.communicate(timeout=120)
    finally:
        with_kill(proc)
    assert proc.returncode == 0, err
    assert ("failed: motor.hang_at=0.01: motor took longer than experiment.step_timeout = "
            f"0.3 s in doStep at t = 0.01 s; {LOST}") in printed, printed
    rows = (out / "sweep.csv").read_text().splitlines()
    assert len(rows) == 3 and ",ok," in rows[2]


# a user's script misses its Ctrl-C when this runs after the fast loop and the slow set's first
# files in a fresh clone (CI's order, reproduced twice); it passes alone and after the same files
# without the fast loop: not understood yet (issue 46's closing note)
CI_ORDER = "Ctrl-C lost in CI's order after the fast loop (not understood yet)"


# skipped, not xfail: failing, it waits out a 30 s timeout of CI's time
@pytest.mark.skip(reason=CI_ORDER)
def test_a_users_script_is_told_at_the_first_ctrl_c_and_ended_at_the_second(tmp_path, fmus):
    script = tmp_path / "script.py"
    script.write_text("import sewfmu, sys\n"
                      f"sewfmu.run({str(_scenario(tmp_path, fmus, mode=2))!r})\n"
                      "print('went on')\n")
    marker = tmp_path / "hanging"
    marker.mkdir()
    proc = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            cwd=tmp_path, env={**os.environ, "HANG_MARKER": str(marker)})
    STARTED.append(proc)
    _when_stuck(proc, marker)
    proc.send_signal(signal.SIGINT)
    time.sleep(2.0)
    assert proc.poll() is None                    # told, not ended
    err, took = _signal_and_wait(proc, signal.SIGINT)
    assert proc.returncode == -signal.SIGKILL, err
    assert took < 0.5, took
    where = f"sewfmu: interrupted (SIGINT) while motor was in doStep at t = {HANG_AT:g} s; "
    assert err.splitlines() == [
        where + "its code holds Python's interpreter lock, so nothing in this process can "
                "answer; another Ctrl-C ends it (SIGKILL: the record so far is lost)",
        where + LOST]
