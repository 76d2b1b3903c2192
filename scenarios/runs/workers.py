"""Worker processes for a sweep, one point at a time each, tied to the main process's life.

concurrent.futures' process pool cannot say which point a dead worker was running: one worker
killed (as the out-of-memory killer does) breaks the whole pool and every pending point with it.
Here each worker holds one point at a time through its own pipe, so a worker that dies is one
failed point, with the cause (its signal or exit status), and a fresh worker takes the next.

A worker ends with the main process however that ends, a kill -9 too, and even while an FMU's
code holds the worker's interpreter lock (no thread of the worker can run then): each worker
holds the read end of a pipe ("life") whose write end only the main process has, and asks the
kernel (O_ASYNC, F_SETSIG) for SIGKILL when it closes, which it does when the main process ends.
(The forkserver cannot be relied on: every worker holds its "alive" pipe, so it outlives the main
process as long as a worker does.) A watchdog thread that checks the main process still exists
stands in where the kernel has no F_SETSIG.
Workers ignore Ctrl-C: the terminal sends it to the whole process group, and the main process
decides what an interruption stops (it terminates the workers, all at once: one stuck in an FMU
call ends by its watchdog, scenarios/cosim/watchdog.py, or is killed a second later). A point
whose step runs beyond experiment.step_timeout ends its worker too: the point fails with the
watchdog's line, and a fresh worker takes the next.
"""
from __future__ import annotations

import contextlib
import ctypes
import fcntl
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections import deque
from functools import partial
from multiprocessing.connection import wait
from typing import Callable, Iterable, Iterator

from sewfmu.processes import safe_path
from sewfmu.scenarios.cosim import watchdog
from sewfmu.scenarios.cosim.interrupt import Interrupted

_PR_SET_PDEATHSIG = 1
_F_SETSIG = getattr(fcntl, "F_SETSIG", 10)      # Linux's number; Python 3.11 does not name it
WATCHDOG_PERIOD = 0.5      # s between the worker's checks that the main process is alive
STOP_WAIT = 1.0            # s the workers have to end after SIGTERM before SIGKILL


class WorkerDied(RuntimeError):
    """The worker process running a task ended before it answered."""


def _end_with(main_pid: int, life) -> None:
    """Make this worker end when the main process does: SIGKILL from the kernel when the main
    process's end of `life` closes (no thread of this process needs to run)."""
    try:                      # Linux: SIGKILL when the parent (forkserver) goes
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    except (OSError, AttributeError):
        pass
    try:
        fd = life.fileno()
        fcntl.fcntl(fd, fcntl.F_SETOWN, os.getpid())
        fcntl.fcntl(fd, _F_SETSIG, signal.SIGKILL)
        fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL) | os.O_ASYNC)
        if os.getppid() == 1 or not _alive(main_pid):      # gone before the request
            os._exit(1)
    except (OSError, AttributeError):
        pass

    def watch():
        while True:
            time.sleep(WATCHDOG_PERIOD)
            try:
                os.kill(main_pid, 0)
            except ProcessLookupError:
                os._exit(1)
            except PermissionError:
                pass

    threading.Thread(target=watch, name="sewfmu-watchdog", daemon=True).start()


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass
    return True


def forkserver_context(preload) -> multiprocessing.context.BaseContext:
    """The forkserver context, its server started with Ctrl-C ignored: a new Python process
    interrupted while it starts prints a "Fatal Python error" traceback, and a terminal's Ctrl-C
    reaches the whole process group. An ignored signal stays ignored through exec, so the server
    and every worker it forks ignore it (the main process ends them itself); a Ctrl-C to the
    main process in the few milliseconds of the server's start is lost (pressed again, it
    counts). The server starts in safe-path mode (sewfmu/processes.py): nothing it or a worker
    imports comes from the current folder."""
    from multiprocessing import forkserver  # with the context: where its server is started

    context = multiprocessing.get_context("forkserver")
    if preload:
        context.set_forkserver_preload(list(preload))
    handler = signal.signal(signal.SIGINT, signal.SIG_IGN)     # inherited through exec
    try:
        with safe_path():
            forkserver.ensure_running()
    finally:
        signal.signal(signal.SIGINT, handler)
    return context


def _serve(conn, main_pid: int, life) -> None:
    """A worker's life: run tasks from the pipe until told to stop or the pipe closes."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _end_with(main_pid, life)
    watchdog.end_process_with(partial(_end_stuck, conn))
    # a point whose FMU holds the GIL beyond step_timeout: its guardian tells the main process
    watchdog.guard_mode("worker", conn.fileno())
    while True:
        try:
            task = conn.recv()
        except (EOFError, OSError):
            return
        if task is None:
            return
        func, args = task
        global _doing
        _doing = next((str(a.label) for a in args if hasattr(a, "label")), None)
        try:
            answer = ("ok", func(*args))
        except Exception as err:          # the task's own failure, reported as such
            answer = ("error", f"{type(err).__name__}: {err}")
        except KeyboardInterrupt:         # SIGTERM from the main process (see interrupt.py)
            return
        conn.send(answer)


def _end_stuck(conn, err: BaseException) -> None:
    """The watchdog's way out of a point stuck in an FMU call: a step beyond step_timeout is the
    point's failure, told to the main process (which takes a fresh worker); an interruption is
    the main process ending this worker, and told nothing. The worker ends at once."""
    with contextlib.suppress(Exception):
        if not isinstance(err, Interrupted):
            conn.send(("died", " ".join(str(err).split())))
        elif err.where:                  # where the point was stuck, for the sweep's line
            conn.send(("stopped", f"{err.where}{f' (point {_doing})' if _doing else ''}"))
    os._exit(err.exit_status if isinstance(err, Interrupted) else 1)


_doing: str | None = None      # the label of the point this worker runs (a sweep's), if any


def describe_exit(exitcode: int | None) -> str:
    if exitcode is None:
        return "worker process vanished"
    if exitcode < 0:
        name = signal.Signals(-exitcode).name if -exitcode in signal.Signals._value2member_map_ \
            else f"signal {-exitcode}"
        hint = " (as the out-of-memory killer does)" if -exitcode == signal.SIGKILL else ""
        return f"worker process killed by {name}{hint}"
    return f"worker process exited with status {exitcode}"


@contextlib.contextmanager
def _main_script_hidden():
    """Start a worker without the user's script: multiprocessing would run the __main__ module
    again in every worker (a plain script without `if __name__ == "__main__":` would start its
    own sweep there). A worker runs only sewfmu's functions, so it needs none of the script."""
    main = sys.modules.get("__main__")
    saved = {name: getattr(main, name) for name in ("__file__", "__spec__")
             if main is not None and hasattr(main, name)}
    try:
        for name in saved:
            setattr(main, name, None) if name == "__spec__" else delattr(main, name)
        yield
    finally:
        for name, value in saved.items():
            setattr(main, name, value)


class _Worker:
    def __init__(self, context, main_pid: int):
        self.conn, child = context.Pipe()
        life, self.life = context.Pipe(duplex=False)     # only this process writes: never
        self.process = context.Process(target=_serve, args=(child, main_pid, life), daemon=True)
        with _main_script_hidden(), safe_path():     # a fork server that died starts anew here
            self.process.start()
        child.close()
        life.close()
        self.task = None

    def give(self, task) -> None:
        self.task = task
        self.conn.send((task[1], task[2]))

    def stop(self) -> None:
        stop_all([self])


def stop_all(workers: list[_Worker], wait_for: float = STOP_WAIT) -> list[str]:
    """End the workers: SIGTERM to all at once, SIGKILL to those still alive `wait_for` seconds
    later (one in an FMU call that never returns), so that they all end within that time.
    Returns where those stuck in an FMU call were (their watchdog's word)."""
    for worker in workers:
        if worker.process.is_alive():
            worker.process.terminate()
    deadline = time.monotonic() + wait_for
    for worker in workers:
        worker.process.join(max(0.0, deadline - time.monotonic()))
    stuck = []
    for worker in workers:
        if worker.process.is_alive():
            worker.process.kill()
            worker.process.join(wait_for)
        with contextlib.suppress(Exception):      # what it said before it ended
            while worker.conn.poll():
                said = worker.conn.recv()
                if said[0] == "stopped":
                    stuck.append(said[1])
        for end in (worker.conn, worker.life):    # (life: the kernel's SIGKILL to one left)
            with contextlib.suppress(OSError, ValueError):
                end.close()
    return stuck


class WorkerPool:
    """Worker processes, one task at a time each, tied to this process's life (they end with
    it), a dead one replaced while the others go on. A pool may be kept for many batches: a
    design study's global method would otherwise pay the workers' start and their first
    loading of the FMUs at every batch (1.7 to 2 s for two workers, measured on this project's
    2-core machine under load)."""

    def __init__(self, size: int, preload: list[str] = ()):
        self.size, self.preload = size, list(preload)
        self.workers: list[_Worker] = []
        self.context = None

    def run(self, tasks: Iterable[tuple[object, Callable, tuple]]) -> Iterator[tuple[object, object]]:
        """Run (key, func, args) tasks; yield (key, result) as each finishes, where result is
        func's return value, or an Exception: the task's own error as a RuntimeError, or
        WorkerDied. When the caller stops iterating (an interruption, an error), every worker
        is stopped."""
        queue = deque(tasks)
        if not queue:
            return
        if self.context is None:
            # forkserver: workers fork from a clean server process that has imported the preload
            # once, so they start fast and do not inherit this process's FMU libraries and threads
            self.context = forkserver_context(self.preload)
        while len(self.workers) < min(self.size, len(queue)):
            self.workers.append(_Worker(self.context, os.getpid()))
        try:
            for worker in self.workers:
                if queue:
                    worker.give(queue.popleft())
            while any(w.task is not None for w in self.workers):
                busy = [w for w in self.workers if w.task is not None]
                wait([w.conn for w in busy] + [w.process.sentinel for w in busy])
                for i, worker in enumerate(self.workers):
                    answer = _answer(worker) if worker.task is not None else None
                    if answer is None:
                        continue                     # idle, or still working
                    key, worker.task = worker.task[0], None
                    if isinstance(answer, WorkerDied):   # replace it, the others go on
                        worker.stop()
                        worker = self.workers[i] = _Worker(self.context, os.getpid())
                    if queue:
                        worker.give(queue.popleft())
                    yield key, answer
        except BaseException as err:                 # Ctrl-C, or the caller gave up
            stuck = self.close()
            if isinstance(err, Interrupted) and stuck and not err.where:
                more = len(stuck) - 1
                err.where = stuck[0] + (f", and {more} other point{'s' * (more > 1)} stuck"
                                        if more else "")
            raise

    def close(self) -> list[str]:
        """Stop every worker; where those stuck in an FMU call were."""
        stuck = stop_all(self.workers)          # all at once: each may be stuck in an FMU call
        self.workers = []
        return stuck


def run_tasks(tasks: Iterable[tuple[object, Callable, tuple]], workers: int,
              preload: list[str] = ()) -> Iterator[tuple[object, object]]:
    """One batch of tasks on a pool of its own (WorkerPool.run), stopped when it ends."""
    pool = WorkerPool(workers, preload)
    try:
        yield from pool.run(tasks)
    finally:
        pool.close()


def _answer(worker: _Worker):
    """The worker's answer if it has one, WorkerDied if it died without one, else None."""
    alive = worker.process.is_alive()         # asked first: an answer sent before dying counts
    try:
        if worker.conn.poll():
            status, value = worker.conn.recv()
            if status == "died":                  # its watchdog's line: the worker is ending
                return WorkerDied(value)
            return value if status == "ok" else RuntimeError(value)
    except (EOFError, OSError):
        alive = False                         # the pipe broke: the process is gone
    if alive:
        return None
    worker.process.join(5)
    return WorkerDied(describe_exit(worker.process.exitcode))
