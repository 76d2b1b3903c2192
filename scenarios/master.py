"""The co-simulation master: fmpy FMU2Slave (or FMU3Slave) instances stepped at a fixed
communication step.

One base class owns the whole run: loading and extracting the FMUs, initialization in dependency
order, the stepping loop, recording into a preallocated numpy array and freeing every instance
whatever happens. A variant declares its `exchange_and_step` (and, for feedback, the hooks it
overrides); the variants live in their own modules (fixed_step.py, coupling.py, adaptive.py) and
masters.py names them:

- Jacobi: every FMU steps from the values at t; then, in dependency order, each FMU's inputs are
  set from its sources' outputs at t + h (a direct-feedthrough FMU's outputs follow its new inputs
  before the next FMU reads them).
- Gauss–Seidel: FMUs step one after another, each fed its sources' newest outputs just before
  its own step. The sweep runs against the data flow (consumers first): along a chain every FMU
  still starts its step from inputs at t, as the contract above requires, while a feedback signal
  reaches the FMU that steps after its source fresh, at t + h (the point of Gauss–Seidel). The
  textbook producers-first sweep would hand each consumer values of t + h as if they were of t:
  FMUs that extrapolate their inputs then run one step early per link, a first-order error
  (1.15° of crank angle at h = 1e-4 s on punch_drive, two links).

Two masters for feedback build on Jacobi: the iterative master (scenarios/coupling.py) repeats a
step around a feedback loop until the exchanged values agree, the adaptive master
(scenarios/adaptive.py) sizes each step from the error of the exchanged signals.

Value references are resolved once; each step makes one batched set and one batched get per FMU
through preallocated ctypes arrays (no lookups by name, no per-step allocation).
"""
from __future__ import annotations

import atexit
import contextlib
import ctypes
import math
import os
import shutil
import sys
import time as clock
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import numpy as np
from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2Boolean,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2Real,
    fmi2ValueReference,
)
from fmpy.fmi3 import FMU3Slave, fmi3Boolean, fmi3Float64

from . import interrupt
from .divergence import DivergenceWatch, bound_text, declared_bound
from .format import Scenario, ScenarioError, did_you_mean

_STATUS = ["OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING"]
_FATAL = 4


class CosimError(RuntimeError):
    """An FMU failed during the run; the message names the instance, the time and its log."""


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


# FMU file (path, size, mtime) -> (unzip dir, model description), for this process's lifetime:
# the FMU's library stays loaded (see Master._free), so it is loaded from one place only.
_EXTRACTED: dict[tuple, tuple[str, object]] = {}

# Every FMU library this process loaded (one dlopen per instance), released at exit while the
# interpreter is still alive. pythonfmu 0.7.0 keeps its interpreter state in a static
# shared_ptr, which the C++ exit handlers destroy, and which the library's unload function
# (finalizePythonInterpreter) releases once more when the process exits after them: a write
# into freed memory that aborts the process at exit ("corrupted double-linked list") or not,
# depending on the heap's layout (seen with four FMU types and scipy loaded). Called first, at
# Python's exit, that function releases the state while all is alive and leaves the static empty,
# so neither later step has anything to free; then the library is unloaded.
_LIBRARIES: list = []


def release_at_exit(fmu) -> None:
    """Have the library of an fmpy FMU object released at Python's exit (see above)."""
    _LIBRARIES.append(fmu.dll)


@atexit.register
def _release_libraries() -> None:
    from fmpy import freeLibrary

    while _LIBRARIES:
        library = _LIBRARIES.pop()
        try:
            release_state = getattr(library, "finalizePythonInterpreter", None)
            if release_state is not None:
                release_state()
            freeLibrary(library._handle)
        except Exception:           # noqa: BLE001 - at exit, nothing to report to
            pass


def extracted_fmu(path: Path) -> tuple[str, object]:
    """(unzip folder, model description) of an FMU file, extracted once per process."""
    stat = path.stat()
    key = (str(path.resolve()), stat.st_size, stat.st_mtime_ns)
    if key not in _EXTRACTED:
        unzip_dir = extract(str(path))
        atexit.register(shutil.rmtree, unzip_dir, True)
        _EXTRACTED[key] = (unzip_dir, read_model_description(str(path)))
    return _EXTRACTED[key]


def check_parameters(scenario: Scenario, fmu_paths: dict[str, Path]) -> None:
    """Every parameter the scenario sets exists in its FMU and fits its type: checked from the
    modelDescriptions alone, before any FMU runs (a sweep checks every point so)."""
    for inst in scenario.instances.values():
        md = extracted_fmu(Path(fmu_paths[inst.fmu]))[1]
        variables = {v.name: v for v in md.modelVariables}
        for key, value in inst.parameters.items():
            v = variables.get(key)
            # an input may be given a value too: it then holds it (unconnected)
            if v is None or v.causality not in ("parameter", "input"):
                names = sorted(n for n, x in variables.items() if x.causality == "parameter")
                raise ScenarioError(f"{scenario.source}: {inst.name}.{key}: {inst.name} "
                                    f"({md.modelName}) has no parameter {key!r}"
                                    f"{did_you_mean(key, names)} (has: {', '.join(names)})")
            if kind_of(v) == "Integer" and value != int(value):
                raise ScenarioError(f"{scenario.source}: {inst.name}.{key}: must be an integer, "
                                    f"got {value!r}")
            low, high = declared_bound(v.min), declared_bound(v.max)
            if (low is not None and value < low) or (high is not None and value > high):
                hint = _unit_hint(v.unit, value) if high is not None and value > high else ""
                raise ScenarioError(f"{scenario.source}: {inst.name}.{key}: parameter {key} = "
                                    f"{value:g} {v.unit or ''} is outside the range "
                                    f"[{bound_text(low, '-inf')}, {bound_text(high, 'inf')}] {inst.name} "
                                    f"({md.modelName}) declares{hint}")


MAX_STEPS = 10**9
# the records of one run may take this share of the memory available when it starts, and
# never more than RECORD_BUDGET (records beyond it are for a file, not for memory)
MEMORY_SHARE = 0.25
RECORD_BUDGET = 1 << 30


def _available_memory() -> int:
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return 8 << 30


def max_rows(columns: int) -> int:
    """The most records of `columns` columns a run may keep (as Python rows: 128 bytes more
    each, besides the values)."""
    return int(_budget() / ((columns + 1) * 8 + 128))


def _budget() -> float:
    return min(RECORD_BUDGET, MEMORY_SHARE * _available_memory())


def check_memory(rows: int, columns: int, source: str, what: str = "records") -> None:
    """Refuse, up front and with the numbers, a run whose records would not fit in memory."""
    need = rows * (columns + 1) * 8
    if need > _budget():
        every = math.ceil(need / _budget())
        raise ScenarioError(f"{source}: the {what} would take {need / 2**30:.3g} GiB ({rows:,} "
                            f"points × {columns + 1} columns), more than the "
                            f"{_budget() / 2**30:.3g} GiB a run may keep: record fewer "
                            f"points (experiment.record_every = {every} or more; the key "
                            f"figures are read from every step of the last revolution all the "
                            f"same), record fewer columns, or take a longer step")


def _unit_hint(unit: str | None, value: float) -> str:
    """How a value out of range may have been meant: with the unit users think in."""
    from ..components.units import DISPLAY_UNITS

    displays = list(DISPLAY_UNITS.get(unit or "", {}))
    return (f" (meant in {displays[0]}? give the unit: \"{value:g} {displays[0]}\")"
            if displays else "")


def check_inputs_given(scenario: Scenario, units: list) -> None:
    """Every input of every instance is connected or given a value in the scenario: an input left
    at its start value runs the FMU on a number nobody chose. A system read from SSP (where the
    standard lets an input keep its start value) gets a warning instead."""
    import warnings

    for unit in units:
        connected = {name for name, _, _ in unit.inputs}
        given = scenario.instances[unit.name].parameters
        for v in unit.md.modelVariables:
            if v.causality != "input" or v.name in connected or v.name in given:
                continue
            text = (f"{scenario.source}: input {unit.name}.{v.name} is neither connected nor "
                    f"given a value")
            if scenario.fmu_files:
                warnings.warn(f"{text}: it keeps its start value {v.start}", InputLeftOpen,
                              stacklevel=2)
                continue
            raise ScenarioError(f"{text}: connect it (\"<instance>.<output> -> "
                                f"{unit.name}.{v.name}\") or give it a value in "
                                f"[instances.{unit.name}] parameters")


class InputLeftOpen(UserWarning):
    """An input of an SSP system that nothing sets: it keeps its start value."""


def _reason(lines: list[str], err: Exception) -> str:
    """The FMU's own error message if it logged one, else the failed call; on one line."""
    errors = [line.split(": ", 1)[-1] for line in lines if line.startswith("[ERROR]")]
    text = errors[-1] if errors else (lines[-1] if lines else str(err))
    return " ".join(text.split())


class LogCollector:
    """FMU log callback that keeps the messages (for error reports) instead of printing them."""

    def __init__(self):
        self.lines: list[str] = []
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        try:
            from fmpy.logging import addLoggerProxy
            addLoggerProxy(ctypes.byref(self.callbacks))
        except Exception:        # without the proxy, messages arrive unformatted: still useful
            pass

    def _log(self, component, instance_name, status, category, message):
        self.add(instance_name.decode("utf-8", "replace") if instance_name else "?", status,
                 message)

    def add(self, name: str, status: int, message: bytes | None) -> None:
        text = message.decode("utf-8", "replace") if message else ""
        self.lines.append(f"[{_STATUS[status] if 0 <= status < 6 else status}] {name}: {text}")

    def for_fmi3(self, name: str):
        """An FMI 3.0 log callback for the instance `name` (FMI 3.0 passes no instance name)."""
        return lambda environment, status, category, message: self.add(name, status, message)

    def for_instance(self, name: str) -> list[str]:
        return [line for line in self.lines if f"] {name}: " in line]


def kind_of(variable) -> str:
    """A variable's type in FMI 2.0's words: Real, Integer, Boolean or String (FMI 3.0 names
    Float64, Int32 and their kin)."""
    return _KINDS.get(variable.type, variable.type)


_KINDS = {"Float64": "Real", "Float32": "Real",
          **{f"{sign}Int{bits}": "Integer" for sign in ("", "U") for bits in (8, 16, 32, 64)}}


class FmuInstance:
    """One instance of an FMI 2.0 FMU as the master runs it (fmpy's FMU2Slave), its value
    references resolved; the scenario declares it as a format.Instance. Fmu3Instance runs an
    FMI 3.0 FMU the same way: `for_fmu` picks by the modelDescription's fmiVersion."""

    FMU_CLASS = FMU2Slave
    BOOLEAN = fmi2Boolean
    # the FMI functions, by what they do
    CALLS = {"set_real": "fmi2SetReal", "get_real": "fmi2GetReal",
             "get_boolean": "fmi2GetBoolean", "do_step": "fmi2DoStep",
             "get_state": "fmi2GetFMUstate", "set_state": "fmi2SetFMUstate",
             "free_state": "fmi2FreeFMUstate", "free": "fmi2FreeInstance"}

    @staticmethod
    def for_fmu(name: str, unzip_dir: str, md, log: "LogCollector") -> "FmuInstance":
        cls = Fmu3Instance if md.fmiVersion.startswith("3") else FmuInstance
        return cls(name, unzip_dir, md, log)

    def __init__(self, name: str, unzip_dir: str, md, log: LogCollector):
        self.name = name
        self.md = md
        self.variables = {v.name: v for v in md.modelVariables}
        self.fmu = self.FMU_CLASS(guid=md.guid, unzipDirectory=unzip_dir,
                                  modelIdentifier=md.coSimulation.modelIdentifier,
                                  instanceName=name)
        release_at_exit(self.fmu)
        self.log = log
        self.instantiated = False
        self.failed = False          # a call returned Fatal: make no further calls
        self.real_out: list[str] = []       # outputs read every step, in order
        self.bool_out: list[str] = []
        self.inputs: list[tuple[str, "FmuInstance", str]] = []   # (input, source unit, source output)

    def variable(self, var: str, causality: tuple[str, ...], what: str):
        v = self.variables.get(var)
        if v is None or v.causality not in causality:
            names = sorted(n for n, x in self.variables.items() if x.causality in causality)
            raise ScenarioError(f"{what}: {self.name} ({self.md.modelName}) has no "
                                f"{'/'.join(causality)} {var!r} (has: {', '.join(names)})")
        return v

    def want_output(self, var: str, what: str) -> tuple[str, int]:
        boolean = kind_of(self.variable(var, ("output",), what)) == "Boolean"
        group = self.bool_out if boolean else self.real_out
        if var not in group:
            group.append(var)
        return ("bool" if boolean else "real"), group.index(var)

    def prepare(self) -> None:
        """Preallocate the ctypes arrays for the batched calls of every step."""
        def arrays(names, ctype):
            vrs = (fmi2ValueReference * len(names))(*[self.variables[n].valueReference
                                                      for n in names])
            vals = (ctype * len(names))()
            return vrs, vals, len(names)

        self.out_vr, self.out_buf, self.n_out = arrays(self.real_out, fmi2Real)
        self.bool_vr, self.bool_buf, self.n_bool = arrays(self.bool_out, self.BOOLEAN)
        self.in_vr, self.in_buf, self.n_in = arrays([i for i, _, _ in self.inputs], fmi2Real)
        # where each input comes from: (source unit, index in its real outputs)
        self.in_sources = [(src, src.real_out.index(out)) for _, src, out in self.inputs]

    # --- the life of the instance --------------------------------------------------------------
    def instantiate(self) -> None:
        """Instantiate, leaving this process's sys.path as it was.

        pythonfmu puts the FMU's resources folder first on sys.path at every instantiation and
        leaves it there: later imports of this process would find the FMU's copies (its
        pythonfmu lacks the binaries the builder needs) and sys.path would grow with every
        instance. The FMU has imported its code by then, so sys.path is put back.
        """
        saved_path = list(sys.path)
        try:
            self._instantiate()
        finally:
            sys.path[:] = saved_path
        self.instantiated = True
        self.bind()

    def _instantiate(self) -> None:
        self.fmu.instantiate(callbacks=self.log.callbacks, loggingOn=True)

    def enter_initialization(self, stop: float) -> None:
        self.fmu.setupExperiment(startTime=0.0, stopTime=stop)
        self.fmu.enterInitializationMode()

    def set_parameter(self, variable, value) -> None:
        if kind_of(variable) == "Integer":
            self.fmu.setInteger([variable.valueReference], [int(value)])
        else:
            self.fmu.setReal([variable.valueReference], [float(value)])

    def release(self) -> None:
        """Terminate and free a healthy instance, keeping its library loaded (see
        Master._free)."""
        try:
            self.fmu.terminate()
        except Exception:
            pass
        getattr(self.fmu, self.CALLS["free"])(self.fmu.component)

    def get_state(self):
        return self.fmu.getFMUstate()

    def set_state(self, state) -> None:
        self.fmu.setFMUstate(state)

    # --- per-step calls: batched, through the raw ctypes functions (fmpy's wrapper costs a few
    # µs per call); a failure marks the instance, so that no further call is made on it ---------
    def bind(self) -> None:
        """Resolve the raw FMI functions once the instance exists, with their arguments."""
        self.component = self.fmu.component
        self._set_reals = self._batched("set_real", self.in_vr, self.n_in, self.in_buf)
        self._get_reals = self._batched("get_real", self.out_vr, self.n_out, self.out_buf)
        self._get_booleans = self._batched("get_boolean", self.bool_vr, self.n_bool,
                                           self.bool_buf)
        self._do_step = self._bound_step(self.fmu._functions[self.CALLS["do_step"]])

    # FMI 3.0's batched getters and setters take the number of values after the values
    VALUES_COUNTED = False

    def _batched(self, call: str, vrs, n: int, values):
        """A raw get or set call with all its arguments bound: calling it makes the call."""
        counted = (n,) if self.VALUES_COUNTED else ()
        return partial(self.fmu._functions[self.CALLS[call]], self.component, vrs, n, values,
                       *counted)

    def _bound_step(self, step):
        """doStep(t, h, noSetFMUStatePriorToCurrentPoint) on this instance."""
        return partial(step, self.component)

    def raw_state_calls(self) -> tuple:
        """The raw get, set and free FMU state functions (for SavedStates)."""
        raw = self.fmu._functions
        return tuple(raw[self.CALLS[k]] for k in ("get_state", "set_state", "free_state"))

    def _check(self, call: str, status: int) -> None:
        if status > 1:                     # worse than Warning: the run stops
            # after Discard or Error the instance may still be terminated and freed; after
            # Fatal FMI allows no call at all
            self.failed = status >= _FATAL
            err = FMICallException(self.CALLS.get(call, call), status)
            err.unit = self
            raise err

    def pull_inputs(self) -> None:
        if self.n_in:
            buf = self.in_buf
            for k, (src, idx) in enumerate(self.in_sources):
                buf[k] = src.out_buf[idx]
            self.set_inputs()

    def pull_changed_inputs(self) -> bool:
        """Within one instant: set the inputs again only if a source's output changed (setting
        an input restarts its extrapolation, so the first setting at an instant is always
        made, by pull_inputs); whether any did."""
        changed = False
        buf = self.in_buf
        for k, (src, idx) in enumerate(self.in_sources):
            value = src.out_buf[idx]
            if buf[k] != value:
                buf[k] = value
                changed = True
        if changed:
            self.set_inputs()
        return changed

    def set_inputs(self) -> None:
        """Set every connected input to its value in in_buf."""
        status = self._set_reals()
        if status > 1:
            self._check("set_real", status)

    def read_outputs(self) -> None:
        if self.n_out:
            status = self._get_reals()
            if status > 1:
                self._check("get_real", status)
            # a NaN or infinite output stops the run here, naming its FMU (sewfmu's FMUs log
            # why; a getter cannot refuse), rather than in the FMU it would be passed to
            if not math.isfinite(sum(self.out_buf)):
                bad = [n for n, x in zip(self.real_out, self.out_buf) if not math.isfinite(x)]
                if bad:
                    own = self.log.for_instance(self.name)
                    if not any(line.startswith("[ERROR]") for line in own):
                        self.log.lines.append(f"[ERROR] {self.name}: output {bad[0]} is "
                                              f"{self.out_buf[self.real_out.index(bad[0])]}")
                    err = FMICallException(self.CALLS["get_real"], 3)
                    err.unit = self
                    raise err
        if self.n_bool:
            status = self._get_booleans()
            if status > 1:
                self._check("get_boolean", status)

    def do_step(self, t: float, h: float) -> None:
        status = self._do_step(t, h, 1)
        if status > 1:
            self._check("do_step", status)


class Fmu3Instance(FmuInstance):
    """An instance of an FMI 3.0 co-simulation FMU (fmpy's FMU3Slave): the same run through
    FMI 3.0's calls (Float64 for Real, the step's extra results, no setupExperiment)."""

    FMU_CLASS = FMU3Slave
    BOOLEAN = fmi3Boolean
    CALLS = {"set_real": "fmi3SetFloat64", "get_real": "fmi3GetFloat64",
             "get_boolean": "fmi3GetBoolean", "do_step": "fmi3DoStep",
             "get_state": "fmi3GetFMUState", "set_state": "fmi3SetFMUState",
             "free_state": "fmi3FreeFMUState", "free": "fmi3FreeInstance"}

    def _instantiate(self) -> None:
        # no event mode: sewfmu's masters step in co-simulation's step mode only
        self.fmu.instantiate(loggingOn=True, logMessage=self.log.for_fmi3(self.name))

    def enter_initialization(self, stop: float) -> None:
        self.fmu.enterInitializationMode(startTime=0.0, stopTime=stop)

    def set_parameter(self, variable, value) -> None:
        if variable.type == "Float64":
            self.fmu.setFloat64([variable.valueReference], [float(value)])
        elif variable.type == "Int32":
            self.fmu.setInt32([variable.valueReference], [int(value)])
        elif variable.type == "Int64":
            self.fmu.setInt64([variable.valueReference], [int(value)])
        else:
            raise ScenarioError(f"{self.name}.{variable.name}: a {variable.type} parameter "
                                f"cannot be set from a scenario")

    def get_state(self):
        return self.fmu.getFMUState()

    def set_state(self, state) -> None:
        self.fmu.setFMUState(state)

    VALUES_COUNTED = True

    def _bound_step(self, step):
        # doStep's results: event handling needed, terminate, early return, last successful
        # time (sewfmu's masters use no event mode and allow no early return)
        self._step_results = [fmi3Boolean(), fmi3Boolean(), fmi3Boolean(), fmi3Float64()]
        refs = [ctypes.byref(x) for x in self._step_results]
        c = self.component
        # noSetFMUStatePriorToCurrentPoint is false: the iterative and adaptive masters do
        return lambda t, h, _: step(c, t, h, False, *refs)


class Master:
    """Runs one scenario; subclasses define how a communication step exchanges and steps."""

    name = "base"

    # how often (in communication steps) the run reports its progress
    PROGRESS_EVERY = 1024

    def __init__(self, scenario: Scenario, fmu_paths: dict[str, Path]):
        self.scenario = scenario
        self.fmu_paths = fmu_paths

    # --- the run -------------------------------------------------------------------------------
    def run(self, progress=None) -> RunResult:
        """Open, step to the end, close: the whole scenario. `progress(done, total)`, if given,
        hears of the steps done every PROGRESS_EVERY steps. Ctrl-C or SIGTERM interrupt the run
        between two communication steps (interrupt.Interrupted), never inside an FMU."""
        started = clock.perf_counter()
        every = self.PROGRESS_EVERY
        with interrupt.deferred(), self:
            while not self.finished():
                self.step()
                if interrupt.pending:
                    interrupt.raise_pending()
                if progress is not None and self.k % every == 0:
                    progress(*self.progress_point())
            result = self.result()
        result.wall_time = clock.perf_counter() - started
        return result

    def finished(self) -> bool:
        return self.k >= self.n_steps

    def progress_point(self) -> tuple[int, int]:
        """(done, total) for a progress report: communication steps."""
        return self.k, self.n_steps

    def __enter__(self) -> "Master":
        try:
            self.open()
        except BaseException:
            self.close()            # instances initialized before the failure are freed
            raise
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def open(self) -> None:
        """Load the FMUs, initialize them in dependency order, record the initial point."""
        sc = self.scenario
        self.stop = sc.end_time()
        if not sc.step > 0:          # an SSP system that gives none
            raise ScenarioError(f"{sc.source}: no communication step: the file gives none; "
                                f"pass --set experiment.step=…")
        if sc.step > self.stop:
            raise ScenarioError(f"{sc.source}: experiment.step {sc.step:g} s is longer than the "
                                f"run ({self.stop:g} s)")
        self.n_steps, self.h = sc.even_steps()
        if self.n_steps > MAX_STEPS:
            raise ScenarioError(f"{sc.source}: {self.n_steps:.3g} communication steps (end "
                                f"{self.stop:g} s at a step of {sc.step:g} s) are more than "
                                f"{MAX_STEPS:.0e}: days of stepping; take a longer "
                                f"experiment.step or a shorter run")
        sc.master_settings()         # a tolerance the master cannot honour: refused here
        self.every = max(1, int(sc.record_every))
        self.log = LogCollector()
        self.instances: list[FmuInstance] = []
        self.k = 0
        self._phase = "loading"
        with self._reporting():
            self.instances = self._load(self.log)
            self.columns = self._plan(self.instances)
            self._phase = "initialization"
            for unit in self.instances:
                self._initialize(unit, self.stop)
        self.watch = DivergenceWatch(self.in_loops, self.h) if self.in_loops else None
        # every step from one step before the last whole revolution on (the analyses' window)
        self.dense_from = 0 if self.every == 1 else \
            max(0, int(sc.last_revolution_start() / self.h) - 1)
        dense = self.n_steps - self.dense_from if self.every > 1 else 0
        self._rows = self.n_steps // self.every + 1 + (self.n_steps % self.every != 0) + dense
        check_memory(self._rows, len(self.columns), sc.source)
        self._data = np.empty((self._rows, len(self.columns)))
        self._times = np.empty(self._rows)
        self._row = 0
        self._record_row(0.0)
        self._phase = "step"

    def step(self) -> None:
        """One communication step: n_steps even steps of h end exactly at the stop time."""
        h = self.h
        t = self.k * h
        try:                       # (no context manager here: this is the hot path)
            self.exchange_and_step(self.instances, t, h)
        except FMICallException as err:
            raise self._failure(err, f"from t = {t:g} to {t + h:g} s") from None
        if self.watch is not None:
            self.watch.check(t + h)
        self.k += 1
        if self.k % self.every == 0 or self.k == self.n_steps or self.k >= self.dense_from:
            self._record_row(self.stop if self.k == self.n_steps else self.k * h)

    def save_state(self) -> tuple:
        """The state of every FMU and of the master: `restore_state` rolls back to it."""
        with self._reporting(self.k * self.h):
            return (self.k, self._row, [u.get_state() for u in self.instances],
                    [list(u.in_buf) for u in self.instances])

    def restore_state(self, state: tuple) -> None:
        self.k, self._row, fmu_states, inputs = state
        with self._reporting(self.k * self.h):
            for unit, fmu_state, values in zip(self.instances, fmu_states, inputs):
                unit.set_state(fmu_state)
                unit.in_buf[:] = values            # the inputs the master last set, as then
            for unit in self.instances:            # the caches follow the restored FMUs
                unit.read_outputs()

    def result(self) -> RunResult:
        rows = slice(0, self._row)
        return RunResult(self.scenario, self._times[rows].copy(),
                         {c: self._data[rows, j].copy() for j, c in enumerate(self.columns)},
                         0.0, self.log.lines, units=self.units)

    def close(self) -> None:
        self._free(getattr(self, "instances", []))

    @contextlib.contextmanager
    def _reporting(self, t: float = 0.0):
        """Turn a failed FMI call into a CosimError naming the FMU, the time and its log."""
        try:
            yield
        except FMICallException as err:
            raise self._failure(err, f"at t = {t:g} s") from None

    def _failure(self, err: FMICallException, when: str) -> CosimError:
        failed = [u for u in self.instances if u.failed]
        unit = getattr(err, "unit", None) or (failed[0] if failed else None)
        who = unit.name if unit else "an FMU"
        return CosimError(f"{who} failed during {self._phase} {when}: "
                          f"{_reason(self.log.for_instance(who), err)}")

    def _record_row(self, t: float) -> None:
        self._times[self._row] = t
        self._record(self._data, self._row)
        self._row += 1

    def exchange_and_step(self, units: list[FmuInstance], t: float, h: float) -> None:
        raise NotImplementedError

    # --- pieces of the run ---------------------------------------------------------------------
    def _load(self, log: LogCollector) -> list[FmuInstance]:
        sc = self.scenario
        by_name = {}
        for inst in sc.instances.values():
            if inst.fmu not in self.fmu_paths:
                raise ScenarioError(f"{sc.source}: instances.{inst.name}: unknown FMU {inst.fmu!r}")
            unzip_dir, md = extracted_fmu(Path(self.fmu_paths[inst.fmu]))
            by_name[inst.name] = FmuInstance.for_fmu(inst.name, unzip_dir, md, log)
        for con in sc.connections:
            what = f"{sc.source}: connection {con}"
            src, dst = by_name[con.src], by_name[con.dst]
            out_var = src.variable(con.src_var, ("output",), what)
            in_var = dst.variable(con.dst_var, ("input",), what)
            if kind_of(out_var) != "Real" or kind_of(in_var) != "Real":
                raise ScenarioError(f"{what}: only Real connections are supported")
            # a variable without a unit says nothing about it (FMUs from elsewhere): only two
            # declared units that differ are a mismatch
            if out_var.unit and in_var.unit and out_var.unit != in_var.unit:
                raise ScenarioError(f"{what}: incompatible units {out_var.unit!r} -> {in_var.unit!r}")
            src.want_output(con.src_var, what)
            dst.inputs.append((con.dst_var, src, con.src_var))
        check_parameters(sc, self.fmu_paths)
        check_inputs_given(sc, list(by_name.values()))
        order, loops = _dependency_order(list(by_name.values()))
        self.in_loops = [u for u in order if u in loops]
        # inputs and outputs settle in one pass along a chain; around a feedback loop each pass
        # carries a change one link further
        self.passes = 1 + len(self.in_loops)
        return order

    def _plan(self, units: list[FmuInstance]) -> list[str]:
        """Decide which outputs are read each step; return the recorded column names."""
        sc = self.scenario
        by_name = {u.name: u for u in units}
        if sc.record is None:
            wanted = [f"{u.name}.{v.name}" for u in units for v in u.md.modelVariables
                      if v.causality == "output"]
        else:
            wanted = list(sc.record)
        self._record_plan = []
        self.units: dict[str, str] = {}
        for col in wanted:
            inst, dot, var = str(col).partition(".")
            if inst not in by_name or not dot:
                raise ScenarioError(f"{sc.source}: record {col!r}: unknown instance")
            kind, idx = by_name[inst].want_output(var, f"{sc.source}: record {col!r}")
            self._record_plan.append((by_name[inst], kind, idx))
            self.units[col] = by_name[inst].variables[var].unit or ""
        for unit in units:
            unit.prepare()
        return wanted

    def _initialize(self, unit: FmuInstance, stop: float) -> None:
        """Instantiate, set parameters, take inputs from the already initialized sources."""
        unit.instantiate()
        try:
            self._set_up(unit, stop)
        except FMICallException as err:
            unit.failed = err.status >= _FATAL
            err.unit = unit
            raise

    def _set_up(self, unit: FmuInstance, stop: float) -> None:
        unit.enter_initialization(stop)
        for key, value in self.scenario.instances[unit.name].parameters.items():
            unit.set_parameter(unit.variables[key], value)
        unit.pull_inputs()
        unit.fmu.exitInitializationMode()
        # sewfmu's FMUs answer bad parameters at exitInitializationMode with an fmi2Error log
        # line (and refuse every step), not with fmi2Fatal: stop here, naming the cause
        errors = [line for line in self.log.for_instance(unit.name) if line.startswith("[ERROR]")]
        if errors:
            raise CosimError(f"{unit.name} failed during initialization at t = 0 s: "
                             f"{_reason(errors, None)}")
        unit.read_outputs()

    def _record(self, data: np.ndarray, row: int) -> None:
        out = data[row]
        for j, (unit, kind, idx) in enumerate(self._record_plan):
            out[j] = unit.out_buf[idx] if kind == "real" else unit.bool_buf[idx]

    @staticmethod
    def _free(units: list[FmuInstance]) -> None:
        for unit in units:
            # after a failed call FMI allows no further call on that instance (pythonfmu
            # reports every Python exception as fmi2Fatal and has already dropped its objects)
            if unit.instantiated and not unit.failed:
                # terminate and free, but keep the library loaded: the extraction cache reuses
                # it, and unloading pythonfmu's binary from a Python host is unsafe
                unit.release()
                unit.instantiated = False


def _dependency_order(units: list[FmuInstance]) -> tuple[list[FmuInstance], list[FmuInstance]]:
    """Sources before the units they feed (a cycle keeps the scenario's order within it), and
    the units that lie on a feedback loop."""
    order, placed, in_loops = [], set(), []
    remaining = list(units)
    while remaining:
        ready = [u for u in remaining
                 if all(src.name in placed or src is u for _, src, _ in u.inputs)]
        if not ready:            # a feedback loop: break it at the first unit in file order
            ready = [remaining[0]]
        for u in ready:
            order.append(u)
            placed.add(u.name)
            remaining.remove(u)
    for unit in units:
        if reaches(unit, unit):
            in_loops.append(unit)
    return order, in_loops


def reaches(start: FmuInstance, target: FmuInstance) -> bool:
    """Whether a signal from `target` comes back to `start` through the connections."""
    seen, todo = set(), [src for _, src, _ in start.inputs]
    while todo:
        unit = todo.pop()
        if unit is target:
            return True
        if unit.name not in seen:
            seen.add(unit.name)
            todo.extend(src for _, src, _ in unit.inputs)
    return False
