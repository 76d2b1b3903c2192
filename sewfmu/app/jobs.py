"""The page's jobs: each run or sweep in a process of its own, known by a random id that only the
tab that started it holds; what the process tells (progress, points, the result) is kept here,
on the server, until the app ends. Nothing is shared between tabs but this table, and a tab can
read only the jobs whose ids it was given.

Processes come from a fork server that has loaded the API once (multiprocessing's forkserver
context), so that a run starts in milliseconds and not in the seconds of importing numpy and
fmpy; where there is none (not Linux), from spawn. A run's process is kept ready before its run
(a spare, warmed on the scenario run last: worker.standby), and the next one made when that run
ends, so that only a warm run stands between Run and the figures. Cancel ends the job's process
group: a sweep's workers with it. Every process starts in safe-path mode (sewfmu/processes.py):
the fork server, its children and a spawned process import nothing from the current folder."""
from __future__ import annotations

import multiprocessing
import os
import secrets
import signal
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import sewfmu
from sewfmu.app.worker import main as work
from sewfmu.app.worker import standby
from sewfmu.processes import safe_path

ENDING = 3.0            # s a job's process is given after SIGTERM before SIGKILL
# jobs running at once, over all tabs and clients: more would only share the cores (a sweep uses
# them all) and let one client (a script posting Run) take the machine
MAX_RUNNING = max(2, os.cpu_count() or 1)


class Busy(sewfmu.Error):
    """As many jobs as the app runs at once are running."""


@dataclass
class Job:
    id: str
    kind: str                       # "run" or "sweep"
    request: dict                   # what the tab asked (scenario, changed values, grid)
    process: object = None
    status: str = "running"         # running, done, error, cancelled
    done: int = 0                   # communication steps (run) or points (sweep) done
    total: int = 0
    result: dict | None = None
    error: str | None = None
    points: list = field(default_factory=list)
    report: str | None = None       # the job making this run's report.html, once asked
    started: float = field(default_factory=time.monotonic)
    finished: float | None = None
    ended: threading.Event = field(default_factory=threading.Event)   # its process is gone
    settled: threading.Event = field(default_factory=threading.Event)  # its result or error is in

    @property
    def fraction(self) -> float:
        if self.status == "done":
            return 1.0
        return min(1.0, self.done / self.total) if self.total else 0.0


def _context():
    methods = multiprocessing.get_all_start_methods()
    if "forkserver" in methods:
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["sewfmu.app.worker"])
        return ctx
    return multiprocessing.get_context("spawn")


class Jobs:
    """`check(kind, request)`, if given, is asked before a job's process starts: a sewfmu.Error
    it raises is the job refused, nothing started."""

    def __init__(self, root: Path, warm: str | None = None, check=None):
        self.root = Path(root)
        self.check = check
        self._jobs: dict[str, Job] = {}
        self._lock = threading.Lock()
        self._ctx = _context()
        self._closed = False
        self._spare = None              # (process, pipe) of the run process kept ready
        if warm is not None:
            threading.Thread(target=self.prepare, args=(warm,), daemon=True,
                             name="spare").start()

    def prepare(self, warm: str) -> None:
        """A run's process ready for the next run, warmed on the scenario `warm`, unless one is."""
        with self._lock:
            if self._closed or (self._spare is not None and self._spare[0].is_alive()):
                return
            here, there = self._ctx.Pipe()
            process = self._ctx.Process(target=standby, args=(warm, there),
                                        name="sewfmu-app-spare")
            with safe_path():       # the fork server starts with the first process
                process.start()
            self._spare = (process, here)
        there.close()

    def _take_spare(self):
        """The ready process and its pipe (the caller holds the lock), or None."""
        spare, self._spare = self._spare, None
        if spare is not None and spare[0].is_alive():
            return spare
        if spare is not None:
            spare[1].close()
            spare[0].join(0)
        return None

    def start(self, kind: str, request: dict, folder: str | None = None) -> str:
        """A new job; its files under root/<its id>, or root/<folder> (a run's report)."""
        if self.check is not None:
            self.check(kind, request)
        job_id = secrets.token_hex(8)
        job = Job(job_id, kind, request, total=len(request.get("points", [])) or 0)
        where = str(self.root / (folder or job_id))
        with self._lock:
            if self._closed:
                raise RuntimeError("the app is ending")
            running = sum(1 for j in self._jobs.values() if not j.ended.is_set())
            if running >= MAX_RUNNING:
                raise Busy(f"{running} runs or sweeps are going already, the most this app runs "
                           f"at once: wait for one to end, or Cancel one")
            spare = self._take_spare() if kind == "run" else None
            if spare is not None:
                try:
                    spare[1].send((kind, request, where))
                    job.process, receive = spare
                except OSError:             # it ended meanwhile (killed from outside)
                    spare[1].close()
                    spare = None
            if spare is None:
                receive, send = self._ctx.Pipe(duplex=False)
                job.process = self._ctx.Process(target=work, name=f"sewfmu-app-{kind}-{job_id}",
                                                args=(kind, request, where, send))
                with safe_path():
                    job.process.start()
                send.close()
            self._jobs[job_id] = job
        threading.Thread(target=self._listen, args=(job, receive), daemon=True,
                         name=f"listen-{job_id}").start()
        return job_id

    def get(self, job_id) -> Job | None:
        return self._jobs.get(job_id) if isinstance(job_id, str) else None

    def _listen(self, job: Job, conn) -> None:
        """Everything the job's process says, until its pipe closes."""
        while True:
            try:
                message = conn.recv()
            except (EOFError, OSError):
                break
            what, *body = message
            if what == "progress":
                job.done, job.total = body
            elif what == "point":
                job.points.append(body[0])
                job.done = len(job.points)
            elif what == "done":
                job.result, job.status, job.finished = body[0], "done", time.monotonic()
                job.settled.set()
            elif what == "error":
                if job.status != "cancelled":
                    job.error, job.status = body[0], "error"
                job.settled.set()
        conn.close()
        job.process.join()              # here only: one thread waits for a process
        job.ended.set()
        if job.status == "running":
            job.status = "error"
            job.error = f"the run's process ended without a result (exit code " \
                        f"{job.process.exitcode})"
        job.settled.set()
        if job.kind == "run":           # the next run's process, warmed on this scenario
            self.prepare(job.request["source"])

    def cancel(self, job_id) -> bool:
        job = self.get(job_id)
        if job is None or job.process is None:
            return False
        if job.status == "running":
            job.status = "cancelled"
        _end(job)
        return True

    def shutdown(self) -> None:
        """End every job's process (and its group) and wait for each."""
        with self._lock:
            self._closed = True
            jobs = list(self._jobs.values())
            spare, self._spare = self._spare, None
        if spare is not None:
            _kill_group(spare[0].pid, signal.SIGKILL)    # it holds no run: nothing half-written
            spare[0].join(ENDING)
            spare[1].close()
        for job in jobs:
            if job.process is not None and not job.ended.is_set():
                if job.status == "running":
                    job.status = "cancelled"
                _end(job)


def _end(job: Job) -> None:
    """SIGTERM to the job's process group, SIGKILL to what is left after ENDING seconds."""
    pid = job.process.pid
    for sig in (signal.SIGTERM, signal.SIGKILL):
        if job.ended.is_set():
            break
        _kill_group(pid, sig)
        job.ended.wait(ENDING)
    _kill_group(pid, signal.SIGKILL)           # a sweep's workers left behind, if any


def _kill_group(pid: int, sig) -> None:
    try:
        os.killpg(pid, sig)
    except (ProcessLookupError, PermissionError):
        try:
            os.kill(pid, sig)
        except (ProcessLookupError, PermissionError):
            pass
