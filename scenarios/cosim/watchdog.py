"""The way out of an FMU call that never returns.

A call into an FMU holds the main thread until it returns, and Python runs its signal handlers
in the main thread only, between two bytecodes: a doStep that never returns (a C library in a
loop, a Python FMU asleep or spinning) would keep Ctrl-C and SIGTERM, which interrupt.py defers
to the next step, waiting for ever. While a run is under way in the main thread (`watching`), a
thread here learns of every signal from the file descriptor Python's C-level handler writes to
(signal.set_wakeup_fd), gives the main thread GRACE seconds to reach its check between two steps,
and otherwise ends the run itself: it names the instance and the FMI call the main thread is in
(read from the main thread's Python stack when it is needed: nothing is noted per step), has the
record so far kept (by the writer a front door gave `keeping`), and ends the process through the
hook of the process's owner (`end_process_with`: the command line, a sweep's worker), since a
call that never returns cannot be unwound. experiment.step_timeout is watched by the same thread,
which then samples the run's step counter (only then: the thread otherwise only waits).

In a process that is not sewfmu's own (the API in a script or a notebook) the thread does not end
the process at the first SIGINT: it says where the run is stuck and that a second signal ends the
process (SIGTERM ends it at once).

All of this needs the interpreter lock; an FMU whose code holds it for ever (a C loop inside a
pythonfmu doStep) is guardian.py's: a process beside this one reads the wakeup pipe (passing each
byte on to this thread) and the board the run writes (a beat per step and per FMI call), and ends
this process when nothing here answers.
"""
from __future__ import annotations

import contextlib
import linecache
import os
import select
import signal
import sys
import threading
import time

# nothing heavy (no fmpy): the command line imports this module before it knows its command
from sewfmu.scenarios.cosim import guardian, interrupt
from sewfmu.scenarios.cosim.guardian import ANSWERED, BEAT, ENDING, IDLE, RELAYED, RUNNING, WHERE
from sewfmu.scenarios.cosim.interrupt import Interrupted

GRACE = 0.5        # s the main thread has to reach its check between two steps after a signal
POLL = 0.1         # s between two looks at the step counter, with experiment.step_timeout


# the run under way in the main thread and what ends it; _lock guards the fields, _ending is
# held by whoever ends a run (the main thread leaving `watching`, or the watchdog)
_lock = threading.Lock()
_ending = threading.Lock()
_left = threading.Event()     # the run under watch has left `watching`
_run = None                   # the Master under way
_timeout: float | None = None
_writer = None                # writer(result, reason) -> "the record up to t = … s is in …"
_instead = None               # (RunResult, where): the record to keep instead of the run's own
_end = None                   # end(err) -> never returns: the process owner's way out
_pipe: tuple[int, int] | None = None   # (read, write): the thread's (relayed by the guardian)
_wake: int | None = None      # the wakeup fd: the guardian reads it
_pid = None                   # the process the pipe and the thread belong to (not a fork's)
_board = None                 # guardian.Board: what the run writes for its guardian
_given = None                 # (board, wake, relay read, relay write) from a waiting parent
_mode, _conn = "api", None    # how the guardian ends this process (guardian.serve)
_guard = None                 # the guardian process this one started


class _Unwatched:
    """The board of a process no guardian reads (before its first run): written, never read."""

    def __init__(self):
        page = bytearray(guardian.SIZE)
        self.q, self.d = memoryview(page).cast("q"), memoryview(page).cast("d")

    def names(self, names) -> None:
        pass


def board():
    """The board the run writes for the guardian (nothing reads it outside a watched run)."""
    return _board or _UNWATCHED


_UNWATCHED = _Unwatched()


def guarded_by_parent(given) -> None:
    """This process is a child the `sewfmu` process waits for and guards
    (guardian.guard_a_child): its board and pipes."""
    global _given, _mode
    _given, _mode = given, "own"


def guard_mode(mode: str, conn: int | None = None) -> None:
    """How a guardian ends this process: "worker" (a sweep's, `conn` its pipe to the main
    process), "own" (sewfmu's command), "api" (a user's: the default)."""
    global _mode, _conn
    _mode, _conn = mode, conn


class Steps:
    """A run that is not a Master's (fmpy's simulate_fmu, for a reference), as `watching` sees
    it: its caller sets the time and the count of steps between two steps."""

    _phase, recorder, scenario = "step", None, None

    def __init__(self, t: float = 0.0):
        self.t, self.k = t, 0


def end_process_with(end) -> None:
    """This process is sewfmu's own: `end(err)` prints what the owner prints for the Interrupted
    or StepTimeout `err` and ends the process (os._exit). (A hook that returns leaves the run to
    the main thread: what a test of the watchdog does. None: the process is not sewfmu's.)"""
    global _end
    _end = end


@contextlib.contextmanager
def keeping(writer):
    """Within the block, a run ended by the watchdog has its record kept by
    `writer(result, reason)`, which returns where it is (`the record up to t = … s is in …`)."""
    global _writer
    previous, _writer = _writer, writer
    try:
        yield
    finally:
        _writer = previous


@contextlib.contextmanager
def keeping_instead(result, where: str):
    """Within the block, an ended run keeps `result` (a finished run whose estimate runs now)
    instead of its own record, and says it was `where`."""
    global _instead
    previous, _instead = _instead, (result, where)
    try:
        yield
    finally:
        _instead = previous


@contextlib.contextmanager
def watching(master):
    """The run `master` is under way in this thread: a signal it does not answer within GRACE,
    or a step beyond its experiment.step_timeout, ends it. Only the main thread is watched (the
    only one that signals reach)."""
    global _run, _timeout
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _start()
    # Python's C-level handler writes the signal's number to the wakeup fd: it wakes the
    # guardian (which passes it on to the watchdog thread) wherever the main thread is (the
    # handler that marks interrupt.pending runs only between bytecodes)
    previous = signal.set_wakeup_fd(_wake, warn_on_full_buffer=False)
    with _lock:
        _run, _timeout = master, getattr(master.scenario, "step_timeout", None)
        _left.clear()
    paper = board()
    paper.q[WHERE], paper.d[guardian.TIMEOUT] = -1, _timeout or 0.0
    paper.q[ANSWERED] = paper.q[RELAYED]
    paper.q[guardian.TOLD] = 0
    paper.q[guardian.STATE] = RUNNING
    interrupt.board = _board
    _poke()
    try:
        yield
    finally:
        with _ending:           # a run being ended by the watchdog: the process ends with it
            with _lock:
                _run, _timeout = None, None
                _left.set()
                paper.q[guardian.STATE] = IDLE
        signal.set_wakeup_fd(previous)
        _poke()


def _start() -> None:
    """The pipe and the thread, once per process (a forked child starts its own)."""
    global _pipe, _pid, _wake, _board, _guard
    if _pid == os.getpid():
        return
    if _given is not None:                    # the parent waiting for this process guards it
        _board, _wake, read, write = _given
    else:
        _board = guardian.Board()
        wake_r, _wake = os.pipe()
        read, write = os.pipe()
        os.set_blocking(_wake, False)          # set_wakeup_fd's rule
        os.set_blocking(write, False)
        try:
            _guard = guardian.spawn(_board, wake_r, write, _mode, _conn)
        except OSError:       # no guardian: the thread reads the wakeup fd itself
            _guard, _wake = None, write
        os.close(wake_r)
    _pipe, _pid = (read, write), os.getpid()
    threading.Thread(target=_watch, args=(read,), name="sewfmu-watchdog", daemon=True).start()


def _poke() -> None:
    """Wake the thread to read the run's settings again (a zero byte: no signal)."""
    with contextlib.suppress(OSError):
        os.write(_pipe[1], b"\0")


def _watch(read: int) -> None:
    seen, since, warned, first_signal = None, 0.0, None, {}
    while True:
        limit = _timeout
        # the step counter sampled at most every 0.1 s (each sample takes the GIL from the
        # run: at 200 a second, 13 % of punch_drive's time; at 10 none measurable)
        period = None if limit is None else min(POLL, max(POLL / 5, limit / 10))
        ready, _, _ = select.select([read], [], [], period)
        signals = [b for b in os.read(read, 512) if b in _SIGNALS] if ready else []
        run = _run
        if run is None:
            seen = warned = None
            first_signal.clear()
            continue
        try:
            if signals:
                # the first signal decides (of two read at once, SIGTERM: interrupt.py)
                first = first_signal.get(run) or (
                    signal.SIGTERM if signal.SIGTERM in signals else signals[0])
                first_signal[run] = first
                if warned is run:                   # a second signal to a stuck run: now
                    _finish(run, Interrupted(first))
                elif not _answered_within(GRACE):
                    warned = _stuck(run, Interrupted(first))
            paper = board()
            # every FMI call is under the limit: from the first (instantiate) on, a beat at each
            # communication step and each other call (nothing before: unpacking, loading)
            if limit is None or (paper.q[WHERE] < 0 and getattr(run, "_phase", "") != "step"):
                seen = None
                continue
            now = time.monotonic()
            if seen != (run, run.k, paper.q[BEAT]):
                seen, since = (run, run.k, paper.q[BEAT]), now
            elif now - since > limit and warned is not run:
                warned = _stuck(run, None, limit)
        except Exception:          # the watchdog outlives a failure of its own: the next run
            seen = None


_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def _answered_within(grace: float) -> bool:
    """Whether the main thread answers the signals so far within `grace` (it leaves the run, or
    a user's own handler took them between two steps: interrupt.raise_pending)."""
    paper, deadline = board(), time.monotonic() + grace
    while not _left.wait(min(0.05, max(0.0, deadline - time.monotonic()))):
        if paper.q[ANSWERED] >= paper.q[RELAYED] > 0 or time.monotonic() >= deadline:
            return paper.q[ANSWERED] >= paper.q[RELAYED] > 0
    return True


def _answer() -> None:
    """Tell the guardian this process answers (the lock is not held)."""
    paper = board()
    paper.q[ANSWERED] = paper.q[RELAYED]


def _stuck(run, err: Interrupted | None, limit: float | None = None):
    """The main thread has not answered the signal `err` (or its step has run beyond `limit`):
    end the run; in a process that is not sewfmu's own, say where it is stuck instead and return
    the run, which the next signal ends."""
    _answer()
    if err is None:
        board().q[guardian.TOLD] = 1    # this thread answers the timeout: the guardian stands down
    if _end is not None or (err is not None and err.signum == signal.SIGTERM):
        _finish(run, err, limit)        # SIGTERM ends a user's process too, as its default does
        return None
    with _lock:
        if _run is not run:
            return None
    said = _interrupted(run, err).reason if err is not None else _overdue(run, limit)
    how = signal.Signals(err.signum).name if err is not None else "Ctrl-C"
    sys.stderr.write(f"sewfmu: {said}: the call does not return, and sewfmu ends only its own "
                     f"processes; a{'nother' if err is not None else ''} {how} ends this "
                     f"one\n")
    sys.stderr.flush()
    return run


def _overdue(run, limit: float) -> str:
    """What a step beyond experiment.step_timeout is, as the line says it."""
    inst, call = stuck_call()
    if inst is None:
        said = (f"the step from t = {run.t:g} s took longer than experiment.step_timeout = "
                f"{limit:g} s")
    else:
        said = f"{inst} took longer than experiment.step_timeout = {limit:g} s in {call} at " \
               f"t = {run.t:g} s"
    return said + _of_the_estimate()


def _of_the_estimate() -> str:
    """Where the stuck run is the coarser run of the coupling-error estimate (its time is not
    the record's: the record kept is the finished run's)."""
    return " of the coarser run that estimates the coupling error, after the run" \
        if _instead is not None else ""


def _finish(run, err: Interrupted | None, limit: float | None = None) -> None:
    """End the run stuck in the main thread: its record kept, the owner's line, the process
    ended (never returns). Nothing happens if the main thread has left the run meanwhile."""
    with _ending:
        if _run is not run:
            return
        board().q[guardian.STATE] = ENDING      # the guardian leaves the ending to this thread
        if err is not None:
            _interrupted(run, err)
            result, reason = err.result, err.reason
        else:
            result, reason = _record_of(run), _overdue(run, limit)
        kept = None
        if result is not None and _writer is not None:
            try:
                kept = _writer(result, reason)
            except Exception as why:       # the line is said whatever happens, and why
                kept = f"its record was not written: {' '.join(str(why).split())}"
        if err is None:
            from sewfmu.scenarios.cosim.fmi_calls import StepTimeout  # loaded with the run
            err = StepTimeout(f"{reason}; {kept}" if kept else reason)
        else:
            err.kept = kept
        try:
            (_end or _default_end)(err)     # ends the process (a hook that returns: a test's)
        except Exception:
            _default_end(err)               # the owner's hook failed: the process ends all the same


def _interrupted(run, err: Interrupted) -> Interrupted:
    """err with where the run is and what it recorded."""
    inst, call = stuck_call()
    phase = getattr(run, "_phase", "loading")
    at = f" at t = {run.t:g} s" if phase in ("initialization", "step") else ""
    if _instead is not None:
        err.result, err.where = _instead
        if inst:
            err.where = f"while {inst} was in {call}{at}{_of_the_estimate()}"
        return err
    if inst:
        err.where = f"while {inst} was in {call}{at}"
    else:
        err.where = at.strip() if phase == "step" else "while loading the FMUs"
    err.result = _record_of(run)
    return err


def _record_of(run):
    """The run's record so far (None before its first record)."""
    if _instead is not None:
        return _instead[0]
    if getattr(run, "recorder", None) is None or not run.recorder.length:
        return None
    try:
        return run.result()
    except Exception:                  # a record that cannot be read is not kept
        return None


def _default_end(err) -> None:
    """The end of a process that is not sewfmu's own, at the user's second signal (or at
    SIGTERM). It runs in the watchdog thread, where signal.signal cannot put SIGTERM's default
    back: the process ends by os._exit with the status a shell gives a SIGTERM'd one (143)."""
    line = err.reason + (f"; {err.kept}" if err.kept else "") if isinstance(err, Interrupted) \
        else f"error: {err}"
    with contextlib.suppress(Exception):
        sys.stderr.write(f"sewfmu: {line}\n")
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(err.exit_status if isinstance(err, Interrupted) else 1)


# the FMI call an Instance method makes, by the words of its source line (a method that makes
# several) or by its name
_WORDS = (("_step(", "doStep"), ("_set_reals", "set inputs"), ("_get_reals", "get outputs"),
          ("_get_booleans", "get Boolean outputs"), ("terminate", "terminate"),
          ("free", "freeInstance"))
_NAMES = {"_do_step": "doStep", "do_step": "doStep", "instantiate": "instantiate",
          "_instantiate": "instantiate", "get_state": "getFMUState",
          "set_state": "setFMUState", "free_state": "freeFMUState", "set_inputs": "set inputs",
          "pull_changed_inputs": "set inputs", "_set_reals": "set inputs",
          "_get_reals": "get outputs", "_get_booleans": "get Boolean outputs",
          "enter_initialization": "enterInitializationMode",
          "exit_initialization": "exitInitializationMode", "set_parameter": "set a parameter",
          "release": "terminate"}


def stuck_call(thread: threading.Thread | None = None) -> tuple[str | None, str | None]:
    """(instance name, FMI call) the thread (the main thread) is in now, from its Python stack:
    the innermost frame of a method of sewfmu's Instance or of fmpy's FMU object (an FMU's own
    Python code runs above it); (None, None) where it is in no FMU call."""
    # loaded with the first FMU (a call needs them), never by this module: see its imports
    instance = getattr(sys.modules.get("sewfmu.scenarios.cosim.instances"), "Instance", None)
    fmpy_fmu = getattr(sys.modules.get("fmpy.fmi1"), "_FMU", None)
    ident = (thread or threading.main_thread()).ident
    frame = sys._current_frames().get(ident)
    while frame is not None and (instance or fmpy_fmu):
        inst = frame.f_locals.get("self")
        if fmpy_fmu and isinstance(inst, fmpy_fmu):
            if frame.f_code.co_name == "_call":   # fmpy's call of any function: fmi2DoStep
                name = str(frame.f_locals.get("fname", "an FMI call"))
                if name[:4] in ("fmi2", "fmi3"):   # as the calls are named elsewhere: doStep
                    name = name[4].lower() + name[5:]
                return str(inst.instanceName), name
            return str(inst.instanceName), frame.f_code.co_name     # its methods' FMI names
        if instance and isinstance(inst, instance):
            name = frame.f_code.co_name
            if name == "_call":
                return inst.name, str(frame.f_locals.get("what", "an FMI call"))
            if name in ("exchange", "release"):
                line = linecache.getline(frame.f_code.co_filename, frame.f_lineno)
                call = next((c for word, c in _WORDS if word in line), None)
                if call:
                    return inst.name, call
            return inst.name, _NAMES.get(name, name)
        frame = frame.f_back
    return None, None
