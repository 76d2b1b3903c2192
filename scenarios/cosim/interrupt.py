"""Ctrl-C and SIGTERM as an interruption, never as an FMU failure.

The FMUs' Python code runs in this process's interpreter (pythonfmu embeds it), so a
KeyboardInterrupt raised by Python's default SIGINT handler lands, most of the time, inside an
FMU's doStep; pythonfmu answers it with fmi2Fatal and the run would end as "shaft failed during
step". Within `deferred()` the signals only mark the interruption; the master raises it between
communication steps (`raise_pending`), where no FMU code runs and every instance can still be
freed. Outside of it (reading, writing, plotting) the CLI lets SIGTERM interrupt like Ctrl-C.
A call that never returns would keep the interruption waiting for ever: cosim/watchdog.py ends
the run then. A signal the process ignores (a sweep's workers ignore Ctrl-C: their main process
decides) stays ignored.
"""
from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time

SIGNALS = (signal.SIGINT, signal.SIGTERM)

pending: list[int] = []         # signals received within deferred(), oldest first
board = None                    # the watched run's guardian.Board (watchdog.py), or None
_installed: list[dict] = []     # per deferred() block: the handlers it installed, and replaced
_own = False                    # interrupt_on_signals() made SIGINT and SIGTERM sewfmu's
# the signal of the interruption under way in sewfmu's own process: the first decides, and a
# later one (a second Ctrl-C while the record is written) is not raised over it
under_way: int | None = None
_current: "Interrupted | None" = None   # the exception raised for it, and when
_since = 0.0
_marked_at: list[float] = []    # when each of `pending` came
# s: two signals this close may have been sent in either order: both were pending together, and
# the kernel delivers the lower number (SIGINT) first whatever the order they were sent in; then
# SIGTERM, the request to end, decides (a supervisor's `kill -TERM; kill -INT` is 143)
SAME_INSTANT = 0.05


class Interrupted(KeyboardInterrupt):
    """The run was interrupted by a signal; exit status 128 + the signal's number.

    `where` says where the run was ("at t = 0.25 s", "while motor was in doStep at t = 0.25 s"),
    `result` is what it had recorded (a RunResult, or None before its first record) and `kept`
    where a front door wrote that record ("the record up to t = … s is in …")."""

    def __init__(self, signum: int = signal.SIGINT, where: str = ""):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum
        self.where = where
        self.result = None
        self.run = None           # the record so far as a sewfmu.Run (sewfmu.run sets it)
        self.kept: str | None = None

    @property
    def exit_status(self) -> int:
        return 128 + self.signum

    @property
    def reason(self) -> str:
        """What happened, as a line says it: `interrupted (SIGINT) at t = 0.25 s`."""
        return f"interrupted ({self.args[0]}){' ' + self.where if self.where else ''}"


def raise_pending() -> None:
    """Act on the first signal received (the first decides): a user's own handler that
    deferred() replaced is called now, between two steps (it may stop the run by raising, or let
    it go on); otherwise Interrupted."""
    if pending:
        signum = pending[0]
        if signum == signal.SIGINT and signal.SIGTERM in pending and \
                _marked_at[pending.index(signal.SIGTERM)] - _marked_at[0] < SAME_INSTANT:
            signum = signal.SIGTERM
        pending.clear()
        _marked_at.clear()
        if board is not None:                 # answered: the guardian need not step in
            board.q[4] = board.q[3]           # guardian.ANSWERED = RELAYED
        replaced = _installed[-1]["replaced"].get(signum) if _installed else None
        if callable(replaced) and replaced not in (_interrupt, signal.default_int_handler):
            replaced(signum, None)
            return
        _raising(signum)


def _raising(signum: int):
    """Raise the interruption by `signum`; in sewfmu's own process it is the one under way."""
    global under_way, _current, _since
    err = Interrupted(signum)
    if _own and under_way is None:
        under_way, _current, _since = signum, err, time.monotonic()
    raise err


def _later(signum: int) -> None:
    """A signal while an interruption is under way: it does not decide, unless it is a SIGTERM
    at the same instant as the SIGINT under way (SAME_INSTANT)."""
    global under_way
    if signum == signal.SIGTERM and under_way == signal.SIGINT and _current is not None and \
            time.monotonic() - _since < SAME_INSTANT:
        under_way = signum
        _current.signum, _current.args = signum, (signal.Signals(signum).name,)


def settled() -> None:
    """The interruption under way has been said (main() called by a process that goes on)."""
    global under_way, _current
    pending.clear()
    _marked_at.clear()
    under_way, _current = None, None


def _mark(signum, frame) -> None:
    if under_way is not None:
        _later(signum)
        return
    pending.append(signum)
    _marked_at.append(time.monotonic())


def _interrupt(signum, frame) -> None:
    # noted before it is raised: raised where Python ignores exceptions (a weakref callback of
    # an import, a __del__: "Exception ignored in ...") it would be lost, and a run started next
    # would go on; deferred() raises it again
    if under_way is not None:        # one is being answered (its record written): it decides
        _later(signum)
        return
    pending.append(signum)
    _marked_at.append(time.monotonic())
    _raising(signum)


def interrupt_on_signals() -> None:
    """SIGINT and SIGTERM raise Interrupted (SIGTERM's default would end the process without
    cleaning up: staging folders, worker processes); one raised where Python drops exceptions
    is raised again when the next run starts."""
    global _own
    if threading.current_thread() is threading.main_thread():
        _own = True
        for s in SIGNALS:
            signal.signal(s, _interrupt)
        if not getattr(sys.unraisablehook, "keeps_interruptions", False):
            sys.unraisablehook = _quiet(sys.unraisablehook)


def _quiet(hook):
    """An unraisable-exception hook that says nothing of an Interrupted Python dropped (pending
    holds it: the one line comes when it is raised again), and passes anything else on."""
    def keep(unraisable) -> None:
        if not isinstance(unraisable.exc_value, Interrupted):
            hook(unraisable)
    keep.keeps_interruptions = True
    return keep


@contextlib.contextmanager
def deferred():
    """Within the block SIGINT and SIGTERM only mark the interruption; it is raised by
    `raise_pending()`, or when the block ends."""
    if threading.current_thread() is not threading.main_thread():
        yield                    # signal handlers belong to the main thread
        return
    raise_pending()              # one received before, and lost where it was raised
    global under_way, _current
    under_way, _current = None, None   # a new run: an interruption before it was answered
    previous = {s: signal.getsignal(s) for s in SIGNALS}
    mine = {s: _mark for s in SIGNALS if previous[s] is not signal.SIG_IGN}   # ignored stays so
    _installed.append({"mine": mine, "replaced": previous})
    for s, handler in mine.items():
        signal.signal(s, handler)
    try:
        yield
        _installed.pop()
        for s, handler in previous.items():
            signal.signal(s, handler)
        raise_pending()
    except Interrupted as err:
        if _installed and _installed[-1]["mine"] is mine:
            _installed.pop()
        for s, handler in previous.items():
            signal.signal(s, handler)
        if err.signum == signal.SIGTERM and previous[signal.SIGTERM] is signal.SIG_DFL:
            # a process that left SIGTERM at its default (a user's script) ends as that default
            # ends it, now that the run is cleaned up: a KeyboardInterrupt would let it go on
            signal.pthread_sigmask(signal.SIG_UNBLOCK, [signal.SIGTERM])
            os.kill(os.getpid(), signal.SIGTERM)
        raise
    except BaseException:
        if _installed and _installed[-1]["mine"] is mine:
            _installed.pop()
        for s, handler in previous.items():
            signal.signal(s, handler)
        raise


def keep_handlers() -> None:
    """Put sewfmu's handlers back: an FMU may set its own (or ignore SIGINT) while it is
    instantiated, and Ctrl-C would then do nothing. Called after every instantiate."""
    if threading.current_thread() is not threading.main_thread():
        return
    handlers = _installed[-1]["mine"] if _installed else \
        ({s: _interrupt for s in SIGNALS} if _own else {})
    for s, handler in handlers.items():
        signal.signal(s, handler)           # also where C code changed it behind Python's back
