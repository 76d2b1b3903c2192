"""The way out that needs no interpreter lock: a process beside the one that runs the FMUs.

A pythonfmu FMU's doStep that runs a C loop holding Python's interpreter lock (GIL), say
`sum(itertools.repeat(0))`, keeps every thread of its process from running: the watchdog thread
(watchdog.py) never wakes, and only SIGKILL ends the process. So a second process guards each
process that runs FMUs: the command line's own process (the run happens in a child of it, and the
`sewfmu` process the shell waits for guards it: `guard_a_child`), or a small `python -I -S` of this
file beside a sweep's worker or a user's script (`spawn`). It learns of every signal from the
wakeup pipe (Python's C-level handler writes the signal's number there without the GIL; the
guardian passes each byte on to the watchdog thread), and of the run from a shared page (`Board`)
the run writes to: a beat at every communication step and every other FMI call, the time, the
instance and call under way, experiment.step_timeout, and what the watchdog thread answered. A
signal no thread of the run's process answers within GRACE + MARGIN, or a call beyond
step_timeout + GRACE + MARGIN that none refuses, is a process whose lock is held for ever: the
guardian says the one line (instance, call and time as the run last wrote them) and ends it
with SIGKILL. Its record so far is lost then, and only then: it lives in the killed process.

Standard library only, and runnable as a script by its path: the guardian starts in ~15 ms.
"""
from __future__ import annotations

import contextlib
import ctypes
import mmap
import os
import select
import signal
import struct
import sys
import time

GRACE = 0.5          # s the run's own process has to answer a signal (watchdog.GRACE)
MARGIN = 0.6         # s more before the guardian takes the lock for held (a loaded machine)
ENDING_LIMIT = 30.0  # s the watchdog's own ending (writing the record) may take before SIGKILL
# s a child may take to show a forwarded signal reached Python (a byte on its wakeup pipe) before
# the waiter takes it for ignored (an FMU's SIG_IGN or handler of its own): within the 2 s promise
IGNORED_GRACE = 1.5
SIGNALS = (signal.SIGINT, signal.SIGTERM)

# the board: int64 fields, then float64 fields, then the instances' names
STATE, BEAT, WHERE, RELAYED, ANSWERED, TOLD = range(6)  # int64 index
# TOLD: 1 once the watchdog thread has said the run's step_timeout line (the lock is free then)
T, TIMEOUT = 8, 9                                      # float64 index (byte 64 on)
NAMES_AT, SIZE = 128, 4096
IDLE, RUNNING, ENDING = 0, 1, 2
# the FMI call under way, as WHERE = slot * 32 + code says it
CALLS = ("an FMI call", "doStep", "set inputs", "get outputs", "instantiate",
         "setupExperiment", "enterInitializationMode", "exitInitializationMode",
         "set a parameter", "terminate", "freeInstance", "getFMUState", "setFMUState",
         "get Boolean outputs")
CODE = {name: k for k, name in enumerate(CALLS)}


class Board:
    """The page the run writes and the guardian reads (a memfd: shared across fork and exec)."""

    def __init__(self, fd: int | None = None):
        if fd is None:
            fd = os.memfd_create("sewfmu-board", os.MFD_CLOEXEC)
            os.ftruncate(fd, SIZE)
        self.fd = fd
        self.page = mmap.mmap(fd, SIZE)
        self.q = memoryview(self.page).cast("q")
        self.d = memoryview(self.page).cast("d")

    def names(self, names: list[str]) -> None:
        data = "\n".join(names).encode("utf-8", "replace")[:SIZE - NAMES_AT - 1]
        self.page[NAMES_AT:NAMES_AT + len(data) + 1] = data + b"\0"

    def where(self) -> tuple[str | None, str | None]:
        """(instance, call) as the run last wrote them."""
        code = self.q[WHERE]
        if code < 0:
            return None, None
        raw = self.page[NAMES_AT:SIZE].split(b"\0", 1)[0].decode("utf-8", "replace")
        names = raw.split("\n")
        slot, call = divmod(code, 32)
        name = names[slot] if slot < len(names) else None
        return name, CALLS[call] if call < len(CALLS) else CALLS[0]


# why the guardian ends a process, as its line says it (besides a held lock)
WHY_IGNORED = ("it ignores the signal (an FMU's own signal handling), so sewfmu killed it "
               "(SIGKILL) and the record so far could not be kept")
WHY_ENDING = (f"its own ending (writing the record) took longer than {ENDING_LIMIT:g} s, so "
              f"sewfmu killed it (SIGKILL) and the record may be incomplete")


def _line(board: Board, signum: int | None, limit: float | None, own: bool,
          end: bool = True, why: str | None = None) -> str:
    """The one line of a run the guardian ends (or, not `end`, tells a user's process of);
    `why` instead of the held lock where that is not the reason."""
    inst, call = board.where()
    t = board.d[T]
    lost = why or ("its code holds Python's interpreter lock, so nothing in that process can answer: "
            "sewfmu killed it (SIGKILL) and the record so far is lost") if end else \
        ("its code holds Python's interpreter lock, so nothing in this process can answer; "
         "another Ctrl-C ends it (SIGKILL: the record so far is lost)")
    who = inst or "an FMU"
    if signum is not None:
        name = signal.Signals(signum).name
        said = f"interrupted ({name}) while {who} was in {call or 'an FMI call'} at t = {t:g} s"
        head = f"sewfmu: {said}; "
    else:
        said = (f"{who} took longer than experiment.step_timeout = {limit:g} s in "
                f"{call or 'an FMI call'} at t = {t:g} s")
        head = f"sewfmu: {'error: ' if own else ''}{said}; "
    return head + lost


def serve(board: Board, wake: int, relay: int | None, target: int, mode: str,
          conn: int | None = None, child: int | None = None) -> int:
    """Guard the process `target` until it ends (EOF on its wakeup pipe `wake`, or `child`'s
    exit); pass each byte read from `wake` on to `relay`. mode: "own" (sewfmu's command: end at
    the first signal), "api" (a user's process: say it at the first SIGINT, end at the second or
    at SIGTERM), "worker" (a sweep's: a call beyond step_timeout is told to the main process as
    the point's failure through `conn`, a multiprocessing Connection's file descriptor).
    Returns the exit status the waiter of a child gives (guard_a_child)."""
    pidfd = None
    if child is not None:
        with contextlib.suppress(OSError, AttributeError):
            pidfd = os.pidfd_open(child)
    signum, deadline, relayed, said = None, None, 0, False
    seen, since, ending = None, time.monotonic(), None
    last_byte = None          # when the last signal byte came from the guarded process
    while True:
        limit = board.d[TIMEOUT]
        # a run's beat is looked at 10 times a second (a few µs each); idle, 4 times
        period = 0.1 if (deadline or board.q[STATE] != IDLE) else 0.25
        watched = ([wake] if wake is not None else []) + ([pidfd] if pidfd is not None else [])
        try:
            ready, _, _ = select.select(watched, [], [], period)
        except OSError:
            ready = []
        now = time.monotonic()
        if child is not None:
            done = _reaped(child)
            if done is not None:
                return done
        if wake is not None and wake in ready:
            data = os.read(wake, 512)
            if not data:
                if child is None:
                    return 0                  # the guarded process is gone
                os.close(wake)
                wake = None                   # the child's status comes next
                continue
            signals = [b for b in data if b in SIGNALS]
            if signals:
                last_byte = now
            running = board.q[STATE] == RUNNING
            if signals and running:     # counted before the thread can read them
                relayed += len(signals)
                board.q[RELAYED] = relayed
            if relay is not None:
                with contextlib.suppress(OSError):
                    os.write(relay, data)
            if signals and running:
                if signum is None or not said:
                    # the first signal decides (of two read at once, SIGTERM: interrupt.py)
                    signum = signum or (signal.SIGTERM if signal.SIGTERM in signals
                                        else signals[0])
                    deadline = now + GRACE + MARGIN
                elif mode == "api":                        # the second: now
                    return _kill(target, board, signum, None, mode, conn, child, True)
        state = board.q[STATE]
        if state == IDLE:
            signum, deadline, said, seen, ending = None, None, False, None, None
            relayed = board.q[RELAYED]
            continue
        if state == ENDING:
            ending = ending or now + ENDING_LIMIT
            if now > ending:
                return _kill(target, board, signum, None, mode, conn, child, True, WHY_ENDING)
            continue
        forwarded = _FORWARDED
        if child is not None and forwarded is not None and \
                now - forwarded[1] > IGNORED_GRACE and \
                (last_byte is None or last_byte < forwarded[1] - GRACE):
            # a signal this waiter passed on never reached the child's Python (its C handler
            # writes the wakeup pipe, whatever holds the lock): an FMU ignores it or handles it
            # itself, and nothing else would ever end the child
            return _kill(target, board, signum or forwarded[0], None, mode, conn, child, True,
                         WHY_IGNORED)
        if deadline is not None and now >= deadline and board.q[ANSWERED] < relayed:
            end_now = mode != "api" or signum == signal.SIGTERM
            done = _kill(target, board, signum, None, mode, conn, child, end_now)
            if end_now:
                return done
            deadline, said = None, True
        # a step beyond step_timeout the watchdog thread has told of: the lock is free
        if limit > 0 and board.q[WHERE] >= 0 and not board.q[TOLD]:
            beat = board.q[BEAT]
            if seen != beat:
                seen, since = beat, now
            elif now - since > limit + GRACE + MARGIN:
                end_now = mode != "api"
                done = _kill(target, board, None, limit, mode, conn, child, end_now)
                if end_now:
                    return done
                since = float("inf")            # said once; a Ctrl-C ends it
                said, signum = True, signal.SIGINT


def _kill(target: int, board: Board, signum, limit, mode: str, conn, child, end: bool,
          why: str | None = None) -> int:
    """Say the line (or hand it to the sweep), and with `end` kill the process."""
    line = _line(board, signum, limit, mode != "worker", end, why)
    if mode == "worker":
        if signum is None and conn is not None:          # the point's failure, to the sweep
            import pickle  # only for this message

            message = pickle.dumps(("died", line.removeprefix("sewfmu: ")))
            with contextlib.suppress(OSError):
                os.write(conn, struct.pack("!i", len(message)) + message)
    else:
        with contextlib.suppress(OSError):
            os.write(2, (("\r\033[K" if os.isatty(2) else "") + line + "\n").encode())
    if not end:
        return 0
    with contextlib.suppress(OSError):
        os.kill(target, signal.SIGKILL)
    if child is not None:
        with contextlib.suppress(ChildProcessError):
            os.waitpid(child, 0)
    return 128 + signum if signum is not None else 1


def _reaped(child: int) -> int | None:
    """The exit status a shell would see for `child`, once it has ended."""
    try:
        pid, status = os.waitpid(child, os.WNOHANG)
    except ChildProcessError:
        return 1
    if pid == 0:
        return None
    if os.WIFSIGNALED(status):
        return -os.WTERMSIG(status)
    return os.waitstatus_to_exitcode(status)


def die_with_parent() -> None:
    """SIGKILL when the parent ends (Linux), without the parent's or this process's GIL."""
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)   # PR_SET_PDEATHSIG


# the child of guard_a_child: None in the waiter before the fork and in the child
_CHILD: int | None = None
# (signal, when) of the first signal the waiter passed on to its child while the child ran
# FMUs and had not shown it yet (serve: none shown within IGNORED_GRACE is an ignored one)
_FORWARDED: tuple[int, float] | None = None
_BOARD: Board | None = None     # the child's board, in the waiter


def guard_a_child(starting_handler) -> tuple[Board, int, int, int]:
    """The command line's run happens in a child; this process waits for it, passes the signals
    it gets on, guards it (serve) and ends with its exit status (a child killed by a signal: this
    process ends by the same). Returns, in the child, (board, wakeup write end, relay read end,
    relay write end). `starting_handler(signum, frame)`: what a signal does in the child before
    the child's own handlers (sewfmu/__main__.py's)."""
    global _CHILD, _BOARD
    board = Board()
    wake_r, wake_w = os.pipe()
    relay_r, relay_w = os.pipe()
    os.set_blocking(wake_w, False)              # set_wakeup_fd's rule
    os.set_blocking(relay_w, False)
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    parent = os.getpid()
    signal.pthread_sigmask(signal.SIG_BLOCK, SIGNALS)
    pid = os.fork()
    if pid == 0:
        die_with_parent()
        for s in SIGNALS:
            signal.signal(s, starting_handler)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, SIGNALS)
        if os.getppid() != parent:
            os._exit(1)
        os.close(wake_r)
        return board, wake_w, relay_r, relay_w
    _CHILD, _BOARD = pid, board
    for s in SIGNALS:
        signal.signal(s, _forward)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, SIGNALS)
    os.close(wake_w)
    os.close(relay_r)
    status = serve(board, wake_r, relay_w, pid, "own", child=pid)
    if status < 0:                              # killed by a signal: so is this process
        with contextlib.suppress(OSError, ValueError):     # SIGKILL has no handler to reset
            signal.signal(-status, signal.SIG_DFL)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, [-status])
        os.kill(os.getpid(), -status)
        status = 128 - status
    os._exit(status)


def _forward(signum, frame) -> None:
    """A signal to the waiter is the child's (a terminal's Ctrl-C reaches both: the child takes
    it twice, and the first decides)."""
    global _FORWARDED
    with contextlib.suppress(OSError):
        os.kill(_CHILD, signum)
        if _FORWARDED is None and _BOARD is not None and _BOARD.q[STATE] == RUNNING:
            _FORWARDED = (signum, time.monotonic())


def spawn(board: Board, wake_r: int, relay_w: int, mode: str, conn: int | None = None) -> int:
    """A guardian process beside this one (a sweep's worker, a user's script); its pid. (No
    Popen: nothing waits for it, and a Popen left running warns at the interpreter's exit.)"""
    fds = [wake_r, relay_w, board.fd] + ([conn] if conn is not None else [])
    args = [sys.executable, "-I", "-S", os.path.abspath(__file__), str(os.getpid()), mode,
            *(str(fd) for fd in fds)]
    was = [os.get_inheritable(fd) for fd in fds]
    try:
        for fd in fds:
            os.set_inheritable(fd, True)
        return os.posix_spawn(sys.executable, args, os.environ, file_actions=[
            (os.POSIX_SPAWN_OPEN, 0, os.devnull, os.O_RDONLY, 0)])
    finally:
        for fd, inheritable in zip(fds, was):
            os.set_inheritable(fd, inheritable)


def _main(argv: list[str]) -> None:
    target, mode, wake, relay, board_fd, *rest = argv
    signal.signal(signal.SIGINT, signal.SIG_IGN)     # a terminal's Ctrl-C is the run's to answer
    die_with_parent()
    if os.getppid() != int(target):
        return
    serve(Board(int(board_fd)), int(wake), int(relay), int(target), mode,
          int(rest[0]) if rest else None)


if __name__ == "__main__":
    _main(sys.argv[1:])
