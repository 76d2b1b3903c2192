"""FMUs whose doStep never returns, run by `sewfmu` in a subprocess: a Python FMU (pythonfmu, as
a third party writes one) asleep or spinning in pure Python, and a C FMU spinning in `for (;;);`
(its ctypes call holds the main thread, where Python's signal handlers would run). Ctrl-C or
SIGTERM ends the run, a sweep or a design study (their worker processes too), the check of an
FMU against its references within 2 s with exit status 130 or 143
and one line naming the instance, the FMI call and the time; experiment.step_timeout refuses the
step. The record so far is kept, and checked against the closed forms x = t (the hanging FMU)
and phi = omega0·t (the MainShaft beside it)."""
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tests import foreign_fmus
from tests.processes import processes_in

pytestmark = pytest.mark.slow

SEWFMU = str(Path(sys.executable).with_name("sewfmu"))
H = 0.0025              # s, the communication step
HANG_AT = 0.0125        # s, the start of the step that never ends: the sixth
OMEGA0 = 100.0          # rad/s, the shaft's speed
WITHIN = 2.0            # s from the signal to the end of the process

HANG_PY = '''
import itertools
import os
import signal
import time

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class Hang(Fmi2Slave):
    """x = t; the doStep from t = hang_at never returns: asleep (mode 0), spinning in pure
    Python (mode 1), or in a C loop holding the interpreter lock (mode 2); mode 3 sleeps in
    exitInitializationMode. It touches $HANG_MARKER when it starts hanging; with
    $HANG_IGNORE_SIGINT it ignores SIGINT from its instantiation on."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        if os.environ.get("HANG_IGNORE_SIGINT"):
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        self.hang_at, self.mode, self.x = 1e9, 0.0, 0.0
        for name in ("hang_at", "mode"):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.tunable))
        self.register_variable(Real("x", causality=Fmi2Causality.output))

    def exit_initialization_mode(self):
        if self.mode == 3.0:
            self._hang()

    def _hang(self):
        marker = os.environ.get("HANG_MARKER")
        if marker:
            open(os.path.join(marker, str(os.getpid())), "w").close()
        if self.mode in (0.0, 3.0):
            while True:
                time.sleep(3600)
        if self.mode == 2.0:
            sum(itertools.repeat(0))
        while True:
            pass

    def do_step(self, current_time, step_size):
        if current_time >= self.hang_at - 1e-12:
            self._hang()
        self.x = current_time + step_size
        return True
'''

# the C gain of tests/foreign_fmus.py, whose doStep spins for ever from t = k (its parameter)
SPINNING_STEP = ("fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, "
                 "fmi2Boolean noSet)\n{ ((Gain *)c)->t = t + h; return fmi2OK; }")
SPINNING = ("fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSet)\n"
            "{ if (t >= ((Gain *)c)->k - 1e-12) for (;;); ((Gain *)c)->t = t + h; "
            "return fmi2OK; }")


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """Hang.fmu (pythonfmu) and, where gcc is, Spin.fmu (C): built once for the module."""
    return build_fmus(tmp_path_factory)


def build_fmus(tmp_path_factory) -> dict:
    """The FMUs of `fmus` (tests/cosim/test_gil_held.py builds them too)."""
    from pythonfmu import FmuBuilder  # pythonfmu: only the tests that build an FMU need it

    folder = tmp_path_factory.mktemp("stuck_fmus")
    script = folder / "hang.py"
    script.write_text(HANG_PY)
    hang = Path(FmuBuilder.build_FMU(script, dest=folder))
    spin = None
    if shutil.which("gcc"):
        assert SPINNING_STEP in foreign_fmus.GAIN_C
        c_folder = folder / "c"
        c_folder.mkdir()
        source = foreign_fmus.GAIN_C.replace(SPINNING_STEP, SPINNING)
        saved, foreign_fmus.GAIN_C = foreign_fmus.GAIN_C, source
        try:
            spin = foreign_fmus.build_gain(c_folder)
        finally:
            foreign_fmus.GAIN_C = saved
    # the same, hanging with its defaults in its default experiment: for `sewfmu references`
    now = folder / "now"
    now.mkdir()
    (now / "hang_now.py").write_text(
        HANG_PY.replace("class Hang(Fmi2Slave):", "class HangNow(Fmi2Slave):\n"
                        "    default_experiment = DefaultExperiment(0.0, 1.0, 0.0025)")
        .replace("import Fmi2Causality", "import DefaultExperiment, Fmi2Causality")
        .replace("self.hang_at, self.mode, self.x = 1e9,", f"self.hang_at, self.mode, self.x = "
                                                          f"{HANG_AT},"))
    hang_now = Path(FmuBuilder.build_FMU(now / "hang_now.py", dest=now))
    return {"hang": hang, "spin": spin, "hang_now": hang_now}


def _scenario(folder: Path, fmus: dict, mode: int = 0, spin: bool = False) -> Path:
    """The MainShaft beside the hanging FMU (or, with `spin`, beside the C FMU spinning from
    HANG_AT on)."""
    if spin:
        other = (f'[instances.motor]\nfmu = "{fmus["spin"]}"\n'
                 f'parameters = {{ k = {HANG_AT}, u = 0.0 }}\n')
    else:
        other = (f'[instances.motor]\nfmu = "{fmus["hang"]}"\n'
                 f'parameters = {{ hang_at = {HANG_AT}, mode = {mode} }}\n')
    path = folder / "stuck.toml"
    path.write_text('description = "an FMU that does not return"\n\n'
                    f'[experiment]\nstop_time = 1.0\nstep = {H}\naccuracy = "off"\n\n'
                    f'[instances.shaft]\nfmu = "MainShaft"\nparameters = {{ omega0 = {OMEGA0} }}\n\n'
                    + other)
    return path


STARTED: list[subprocess.Popen] = []


@pytest.fixture(autouse=True)
def _nothing_left_running():
    """Whatever a test found (a failed assertion before its signal too), nothing it started
    stays running: a hanging FMU would spin for ever."""
    yield
    while STARTED:
        with_kill(STARTED.pop())


def _start(folder: Path, *args: str) -> tuple[subprocess.Popen, Path]:
    marker = folder / "hanging"
    marker.mkdir(exist_ok=True)
    env = {**os.environ, "HANG_MARKER": str(marker)}
    proc = subprocess.Popen([SEWFMU, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env, start_new_session=True)
    STARTED.append(proc)
    return proc, marker


def _when_stuck(proc: subprocess.Popen, marker: Path, count: int = 1, settle: float = 0.3):
    """Wait until `count` processes hang in the FMU (their marker files), then a moment more."""
    deadline = time.monotonic() + 120
    while len(list(marker.iterdir())) < count:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "the FMU never started hanging"
        time.sleep(0.05)
    time.sleep(settle)


def _signal_and_wait(proc: subprocess.Popen, sig: int) -> tuple[str, float]:
    sent = time.monotonic()
    proc.send_signal(sig)
    try:
        _, err = proc.communicate(timeout=30)
    finally:
        with_kill(proc)
    return err, time.monotonic() - sent


def with_kill(proc: subprocess.Popen) -> None:
    """SIGKILL to what is left of the process's session (it leads its own)."""
    for pid in processes_in("session", proc.pid):
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    if proc.poll() is None:
        proc.kill()
        proc.wait()


def _record(path: Path, steps: int, spin: bool = False) -> None:
    """results.csv holds the steps completed: t = 0 .. steps·H, against the closed forms."""
    with open(path, encoding="utf-8") as f:
        header = f.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    assert len(data) == steps + 1
    column = {name.split(" [")[0]: data[:, k] for k, name in enumerate(header)}
    np.testing.assert_allclose(column["time"], H * np.arange(steps + 1), rtol=0, atol=1e-15)
    np.testing.assert_allclose(column["shaft.phi"], OMEGA0 * column["time"], rtol=1e-12)
    if not spin:
        np.testing.assert_allclose(column["motor.x"], column["time"], rtol=0, atol=1e-15)


STEPS_DONE = round(HANG_AT / H)          # 5 whole steps, then the sixth never ends


@pytest.mark.parametrize("sig, mode", [(signal.SIGINT, 0), (signal.SIGTERM, 1)],
                         ids=["SIGINT-asleep", "SIGTERM-spinning"])
def test_a_signal_ends_a_run_stuck_in_a_python_fmu_and_keeps_its_record(tmp_path, fmus, sig,
                                                                         mode):
    out = tmp_path / "out"
    proc, marker = _start(tmp_path, "run", str(_scenario(tmp_path, fmus, mode)), "--out",
                          str(out))
    _when_stuck(proc, marker)
    err, took = _signal_and_wait(proc, sig)
    name = signal.Signals(sig).name
    assert proc.returncode == 128 + sig, err
    assert took < WITHIN, took
    kept = out / "interrupted" / "results.csv"
    assert err.splitlines() == [
        f"sewfmu: interrupted ({name}) while motor was in doStep at t = {HANG_AT:g} s; the "
        f"record up to t = {HANG_AT:g} s is in {kept}"]
    _record(kept, STEPS_DONE)


def test_a_signal_ends_a_run_stuck_in_a_c_fmus_endless_loop(tmp_path, fmus):
    if fmus["spin"] is None:
        pytest.skip("no gcc to compile the C FMU")
    out = tmp_path / "out"
    proc, _ = _start(tmp_path, "run", str(_scenario(tmp_path, fmus, spin=True)), "--out",
                     str(out))
    # no marker from C: the run takes well under a second up to the endless step
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None and \
            not _spinning(proc.pid):
        time.sleep(0.1)
    err, took = _signal_and_wait(proc, signal.SIGINT)
    assert proc.returncode == 130, err
    assert took < WITHIN, took
    kept = out / "interrupted" / "results.csv"
    assert err.splitlines() == [
        f"sewfmu: interrupted (SIGINT) while motor was in doStep at t = {HANG_AT:g} s; the "
        f"record up to t = {HANG_AT:g} s is in {kept}"]
    _record(kept, STEPS_DONE, spin=True)


def _spinning(pid: int) -> bool:
    """The process has burnt a second of CPU time since it was counted first: in the loop."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    ticks = int(fields[11]) + int(fields[12])         # utime + stime
    _spinning.seen.setdefault(pid, []).append((time.monotonic(), ticks))
    first_t, first_ticks = _spinning.seen[pid][0]
    hz = os.sysconf("SC_CLK_TCK")
    return time.monotonic() - first_t > 1.5 and (ticks - first_ticks) / hz > 1.0


_spinning.seen = {}


def test_a_signal_ends_the_reference_run_of_any_fmu_stuck_in_a_call(tmp_path, fmus):
    """`sewfmu references --fmu` runs a supplier's FMU through fmpy's simulate_fmu: the same way
    out."""
    refs = tmp_path / "refs"
    proc, marker = _start(tmp_path, "references", "--fmu", str(fmus["hang_now"]), "--refs",
                          str(refs), "--regenerate")
    _when_stuck(proc, marker)
    err, took = _signal_and_wait(proc, signal.SIGINT)
    assert proc.returncode == 130, err
    assert took < WITHIN, took
    assert err.splitlines() == [f"sewfmu: interrupted (SIGINT) while reference was in doStep at "
                                f"t = {HANG_AT:g} s; nothing of the interrupted run was written"]
    assert not refs.exists() or not list(refs.rglob("*.csv"))


def test_a_step_beyond_step_timeout_is_refused_with_the_record_kept(tmp_path, fmus):
    out = tmp_path / "out"
    proc, _ = _start(tmp_path, "run", str(_scenario(tmp_path, fmus, mode=1)), "--out", str(out),
                     "--set", 'experiment.step_timeout="300 ms"')
    started = time.monotonic()
    try:
        _, err = proc.communicate(timeout=60)
    finally:
        with_kill(proc)
    assert proc.returncode == 1, err
    assert time.monotonic() - started < 30
    kept = out / "interrupted" / "results.csv"
    assert err.splitlines() == [
        f"sewfmu: error: motor took longer than experiment.step_timeout = 0.3 s in doStep at "
        f"t = {HANG_AT:g} s; the record up to t = {HANG_AT:g} s is in {kept}"]
    _record(kept, STEPS_DONE)


def test_a_signal_ends_a_sweep_whose_workers_are_stuck_leaving_no_process(tmp_path, fmus):
    out = tmp_path / "sweep"
    proc, marker = _start(tmp_path, "sweep", str(_scenario(tmp_path, fmus, mode=1)), "--grid",
                          "motor.hang_at=0.01,0.02,0.03", "--workers", "2", "--quiet",
                          "--out", str(out))
    _when_stuck(proc, marker, count=2)
    assert len(processes_in("session", proc.pid)) >= 3        # the sweep, its two workers
    err, took = _signal_and_wait(proc, signal.SIGINT)
    assert proc.returncode == 130, err
    assert took < WITHIN, took
    # the stuck points' words, passed up by their workers: instance, call, time, point
    lines = [f"sewfmu: interrupted (SIGINT) while motor was in doStep at t = {a:g} s (point "
             f"motor.hang_at={a:g}), and 1 other point stuck; the points finished so far are "
             f"kept: the same command resumes" for a in (0.01, 0.02)]
    assert len(err.splitlines()) == 1 and err.splitlines()[0] in lines, err
    deadline = time.monotonic() + WITHIN
    while processes_in("session", proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert processes_in("session", proc.pid) == []


def test_a_signal_ends_a_design_study_whose_run_is_stuck(tmp_path, fmus):
    """With one worker the study runs in the command's own process, which the watchdog ends
    (worker processes end as a sweep's: the same pool)."""
    punch = subprocess.run([SEWFMU, "show", "punch_drive"], capture_output=True, text=True,
                           check=True).stdout.replace("revolutions = 10", "revolutions = 2")
    study = tmp_path / "study.toml"
    study.write_text(punch + f'\n[instances.motor]\nfmu = "{fmus["hang"]}"\n'
                             f'parameters = {{ hang_at = 0.05, mode = 1 }}\n')
    proc, marker = _start(tmp_path, "optimize", str(study), "--vary", "punch.F30=1..5",
                          "--minimize", "F2_peak", "--workers", "1", "--out",
                          str(tmp_path / "opt"))
    _when_stuck(proc, marker)
    err, took = _signal_and_wait(proc, signal.SIGINT)
    assert proc.returncode == 130, err
    assert took < WITHIN, took
    said = err.splitlines()[-1]
    assert said.startswith("sewfmu: interrupted (SIGINT)") and said.endswith(
        "the points finished so far are kept: the same command resumes"), err
    assert "while motor was in doStep at t = 0.05" in said
    assert "Traceback" not in err
    deadline = time.monotonic() + WITHIN
    while processes_in("session", proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert processes_in("session", proc.pid) == []


def test_a_sweep_point_beyond_step_timeout_fails_and_the_others_go_on(tmp_path, fmus):
    out = tmp_path / "sweep"
    proc, _ = _start(tmp_path, "sweep", str(_scenario(tmp_path, fmus, mode=0)), "--grid",
                     "motor.hang_at=0.01,5", "--workers", "2", "--quiet", "--out", str(out),
                     "--set", "experiment.step_timeout=0.3")
    try:
        printed, err = proc.communicate(timeout=120)
    finally:
        with_kill(proc)
    assert proc.returncode == 0, err
    assert ("failed: motor.hang_at=0.01: motor took longer than experiment.step_timeout = "
            "0.3 s in doStep at t = 0.01 s") in printed
    rows = (out / "sweep.csv").read_text().splitlines()
    assert len(rows) == 3 and ",ok," in rows[2]


def _handles_sigterm(pid: int) -> bool:
    """sewfmu's own handlers are in place (its start-up's catch SIGTERM; Python alone does not)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return True
    caught = int(next(line for line in status.splitlines()
                      if line.startswith("SigCgt:")).split()[1], 16)
    return bool(caught & (1 << (signal.SIGTERM - 1)))


@pytest.mark.parametrize("delay", [0.0, 0.05, 0.1, 0.2, 0.4])
def test_ctrl_c_before_the_fmus_load_is_one_line_and_status_130(tmp_path, fmus, delay):
    out = tmp_path / "out"
    proc, _ = _start(tmp_path, "run", str(_scenario(tmp_path, fmus)), "--out", str(out))
    deadline = time.monotonic() + 10
    while not _handles_sigterm(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.001)
    time.sleep(delay)
    err, took = _signal_and_wait(proc, signal.SIGINT)
    assert proc.returncode == 130, err
    assert took < WITHIN, took
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("sewfmu: interrupted (SIGINT)"), err
    assert "Traceback" not in err
