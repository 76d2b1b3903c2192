"""The run loop: one scenario stepped to its end by its algorithm, as libcosim splits a run into
execution, algorithm and observer.

- the instances: cosim/instances.py (one adapter per FMI version), connected and checked by
  cosim/system.py;
- the algorithm: how one communication step exchanges and steps (cosim/algorithms/: the
  interface base.py, one module per master, the names in its __init__), with its typed settings;
- this loop: loading and initializing the instances in dependency order, the clock (whole even
  steps, or the steps a variable-step algorithm takes), one recorder (cosim/recorder.py), one
  rollback (cosim/rollback.py), progress, Ctrl-C, failure reports naming the FMU, the time and
  its log, and freeing every instance whatever happens.
"""
from __future__ import annotations

import contextlib
import operator
import threading
import time as clock
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np

from sewfmu.scenarios.cosim import interrupt, stepper, watchdog
from sewfmu.scenarios.cosim.algorithms import ALGORITHMS
from sewfmu.scenarios.cosim.divergence import DivergenceWatch
from sewfmu.scenarios.cosim.fmi_calls import CosimError, FmiCallError, LogCollector, reason
from sewfmu.scenarios.cosim.instances import open_instance
from sewfmu.scenarios.cosim.recorder import Recorder
from sewfmu.scenarios.cosim.rollback import Rollback
from sewfmu.scenarios.cosim.system import System
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import ScenarioError

# the most work a run may mean: communication steps × FMU instances (about 25 µs each on a PC:
# 10^8 is some 40 minutes); beyond it a run is refused up front with its estimate
MAX_FMU_STEPS = 10**8
FMU_STEP_SECONDS = 25e-6


@dataclass
class RunResult:
    scenario: Scenario
    time: np.ndarray
    columns: dict[str, np.ndarray]
    wall_time: float
    log: list[str] = field(default_factory=list)
    coupling: dict = field(default_factory=dict)     # what the iterative or adaptive master did
    units: dict[str, str] = field(default_factory=dict)   # column -> its declared unit

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]


class Snapshot(NamedTuple):
    """A point of the run to come back to (Master.save_state)."""
    k: int
    t: float
    rows: int
    states: Rollback
    run: object            # the open run it was saved in: only that run comes back to it


def run(scenario: Scenario, fmu_paths: dict[str, Path], progress=None) -> RunResult:
    """Run the scenario with its experiment.master on these FMU files."""
    return Master(scenario, fmu_paths).run(progress)


def planned_steps(sc: Scenario) -> tuple[int, float]:
    """The run's whole even steps (n, h), or the ScenarioError of a run refused before anything
    loads: no step, a step longer than the run, more work than MAX_FMU_STEPS. sewfmu.check
    (runs/checks.py) asks it too, so that a run it passes is not refused at its start."""
    stop = sc.end_time()
    if not sc.step > 0:          # an SSP system that gives none
        raise ScenarioError(f"{sc.source}: no communication step: the file gives none; "
                            f"pass --set experiment.step=…")
    if sc.step > stop:
        raise ScenarioError(f"{sc.source}: experiment.step {sc.step:g} s is longer than the "
                            f"run ({stop:g} s)")
    n_steps, h = sc.even_steps()
    work = n_steps * max(1, len(sc.instances))
    if work > MAX_FMU_STEPS:
        hours = work * FMU_STEP_SECONDS / 3600
        raise ScenarioError(f"{sc.source}: {n_steps:.3g} communication steps of "
                            f"{len(sc.instances)} FMUs (end {stop:g} s at a step of "
                            f"{sc.step:g} s) are {work:.3g} FMU steps, about {hours:.3g} "
                            f"hours of stepping, more than the {MAX_FMU_STEPS:.0e} a run "
                            f"may take; take a longer experiment.step or a shorter run")
    return n_steps, h


class Master:
    """Runs one scenario with the algorithm its experiment.master names.

    `make_instance(declaration, log)`, if given, makes the instances instead of opening the FMU
    files (tests/fake_fmu.py: the loop and the algorithms tested without FMUs)."""

    # how often (in communication steps) the run reports its progress
    PROGRESS_EVERY = 1024

    def __init__(self, scenario: Scenario, fmu_paths: dict[str, Path], make_instance=None):
        self.scenario = scenario
        self.fmu_paths = fmu_paths
        self.make_instance = make_instance or self._open_fmu
        self.system: System | None = None
        self.algorithm = None
        self._snapshots: list[Snapshot] = []
        # the run now open (between a whole open() and close(): FMU calls may be made), or None
        self._run: object | None = None
        # held while FMUs are called on behalf of a caller, so that close() from another thread
        # waits for the call under way before it frees the instances
        self._calling = threading.RLock()
        self._closing = False        # close() asked from another thread: stop between two steps
        self._failed_at: float | None = None     # the time of a failed step not yet undone
        self.recorder: Recorder | None = None      # made by open(); read by result() after close
        self._compiled = None      # the compiled step loop of the open run (cosim/stepper.py)

    @property
    def instances(self) -> list:
        return self.system.instances if self.system else []

    # --- the run -------------------------------------------------------------------------------
    def run(self, progress=None) -> RunResult:
        """Open, step to the end, close: the whole scenario. `progress(done, total)`, if given,
        hears of the steps done every PROGRESS_EVERY steps and at the end. Ctrl-C or SIGTERM
        interrupt the run between two communication steps (interrupt.Interrupted), never inside
        an FMU."""
        started = clock.perf_counter()
        every = self.PROGRESS_EVERY
        try:
            # a call that never returns is the watchdog's (cosim/watchdog.py)
            with interrupt.deferred(), watchdog.watching(self), self:
                while not self.finished():
                    self.steps(every - self.k % every)        # up to the next report
                    if progress is not None and (self.k % every == 0 or self.finished()):
                        progress(*self.progress_point())
                result = self.result()
        except interrupt.Interrupted as err:
            if err.result is None and not err.where:        # where it stopped, what it kept
                opened = self.recorder is not None
                err.where = f"at t = {self.t:g} s" if opened else "while loading the FMUs"
                err.result = self.result() if opened and self.recorder.length else None
            raise
        result.wall_time = clock.perf_counter() - started
        return result

    def finished(self) -> bool:
        self._require_opened("finished")
        if self.algorithm.variable_step:
            return self.t >= self.stop * (1 - 1e-12)
        return self.k >= self.n_steps

    def progress_point(self) -> tuple[int, int]:
        """(done, total) for a progress report: communication steps, or thousandths of the run
        where the algorithm sizes its steps."""
        self._require_opened("progress_point")
        if self.algorithm.variable_step:
            return int(1000 * self.t / self.stop), 1000
        return self.k, self.n_steps

    def __enter__(self) -> "Master":
        with self._calling:         # another thread's opening or closing waits for this one
            self._refuse_second_opening()
            try:
                self.open()
            except BaseException:
                self.close()        # instances initialized before the failure are freed
                raise
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def open(self) -> None:
        """Check the experiment, load and connect the FMUs, initialize them in dependency order,
        record the initial point."""
        with self._calling:
            self._refuse_second_opening()
            self._failed_at = None
            self._open()

    def _open(self) -> None:
        sc = self.scenario
        self.stop = sc.end_time()
        self.n_steps, self.h = planned_steps(sc)
        # a setting the master cannot honour is refused here, before any FMU is loaded
        self.algorithm = algorithm = ALGORITHMS[sc.master](sc.settings())
        self.every = max(1, int(sc.record_every))
        self.log = LogCollector()
        self.k, self.t = 0, 0.0
        self._phase = "loading"
        with self._reporting():
            self.system = system = System(sc, self.make_instance, self.log)
            algorithm.plan(system)
            system.plan_records()
            self._phase = "initialization"
            # where the run is, for the guardian of a process whose FMU holds the GIL
            paper = watchdog.board()
            paper.names([inst.name for inst in system.instances])
            for slot, inst in enumerate(system.instances):
                inst.note(paper.q, slot)
            for inst in system.instances:
                # a signal while the FMUs load stops the run between two of them
                interrupt.raise_pending()
                inst.may_roll_back = algorithm.rolls_back
                self._initialize(inst)
            # around a loop the first instance initialized took its partners' outputs before
            # they had any: each takes them again now, as at the end of a step
            system.settle_loops()
        explicit = not (algorithm.rolls_back or algorithm.variable_step)
        self.watch = DivergenceWatch(
            system.in_loops, self.h, explicit,
            {name: inst.parameters for name, inst in sc.instances.items()}) \
            if system.in_loops else None
        algorithm.start(system, sc.step)
        # record_every thins the records, but every step is kept from one step before the last
        # whole revolution on (the analyses' window; a scenario without a shaft has none, and
        # with record_every = 1 every step is kept anyway)
        window = sc.last_revolution_start() if self.every > 1 else None
        if window is None:
            window = 2 * self.stop                   # after the end: no window
        if algorithm.variable_step:
            rows = None
            self.dense_k, self.dense_t = None, window - sc.step
        else:
            self.dense_k, self.dense_t = max(0, int(window / self.h) - 1), None
            rows = (self.n_steps // self.every + 1 + (self.n_steps % self.every != 0)
                    + max(0, self.n_steps - self.dense_k))
        # kept at every step whatever record_every: the last revolution (for the advice)
        last = sc.last_revolution_start()
        dense = 0 if last is None else max(0, self.n_steps - int(last / self.h) + 1)
        self.recorder = Recorder(system.columns, system.plan, rows, sc.source,
                                 None if rows is None else (self.n_steps, self.every, dense),
                                 outputs=system.outputs)
        self.recorder.record(0.0)
        self._compiled = stepper.compiled_loop(self)
        self._phase = "step"
        self._run = object()

    def step(self) -> None:
        """One communication step: n_steps even steps of h end exactly at the stop time; a
        variable-step algorithm ends its last step there."""
        self.steps(1, "step")

    def steps(self, count: int, _call: str = "steps") -> None:
        """Up to `count` communication steps (fewer where the run ends). A signal received
        within interrupt.deferred() stops them between two steps (interrupt.Interrupted)."""
        self._require_open(_call)
        try:
            count = operator.index(count)
        except TypeError:
            raise ScenarioError(f"Master.{_call}({count!r}): the number of steps is a whole "
                                f"number") from None
        if count < 0:
            raise ScenarioError(f"Master.{_call}({count}): the number of steps cannot be "
                                f"negative")
        with self._calling:
            self._require_open(_call)          # closed by another thread while this one waited
            self._refuse_after_failure(_call)
            if self.algorithm.variable_step:
                self._variable_steps(count)
            else:
                self._fixed_steps(count)

    def _variable_steps(self, count: int) -> None:
        for _ in range(count):
            if self.finished():
                break
            self._variable_step()
            if interrupt.pending:
                interrupt.raise_pending()
            if self._closing:                  # close() asked from another thread
                self._require_open("steps")

    def _fixed_steps(self, count: int) -> None:
        # the fixed-step loop, what it uses bound once: the hot path of every run
        advance, system, h, n, stop = (self.algorithm.advance, self.system, self.h,
                                       self.n_steps, self.stop)
        watch, record, every, dense_k = self.watch, self.recorder.record, self.every, self.dense_k
        paper = watchdog.board()
        beat, now = paper.q, paper.d        # a beat and the time per step: ~0.1 µs
        k = self.k
        end = min(n, k + count)
        if self._compiled is not None:         # the same steps in C (cosim/stepper.py)
            return self._compiled_steps(end, paper)
        while k < end:
            t = k * h
            beat[1] += 1                       # guardian.BEAT
            now[8] = t                         # guardian.T
            if self._closing:                  # close() asked from another thread
                self._require_open("steps")
            try:                   # (no context manager here: this is the hot path)
                advance(system, t, h)
            except FmiCallError as err:
                self._failed_at = t
                raise self._failure(err, err.when or f"from t = {t:g} to {t + h:g} s") from None
            k += 1
            self.k = k
            # n_steps even steps of h end exactly at the stop time
            self.t = t = stop if k == n else k * h
            if watch is not None:
                watch.check(t)
            if k % every == 0 or k >= dense_k or k == n:
                record(t)
            if interrupt.pending:
                interrupt.raise_pending()

    def _compiled_steps(self, end: int, paper) -> None:
        """_fixed_steps through the compiled loop, in chunks of stepper.CHUNK steps: between
        two, what the loop above does between two steps."""
        h, n = self.h, self.n_steps
        while self.k < end:
            if self._closing:
                self._require_open("steps")
            k, err = self._compiled.steps(self.k, min(end, self.k + stepper.CHUNK), paper)
            self.k = k
            self.t = self.stop if k == n else k * h
            if err is not None:
                self._failed_at = t = k * h
                raise self._failure(err, err.when or f"from t = {t:g} to {t + h:g} s") from None
            if interrupt.pending:
                interrupt.raise_pending()

    def _variable_step(self) -> None:
        """One step of an algorithm that sizes its own: it ends its last step at the stop time."""
        t = self.t
        limit = self.stop - t
        paper = watchdog.board()
        paper.q[1] += 1                        # guardian.BEAT
        paper.d[8] = t                         # guardian.T
        try:
            taken = self.algorithm.advance(self.system, t, limit)
        except FmiCallError as err:
            self._failed_at = t
            raise self._failure(err, err.when or f"from t = {t:g} to {t + limit:g} s") from None
        self.k += 1
        self.t = t + taken if t + taken < self.stop * (1 - 1e-12) else self.stop
        if self.watch is not None:
            self.watch.check(self.t)
        if self.t >= self.dense_t or self.finished() or self.k % self.every == 0:
            self.recorder.record(self.t)

    def _require_open(self, call: str) -> None:
        """Refuse a call that would reach the FMUs before the run is opened or after it is
        closed (its instances freed: a call on them is undefined, a crash with pythonfmu's)."""
        if self._run is None or self._closing:
            raise CosimError(f"Master.{call}(): the run is not open: call it within "
                             f"`with Master(scenario, fmus) as master:`")

    def _refuse_after_failure(self, call: str) -> None:
        """After a failed step the FMUs are part-way through it: only a state saved before it
        (or a new opening) gives a run to go on from."""
        if self._failed_at is not None:
            raise CosimError(f"Master.{call}(): a step from t = {self._failed_at:g} s failed; "
                             f"the run goes on only from a state saved before it "
                             f"(restore_state) or opened again")

    def _refuse_second_opening(self) -> None:
        """A run open already (a `with` inside its own `with`, run() within it) would be
        restarted from zero and its instances never freed: refused."""
        if self._run is not None:
            raise CosimError("Master.open(): the run is open already: one Master runs one "
                             "run at a time (make another Master for another)")

    def _require_opened(self, call: str) -> None:
        """Refuse a question about the run before it has been opened (after it closed, what it
        recorded and how far it came stand)."""
        if self.recorder is None:
            raise CosimError(f"Master.{call}(): the run has not been opened: call it within or "
                             f"after `with Master(scenario, fmus) as master:`")

    def save_state(self) -> Snapshot:
        """The state of every FMU and of the run: `restore_state` comes back to it."""
        self._require_open("save_state")
        with self._calling:
            self._require_open("save_state")
            self._refuse_after_failure("save_state")
            states = Rollback(self.instances)
            self._snapshots.append(states)
            with self._reporting(self.t):
                states.save()
            return Snapshot(self.k, self.t, self.recorder.length, states, self._run)

    def restore_state(self, snapshot: Snapshot) -> None:
        self._require_open("restore_state")
        # another run's FMU states are not this run's FMUs' (another Master's, or this one's
        # before it was closed and opened again: freed at its close)
        if getattr(snapshot, "run", None) is not self._run:
            raise CosimError("Master.restore_state(): that snapshot was not saved in this open "
                             "run (a run comes back only to its own save_state())")
        with self._calling:
            self._require_open("restore_state")
            fatal = [inst.name for inst in self.instances if inst.failed]
            if fatal:
                raise CosimError(f"Master.restore_state(): {fatal[0]} failed fatally, after "
                                 f"which FMI allows no call on it: the run can only be opened "
                                 f"again")
            self.k, self.t = snapshot.k, snapshot.t
            self.recorder.truncate(snapshot.rows)
            with self._reporting(self.t):
                snapshot.states.restore()
            self._failed_at = None

    def result(self) -> RunResult:
        self._require_opened("result")
        time, columns = self.recorder.arrays()
        coupling, warnings = self.algorithm.report(self.k)
        return RunResult(self.scenario, time, columns, 0.0, self.log.lines + warnings,
                         coupling, dict(self.system.units))

    def close(self) -> None:
        self._closing = True               # a stepping thread stops between two steps
        with self._calling:                # a call under way in another thread ends first
            self._run = None
            self._closing = False
            self._free()

    def _free(self) -> None:
        self._compiled = None          # it points into the instances' buffers
        if self.algorithm is not None:
            self.algorithm.close()
        while self._snapshots:
            self._snapshots.pop().free()
        for inst in self.instances:
            # after a Fatal call FMI allows no further call on that instance (pythonfmu
            # reports every Python exception as fmi2Fatal and has already dropped its objects)
            if inst.instantiated and not inst.failed:
                inst.release()

    # --- pieces of the run ---------------------------------------------------------------------
    def _open_fmu(self, declaration, log: LogCollector):
        if declaration.fmu not in self.fmu_paths:
            raise ScenarioError(f"{self.scenario.source}: instances.{declaration.name}: unknown "
                                f"FMU {declaration.fmu!r}")
        return open_instance(declaration.name, self.fmu_paths[declaration.fmu], log)

    def _initialize(self, inst) -> None:
        """Instantiate, set parameters, take inputs from the already initialized sources."""
        inst.instantiate()
        inst.enter_initialization(self.stop)
        for key, value in self.scenario.instances[inst.name].parameters.items():
            inst.set_parameter(inst.variables[key], value)
        inst.pull_inputs()
        inst.exit_initialization()
        # sewfmu's FMUs answer bad parameters at exitInitializationMode with an Error log line
        # (and refuse every step), not with Fatal: stop here, naming the cause
        errors = self.log.errors_of(inst.name)
        if errors:
            raise CosimError(f"{inst.name} failed during initialization at t = 0 s: "
                             f"{reason(errors, None)}")
        inst.read_outputs()

    @contextlib.contextmanager
    def _reporting(self, t: float = 0.0):
        """Turn a failed FMI call into a CosimError naming the FMU, the time and its log."""
        try:
            yield
        except FmiCallError as err:
            raise self._failure(err, f"at t = {t:g} s") from None

    def _failure(self, err: FmiCallError, when: str) -> CosimError:
        failed = [i for i in self.instances if i.failed]
        inst = err.instance or (failed[0] if failed else None)
        who = inst.name if inst else "an FMU"
        return CosimError(f"{who} failed during {self._phase} {when}: "
                          f"{reason(self.log.for_instance(who), err)}")
