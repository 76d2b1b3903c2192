"""FMU instances as the master runs them: one interface, one adapter per FMI version.

`Instance` holds what every instance has whatever runs it: its connected inputs and the outputs
read every step, in preallocated ctypes arrays (one batched set and one batched get per step, no
lookups by name, no allocation), and the rules of a failed call (a status worse than Warning
raises FmiCallError; after Fatal no further call is made). The adapters make the calls:
`Fmi2Instance` through fmpy's FMU2Slave, `Fmi3Instance` through FMU3Slave; the per-step calls go
to the library's functions directly (fmpy's wrapper costs a few µs per call). A test can put a
plain Python instance behind the same interface (tests/fake_fmu.py).
"""
from __future__ import annotations

import ctypes
import math
import os
from functools import partial
from pathlib import Path

from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave, fmi2Boolean, fmi2Real, fmi2ValueReference
from fmpy.fmi3 import FMU3Slave, fmi3Boolean, fmi3Float64

from sewfmu.scenarios.cosim.fmi_calls import (
    WARNING_LEVEL,
    FmiCallError,
    LogCollector,
    Status,
    failed,
    kind_of,
)
from sewfmu.scenarios.cosim.fmu_cache import extract_cached, is_cached
from sewfmu.scenarios.cosim.guardian import BEAT, CODE, SIZE, WHERE
from sewfmu.scenarios.cosim.interrupt import keep_handlers
from sewfmu.scenarios.cosim.pythonfmu_host import instantiating, release_at_exit
from sewfmu.scenarios.format.fmu_file import check_binary, model_description
from sewfmu.scenarios.format.values import ScenarioError

# FMU file (path, size, mtime) -> (unzip dir, model description), for this process's lifetime:
# the FMU's library stays loaded (see Instance.release), so it is loaded from one place only.
_EXTRACTED: dict[tuple, tuple[str, object]] = {}
# an instance's board before a watched run notes it: written, never read
_NO_BOARD = memoryview(bytearray(SIZE)).cast("q")


def extracted_fmu(path: Path) -> tuple[str, object]:
    """(unzip folder, model description) of an FMU file, extracted once (scenarios/cosim/fmu_cache.py:
    kept between processes too)."""
    stat = path.stat()
    key = (str(path.resolve()), stat.st_size, stat.st_mtime_ns)
    if key not in _EXTRACTED:
        # its description and its library for this platform checked before anything is
        # unpacked or loaded: one line naming what is missing, not fmpy's "instantiate
        # returned FATAL"
        md = model_description(path, "")
        check_binary(path, md)
        _EXTRACTED[key] = (extract_cached(path), md)
    return _EXTRACTED[key]


# Idle fmpy FMU objects, by unzip folder: an instance takes one when it is instantiated and hands
# it back when it is released, for the next instance of that FMU. So the library is loaded, and
# fmpy binds its functions, once per FMU and concurrent instance rather than once per instance,
# and a process that runs thousands of sweep points keeps a flat memory (every library object
# stays referenced until exit: see pythonfmu_host.py). FMI allows a new instantiation from a
# library whose instance was freed.
_IDLE: dict[str, list] = {}


def _loaded_fmu(cls, unzip_dir: str, md, name: str):
    """An fmpy FMU object of this FMU, named `name`: an idle one, or a newly loaded one."""
    idle = _IDLE.get(unzip_dir)
    while idle:
        fmu = idle.pop()
        if type(fmu) is cls:
            fmu.instanceName = name
            return fmu
    fmu = cls(guid=md.guid, unzipDirectory=unzip_dir,
              modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    release_at_exit(fmu)
    return fmu


def open_instance(name: str, path: Path, log: LogCollector) -> "Instance":
    """An instance of the FMU file, by its modelDescription's fmiVersion (not yet instantiated)."""
    unzip_dir, md = extracted_fmu(Path(path))
    cls = Fmi3Instance if md.fmiVersion.startswith("3") else Fmi2Instance
    return cls(name, unzip_dir, md, log)


class Instance:
    """One instance in a run: its variables, connections and per-step buffers. Subclasses make
    the FMI calls (the methods below that raise NotImplementedError)."""

    BOOLEAN = fmi2Boolean            # the ctypes type of a Boolean value

    def __init__(self, name: str, md, log: LogCollector):
        self.name = name
        self.md = md
        self.log = log
        self.variables = {v.name: v for v in md.modelVariables}
        self.instantiated = False
        self.failed = False          # a call returned Fatal: make no further calls
        # noSetFMUStatePriorToCurrentPoint is this negated: the run loop clears it for an
        # algorithm that never rolls back
        self.may_roll_back = True
        self.real_out: list[str] = []       # outputs read every step, in order
        self.bool_out: list[str] = []
        self.inputs: list[tuple[str, Instance, str]] = []   # (input, source, source's output)

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name}>"

    # --- what the run connects and reads -------------------------------------------------------
    def variable(self, var: str, causality: tuple[str, ...], what: str):
        v = self.variables.get(var)
        if v is None or v.causality not in causality:
            names = sorted(n for n, x in self.variables.items() if x.causality in causality)
            raise ScenarioError(f"{what}: {self.name} ({self.md.modelName}) has no "
                                f"{'/'.join(causality)} {var!r} (has: {', '.join(names)})")
        return v

    def want_output(self, var: str, what: str) -> tuple[str, int]:
        """Read this output every step: ("real" or "bool", its index in the buffer)."""
        boolean = kind_of(self.variable(var, ("output",), what)) == "Boolean"
        group = self.bool_out if boolean else self.real_out
        if var not in group:
            group.append(var)
        return ("bool" if boolean else "real"), group.index(var)

    def prepare(self, outputs=None) -> None:
        """Preallocate the ctypes arrays for the batched calls of every step. `outputs`, if
        given, is the part of a run's array of outputs (System.outputs, a numpy view) that this
        instance's Real outputs are read into."""
        def arrays(names, ctype, values=None):
            vrs = (fmi2ValueReference * len(names))(*[self.variables[n].valueReference
                                                      for n in names])
            vals = (ctype * len(names))() if values is None else \
                (ctype * len(names)).from_buffer(values)
            return vrs, vals, len(names)

        self.out_vr, self.out_buf, self.n_out = arrays(self.real_out, fmi2Real, outputs)
        self.bool_vr, self.bool_buf, self.n_bool = arrays(self.bool_out, self.BOOLEAN)
        self.in_vr, self.in_buf, self.n_in = arrays([i for i, _, _ in self.inputs], fmi2Real)
        # the outputs as C doubles, summed at every read without a copy (the finiteness check)
        self.out_doubles = memoryview(self.out_buf).cast("B").cast("d")
        # where each input comes from: (source, index in its real outputs)
        self.in_sources = [(src, src.real_out.index(out)) for _, src, out in self.inputs]
        # all from one source's outputs in a row and in the same unit (a linkage fed by the
        # shaft): that slice of its buffer is copied at once
        first = self.in_sources[0] if self.in_sources else None
        self.in_block = None
        if first and self.in_scales is None and all(
                src is first[0] and idx == first[1] + k
                for k, (src, idx) in enumerate(self.in_sources)):
            self.in_block = (first[0], first[1], first[1] + len(self.in_sources))

    # --- the life of the instance: the FMI calls -----------------------------------------------
    # the instance's code lives in sewfmu's cache of extracted FMUs: keep its bytecode there
    cached = False
    carried = None        # the pythonfmu package the FMU carries a copy of (pythonfmu_host.py)
    in_block = None       # (source, start, stop): the inputs are that slice of its outputs
    # (factor, offset) per input taking its source's value to the input's unit, or None where
    # every input is in its source's unit (scenarios/cosim/connection_units.py)
    in_scales: list[tuple[float, float]] | None = None

    # the guardian's board (cosim/guardian.py): which instance and call the run is in, written
    # before each call (one store: ~30 ns); slot * 32 is this instance's share of the code
    board, at = _NO_BOARD, 0

    def note(self, board, slot: int) -> None:
        """Write where the run is on `board` (a watched run's) as this instance, `slot`."""
        self.board, self.at = board, slot * 32

    def _calling(self, what: str) -> None:
        """A call other than the per-step ones: noted with a beat (experiment.step_timeout
        covers every FMI call)."""
        self.board[WHERE] = self.at + CODE.get(what, 0)
        self.board[BEAT] += 1

    def instantiate(self) -> None:
        self._calling("instantiate")
        with instantiating(keep_bytecode=self.cached, carried=self.carried):
            self._instantiate()
        # an FMU that set its own SIGINT handler (or ignored it) would leave Ctrl-C doing nothing
        keep_handlers()
        self.instantiated = True
        self.bind()

    def _instantiate(self) -> None:
        raise NotImplementedError

    def bind(self) -> None:
        """Make the per-step calls ready once the instance exists."""

    def enter_initialization(self, stop: float) -> None:
        raise NotImplementedError

    def set_parameter(self, variable, value) -> None:
        raise NotImplementedError

    def exit_initialization(self) -> None:
        raise NotImplementedError

    def release(self) -> None:
        """Terminate and free a healthy instance (instantiated is then false)."""
        raise NotImplementedError

    # the per-step calls, each with its arguments bound: they return the status
    def _set_reals(self) -> int:
        raise NotImplementedError

    def _get_reals(self) -> int:
        raise NotImplementedError

    def _get_booleans(self) -> int:
        raise NotImplementedError

    def _do_step(self, t: float, h: float) -> int:
        raise NotImplementedError

    # FMU states: a slot is what the state calls fill and read (a c_void_p for a real FMU)
    def new_state_slot(self):
        return ctypes.c_void_p()

    def get_state(self, slot) -> int:
        raise NotImplementedError

    def set_state(self, slot) -> int:
        raise NotImplementedError

    def free_state(self, slot) -> None:
        raise NotImplementedError

    # --- the per-step rules --------------------------------------------------------------------
    def check(self, call: str, status: int) -> None:
        """A status worse than Warning stops the run (after Fatal no call may follow)."""
        if failed(status):
            self.failed = status >= Status.FATAL
            raise FmiCallError(call, status, self)

    def exchange(self, pull: bool = True, read: bool = True) -> None:
        """Set the inputs from their sources' outputs now, then read the outputs: Jacobi's
        exchange at every step, in one call per instance (the hot path of a run: each call
        less is about 1 % of the master's own time; bench/floor.py). `pull_inputs` and
        `read_outputs` are its two halves."""
        if pull and self.n_in:
            block = self.in_block
            if block is not None:
                src, start, stop = block
                self.in_buf[:] = src.out_buf[start:stop]
            else:
                self.in_buf[:] = self.input_values()
            self.board[WHERE] = self.at + 2            # set inputs
            status = self._set_reals()
            if status > WARNING_LEVEL:
                self.check("set inputs", status)
        if not read:
            return
        if self.n_out:
            self.board[WHERE] = self.at + 3            # get outputs
            status = self._get_reals()
            if status > WARNING_LEVEL:
                self.check("get outputs", status)
            # a NaN or infinite output stops the run here, naming its FMU (sewfmu's FMUs log
            # why; a getter cannot refuse), rather than in the FMU it would be passed to
            if not math.isfinite(sum(self.out_doubles)):
                self._refuse_non_finite_outputs()
        if self.n_bool:
            status = self._get_booleans()
            if status > WARNING_LEVEL:
                self.check("get Boolean outputs", status)

    def pull_inputs(self) -> None:
        """Set every connected input from its source's output now."""
        self.exchange(read=False)

    def read_outputs(self) -> None:
        """Read the outputs the run reads every step."""
        self.exchange(pull=False)

    def input_values(self) -> list[float]:
        """Each connected input's value now: its source's output, in the input's unit."""
        if self.in_scales is None:
            return [src.out_buf[idx] for src, idx in self.in_sources]
        return [a * src.out_buf[idx] + b
                for (src, idx), (a, b) in zip(self.in_sources, self.in_scales)]

    def pull_changed_inputs(self) -> bool:
        """Within one instant: set the inputs again only if a source's output changed (setting
        an input restarts its extrapolation, so the first setting at an instant is always
        made, by pull_inputs); whether any did."""
        values = self.input_values()
        if values == self.in_buf[:]:
            return False
        self.in_buf[:] = values
        self.set_inputs()
        return True

    def set_inputs(self) -> None:
        """Set every connected input to its value in in_buf."""
        status = self._set_reals()
        if status > WARNING_LEVEL:
            self.check("set inputs", status)

    def _refuse_non_finite_outputs(self) -> None:
        """Stop the run at an output that is NaN or infinite (the sum of finite outputs may
        overflow without any being so: the run then goes on)."""
        bad = [n for n, x in zip(self.real_out, self.out_buf) if not math.isfinite(x)]
        if bad:
            if not self.log.errors_of(self.name):
                self.log.lines.append(f"[ERROR] {self.name}: output {bad[0]} is "
                                      f"{self.out_buf[self.real_out.index(bad[0])]}")
            raise FmiCallError("get outputs", Status.ERROR, self)

    def do_step(self, t: float, h: float) -> None:
        self.board[WHERE] = self.at + 1                # doStep
        status = self._do_step(t, h)
        if status > WARNING_LEVEL:
            self.check("doStep", status)


class Fmi2Instance(Instance):
    """An instance of an FMI 2.0 co-simulation FMU, through fmpy's FMU2Slave."""

    FMU_CLASS = FMU2Slave
    # the library's functions, by what they do
    CALLS = {"set_real": "fmi2SetReal", "get_real": "fmi2GetReal",
             "get_boolean": "fmi2GetBoolean", "do_step": "fmi2DoStep",
             "get_state": "fmi2GetFMUstate", "set_state": "fmi2SetFMUstate",
             "free_state": "fmi2FreeFMUstate", "free": "fmi2FreeInstance"}
    # FMI 3.0's batched getters and setters take the number of values after the values
    VALUES_COUNTED = False

    def __init__(self, name: str, unzip_dir: str, md, log: LogCollector):
        super().__init__(name, md, log)
        self.unzip_dir = unzip_dir
        self.cached = is_cached(unzip_dir)
        self.carried = next((name for name in ("pythonfmu", "pythonfmu3")
                             if os.path.isdir(os.path.join(unzip_dir, "resources", name))), None)
        self.fmu = None               # fmpy's FMU object, held from instantiation to release

    def _take_library(self):
        """The loaded library to instantiate from (fmpy's FMU object, named as this instance)."""
        if self.fmu is None:
            self.fmu = _loaded_fmu(self.FMU_CLASS, self.unzip_dir, self.md, self.name)
        return self.fmu

    def _function(self, call: str):
        """The library's function (fmpy has given it its argument types when loading)."""
        return getattr(self.fmu.dll, self.CALLS[call])

    def _call(self, what: str, call, *args):
        """A call through fmpy's wrapper, its failure turned into sewfmu's FmiCallError."""
        self._calling(what)
        try:
            return call(*args)
        except FMICallException as err:
            self.failed = err.status >= Status.FATAL
            raise FmiCallError(what, err.status, self) from None

    def _instantiate(self) -> None:
        try:
            self._take_library().instantiate(callbacks=self.log.callbacks, loggingOn=True)
        except Exception:            # fmpy: "Failed to instantiate model" (a NULL instance)
            self.failed = True
            raise FmiCallError("instantiate", Status.FATAL, self) from None

    def bind(self) -> None:
        self.component = self.fmu.component
        self._set_reals = self._batched("set_real", self.in_vr, self.n_in, self.in_buf)
        self._get_reals = self._batched("get_real", self.out_vr, self.n_out, self.out_buf)
        self._get_booleans = self._batched("get_boolean", self.bool_vr, self.n_bool,
                                           self.bool_buf)
        self._step = self._function("do_step")
        self._get_state, self._set_state, self._free_state = (
            self._function(k) for k in ("get_state", "set_state", "free_state"))

    def _batched(self, call: str, vrs, n: int, values):
        """A raw get or set call with all its arguments bound: calling it makes the call."""
        counted = (n,) if self.VALUES_COUNTED else ()
        return partial(self._function(call), self.component, vrs, n, values, *counted)

    def _do_step(self, t: float, h: float) -> int:
        return self._step(self.component, t, h, not self.may_roll_back)

    def enter_initialization(self, stop: float) -> None:
        self._call("setupExperiment", self.fmu.setupExperiment, None, 0.0, stop)
        self._call("enterInitializationMode", self.fmu.enterInitializationMode)

    def set_parameter(self, variable, value) -> None:
        if kind_of(variable) == "Integer":
            self._call("setInteger", self.fmu.setInteger, [variable.valueReference],
                       [int(value)])
        else:
            self._call("setReal", self.fmu.setReal, [variable.valueReference], [float(value)])

    def exit_initialization(self) -> None:
        self._call("exitInitializationMode", self.fmu.exitInitializationMode)

    def release(self) -> None:
        """Terminate and free, but keep the library loaded for the next instance of this FMU
        (unloading pythonfmu's binary from a Python host is unsafe: pythonfmu_host.py)."""
        self._calling("terminate")
        try:
            self.fmu.terminate()
        except Exception:
            pass
        self._calling("freeInstance")
        self._function("free")(self.fmu.component)
        self.fmu.component = None
        self.instantiated = False
        _IDLE.setdefault(self.unzip_dir, []).append(self.fmu)
        self.fmu = None

    def get_state(self, slot) -> int:
        if slot:
            self._free_state(self.component, ctypes.byref(slot))
        return self._get_state(self.component, ctypes.byref(slot))

    def set_state(self, slot) -> int:
        return self._set_state(self.component, slot)

    def free_state(self, slot) -> None:
        if slot:
            self._free_state(self.component, ctypes.byref(slot))


class Fmi3Instance(Fmi2Instance):
    """An instance of an FMI 3.0 co-simulation FMU (fmpy's FMU3Slave): the same run through
    FMI 3.0's calls (Float64 for Real, the step's extra results, no setupExperiment)."""

    FMU_CLASS = FMU3Slave
    BOOLEAN = fmi3Boolean
    CALLS = {"set_real": "fmi3SetFloat64", "get_real": "fmi3GetFloat64",
             "get_boolean": "fmi3GetBoolean", "do_step": "fmi3DoStep",
             "get_state": "fmi3GetFMUState", "set_state": "fmi3SetFMUState",
             "free_state": "fmi3FreeFMUState", "free": "fmi3FreeInstance"}
    VALUES_COUNTED = True

    def _instantiate(self) -> None:
        # no event mode: sewfmu's masters step in co-simulation's step mode only
        try:
            self._take_library().instantiate(loggingOn=True,
                                             logMessage=self.log.for_fmi3(self.name))
        except Exception:            # fmpy: "Failed to instantiate FMU" (a NULL instance)
            self.failed = True
            raise FmiCallError("instantiate", Status.FATAL, self) from None

    def bind(self) -> None:
        super().bind()
        # doStep's results: event handling needed, terminate, early return, last successful
        # time (sewfmu's masters use no event mode and allow no early return)
        self._step_results = [fmi3Boolean(), fmi3Boolean(), fmi3Boolean(), fmi3Float64()]
        self._step_refs = [ctypes.byref(x) for x in self._step_results]

    def _do_step(self, t: float, h: float) -> int:
        return self._step(self.component, t, h, not self.may_roll_back, *self._step_refs)

    def enter_initialization(self, stop: float) -> None:
        self._call("enterInitializationMode", self.fmu.enterInitializationMode, None, 0.0, stop)

    def set_parameter(self, variable, value) -> None:
        setters = {"Float64": (self.fmu.setFloat64, float), "Int32": (self.fmu.setInt32, int),
                   "Int64": (self.fmu.setInt64, int)}
        if variable.type not in setters:
            raise ScenarioError(f"{self.name}.{variable.name}: a {variable.type} parameter "
                                f"cannot be set from a scenario")
        setter, convert = setters[variable.type]
        self._call(f"set{variable.type}", setter, [variable.valueReference], [convert(value)])
