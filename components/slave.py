"""What every sewfmu FMU does, whichever FMI version carries it.

A concrete FMU subclasses `SewSlave` (or linkage_slave.LinkageSlave) and declares, as class attributes, its
parameter dataclass, its inputs, outputs and calculated parameters and its default experiment;
it implements `build_model`, `initialize`, `advance` and `current_outputs`, which forward to the
plain-Python model. It is not an FMU by itself: `sewfmu build` joins it with the layer of one FMI
version (fmi2_layer.Fmi2Layer on pythonfmu, fmi3_layer.Fmi3Layer on pythonfmu3), which registers
`self.variables` in its own terms, writes its modelDescription and names its calls. This class
gives, the same for both:

- statuses as the standard means them, within what pythonfmu allows. pythonfmu turns every
  Python exception into Fatal (and then keeps the interpreter lock), after which a host may call
  nothing, not even FreeInstance. So no exception leaves this class: a step the model cannot
  take (a NaN input, too many contact switches, a step too long for the switch search, a
  non-finite result, a call out of the standard's order) returns False from do_step, which
  pythonfmu reports as Discard, with an Error log line naming the cause, and the instance stays
  as it was before the step (the host may restore a state, terminate, free);
- parameters checked when the model is built at exitInitializationMode: a bad value or a linkage
  that cannot assemble is logged at Error naming the parameter (or the crank angle), and every
  later doStep is refused the same way (pythonfmu could only say so at exitInitializationMode
  through an exception, i.e. Fatal; see docs/fmi.md);
- FMU state (get/set/serialize) that holds the model's internal state, so that a restored state
  repeats the following steps bit for bit;
- the co-simulation contract every sewfmu FMU follows:
    inputs set before doStep(t, h) are values at t;
    outputs after doStep(t, h) are values at t + h;
    outputs read after inputs were set reflect those inputs (declared direct feedthrough);
    inside a step, inputs are extrapolated from the derivative inputs the FMU is given (Taylor),
  so that a plain Jacobi master of another tool gets the same physics;
    a rate input (x_dot of x, x_ddot of x_dot) counts only while the host gives it: one that was
  not set since its value input was acts as zero (a zero-order hold of the value), so a host
  that connects only the values gets held inputs, never an extrapolation from a start value;
- no module-level mutable state: everything lives on the instance; the standard library only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Callable, Sequence

from .fmu_state import FmuState
from .kinematics import AssemblyError
from .parameters import ParameterError, parameter_info
from .ports import Port, held_note, input_bound, input_ranges
from .pythonfmu_quirks import ExceptionFreeAccess, describe, forget_resources_path, release_state_at_exit

# a step must start where the last one ended, to within this fraction of max(1 s, |t|, h)
_TIME_TOLERANCE = 1e-9


class FmuError(RuntimeError):
    """A call the FMU refuses: a bad parameter, a linkage that cannot assemble, a NaN input."""


@dataclass(frozen=True)
class Variable:
    """One variable of an FMU as both FMI versions declare it (each in its own words: Real or
    Float64, Integer or Int32)."""
    name: str
    kind: str                      # "Real", "Integer" or "Boolean"
    causality: str                 # "parameter", "input", "output" or "calculatedParameter"
    description: str               # with the unit in brackets, for tools that show no units
    unit: str
    getter: Callable[[], Any]
    setter: Callable[[Any], None] | None = None
    start: Any = None              # parameters and inputs
    feedthrough: bool = False      # outputs: depends on the inputs at the same instant
    discrete: bool = False         # outputs: changes only at communication points
    min: float | None = None       # parameters and inputs: the declared range
    max: float | None = None


class SewSlave(ExceptionFreeAccess, FmuState):
    """Base of every sewfmu FMU; see the module docstring for what it adds to pythonfmu. An FMI
    layer comes after it in the class's bases and provides `_error(message)`, the register
    of `self.variables` and the names of its calls (`call_names`)."""

    author = "sewfmu"
    license = "MIT"
    params_class: type | None = None
    model_class: type | None = None   # built from an instance of params_class
    inputs: Sequence[Port] = ()
    outputs: Sequence[Port] = ()
    calculated: Sequence[Port] = ()
    model_name = ""                # the FMU's modelName / modelIdentifier
    # input chains (value, its rate[, its acceleration]) extrapolated inside a step by Taylor
    taylor_inputs: Sequence[tuple[str, ...]] = ()
    # DefaultExperiment (stop time, step size): the FMU run alone shows its mechanism working
    experiment: tuple[float, float] = (1.0, 1e-3)
    # the layer's names of the calls, for log lines: kind -> (getter, setter)
    call_names: dict[str, tuple[str, str]] = {}

    @classmethod
    def whole_step_experiment(cls) -> tuple[float, float]:
        """The DefaultExperiment (stop time, step size) in whole, even steps: the longest step
        not above the declared one, so that a fixed-step host ends exactly at the stop time."""
        stop, step = cls.experiment
        return stop, stop / max(1, math.ceil(stop / step * (1.0 - 1e-12)))

    def __init__(self, **kwargs):
        super().__init__(**kwargs)     # the layer's pythonfmu base
        if "logger" in kwargs:         # instantiated by pythonfmu's binary, not by its builder
            forget_resources_path(kwargs.get("resources"))
            release_state_at_exit(kwargs.get("resources"))
        cls = type(self)
        self.modelName = cls.model_name or cls.__name__
        self._row_names = tuple(p.name for p in (*cls.outputs, *cls.calculated))
        self.description = (cls.__doc__ or "").strip().splitlines()[0]
        self._param_info = parameter_info(cls.params_class) if cls.params_class else []
        self._params = {p.name: p.default for p in self._param_info}
        self._inputs = {p.name: float(p.start) for p in cls.inputs}
        self._ranges = input_ranges(cls.inputs)
        # rate inputs the host does not give: see held_inputs
        self._set_since_step: set[str] = set()    # inputs set since the last step taken
        self._held: set[str] = set()              # rates that act as zero
        self._held_stale = True        # _held is to be worked out again from what was set
        self._elapsed = 0.0            # time since the inputs were last set (for extrapolation)
        self._time = 0.0
        self._initialized = False      # exitInitializationMode has run
        self._broken: str | None = None   # why this instance cannot run (bad parameters)
        self._model = None
        self._cache: list | None = None   # the outputs now, in the order of _row_names
        self._last_error = ""             # the getters log an error once, not at every call
        self.variables = self._declare()
        # value reference -> getter / setter / kind, filled by the layer's register_all
        self._getters: dict[int, Callable[[], Any]] = {}
        self._setters: dict[int, Callable[[Any], None]] = {}
        self._kinds: dict[int, str] = {}
        self._names: dict[int, str] = {}
        self.register_all()
        # a model without internal state (a linkage, the shaft): nothing to keep for a step
        self._stateless = cls.save_internal is SewSlave.save_internal
        # the Real ones apart: the batched calls of every step look them up directly
        self._real_getters = {vr: get for vr, get in self._getters.items()
                              if self._kinds[vr] == "Real"}
        self._real_setters = {vr: set_ for vr, set_ in self._setters.items()
                              if self._kinds[vr] == "Real"}
        # the tables of every step's calls (pythonfmu_quirks.ExceptionFreeAccess): an output's
        # place in the row of outputs, the input a Real value reference sets
        slot = {name: i for i, name in enumerate(self._row_names)}
        outputs = {v.name: v.kind for v in self.variables
                   if v.causality in ("output", "calculatedParameter")}
        self._real_slots = {vr: slot[name] for vr, name in self._names.items()
                            if outputs.get(name) == "Real" and self._kinds[vr] == "Real"}
        self._bool_slots = {vr: slot[name] for vr, name in self._names.items()
                            if outputs.get(name) == "Boolean" and self._kinds[vr] == "Boolean"}
        self._input_names = {vr: name for vr, name in self._names.items()
                             if name in self._inputs and vr in self._real_setters}
        self._read_vrs, self._read_places = None, []   # get_reals: the last read, their places

    # --- declaration ---------------------------------------------------------------------------
    def _declare(self) -> list[Variable]:
        """Every variable, in the order of value references: parameters, inputs, outputs,
        calculated parameters."""
        cls = type(self)
        declared = [Variable(info.name, "Integer" if info.is_integer else "Real", "parameter",
                             f"{info.description} [{info.unit}]", info.unit,
                             self._param_getter(info.name), self._param_setter(info.name),
                             start=info.default, min=info.bounds[0], max=info.bounds[1])
                    for info in self._param_info]
        rate_of = {rate: value for chain in cls.taylor_inputs
                   for value, rate in zip(chain, chain[1:])}
        declared += [Variable(port.name, "Real", "input",
                              f"{port.description} [{port.unit}]" + held_note(port.name, rate_of),
                              port.unit, self._input_getter(port.name),
                              self._input_setter(port.name), start=float(port.start),
                              min=None if input_bound(port) is None else -input_bound(port),
                              max=input_bound(port))
                     for port in cls.inputs]
        declared += [Variable(port.name, port.kind, "output",
                              f"{port.description} [{port.unit}]", port.unit,
                              self._output_getter(port.name), feedthrough=port.feedthrough,
                              discrete=port.discrete or port.kind == "Boolean")
                     for port in cls.outputs]
        declared += [Variable(port.name, "Real", "calculatedParameter",
                              f"{port.description} [{port.unit}]", port.unit,
                              self._output_getter(port.name))
                     for port in cls.calculated]
        return declared

    def remember(self, vr: int, variable: Variable) -> None:
        """The layer tells under which value reference it registered a variable."""
        self._getters[vr] = variable.getter
        if variable.setter is not None:
            self._setters[vr] = variable.setter
        self._kinds[vr] = variable.kind
        self._names[vr] = variable.name

    def _param_getter(self, name: str) -> Callable[[], Any]:
        return lambda: self._params[name]

    def _param_setter(self, name: str) -> Callable[[Any], None]:
        def set_param(value):
            if self._initialized:      # variability "fixed": FMI forbids it after initialization
                self._error(f"parameter {name} is fixed: it cannot change after "
                            f"exitInitializationMode (value {value!r} ignored)")
                return
            self._params[name] = value
            self._model = None        # rebuilt (and checked) with the new value when next needed
            self._cache = None
        return set_param

    def _input_getter(self, name: str) -> Callable[[], float]:
        return lambda: self._inputs[name]

    def _input_setter(self, name: str) -> Callable[[float], None]:
        def set_input(value):
            self._inputs[name] = value
            self._set_since_step.add(name)
            self._held_stale = True
            self._elapsed = 0.0
            self._cache = None
        return set_input

    def _output_getter(self, name: str) -> Callable[[], Any]:
        index = self._row_names.index(name)

        def get_output():
            row = self._cache
            if row is None:
                row = self._fill_cache()
            return row[index]
        return get_output

    def _fill_cache(self) -> list:
        """The outputs now, kept until an input, a parameter, the time or the state changes;
        where the model cannot give them (bad parameters, inputs it cannot take), NaN with an
        Error log line saying why: a getter has no other way to refuse."""
        try:
            row = self.output_row()
        except Exception as err:          # noqa: BLE001 - any failure is reported, none escapes
            # a NaN input is the cause, not what the model then fails on (a linkage given a NaN
            # angle finds pivots that coincide): name it, to lead to the FMU that failed first
            self._error_once(f"outputs unavailable: {self._nan_input() or describe(err)}")
            row = [False if p.kind == "Boolean" else math.nan
                   for p in (*type(self).outputs, *type(self).calculated)]
            self._cache = row
            return row
        try:
            finite = math.isfinite(sum(row))   # the common case, in one C loop
        except TypeError:                      # lists among the values
            finite = False
        if not finite:
            outputs = dict(zip(self._row_names, row))
            bad = _non_finite(outputs)
            if bad:
                cause = self._nan_input() or ("the model has left the range where it computes "
                                              "(inputs or parameters too large?)")
                self._error_once(f"output {bad} is {outputs[bad]} at t = {self._time:g} s: "
                                 f"{cause}", key=f"output {bad} is {outputs[bad]}")
        self._cache = row
        return row

    # --- the model -----------------------------------------------------------------------------
    def model(self):
        """The plain-Python model for the current parameter values (built, and checked, once).
        Raises FmuError naming the parameter (or the crank angle) if it cannot be built."""
        if self._model is None:
            values = {}
            for info in self._param_info:
                value = self._params[info.name]
                values[info.name] = int(value) if info.is_integer else float(value)
            try:
                params = replace(type(self).params_class(), **values)
                self._model = self.build_model(params)
            except (ParameterError, AssemblyError) as err:
                raise FmuError(str(err)) from None
        return self._model

    def _error(self, message: str) -> None:
        """Log an Error line (the FMI layer logs in its version's terms, as `error_line`)."""
        raise NotImplementedError("the FMI layer logs")

    def error_line(self, message: str) -> str:
        """An Error line as every host can show it: naming this instance and its FMU (a
        container FMU passes its components' lines on under its own name; FMI 3.0 passes no
        name), and without '%' (FMI 2.0's logger is printf-like: hosts and containers pass a
        line on as the format, and a '%s' in one crashed fmpy with the container FMU)."""
        name = getattr(self, "instance_name", "") or "?"
        return f"{name} ({self.modelName}): {message}".replace("%", " percent")

    def _error_once(self, message: str, key: str | None = None) -> None:
        """Log an error, but not the same one (the same `key`) again at every getter call of a
        host's loop."""
        key = key or message
        if key != self._last_error:
            self._last_error = key
            self._error(message)

    def held_inputs(self) -> dict[str, float]:
        """The inputs as the model takes them at the instant they were set: a rate the host did
        not set since it set the value it is the rate of acts as zero, and so do the rates of a
        rate that does. A host that connects only the values (libcosim, ecos, a hand-written
        loop) so gets a zero-order hold of them, and a value set once stays where it was set;
        a host that gives the rates gets the Taylor extrapolation. A rate set again counts
        again; where the host set nothing (the FMU run alone), the start values stand."""
        held = self._note_held_rates() if self._held_stale else self._held
        if not held:
            return dict(self._inputs)
        return {name: (0.0 if name in held else x) for name, x in self._inputs.items()}

    def _note_held_rates(self) -> set[str]:
        """Which rates act as zero, from what the host set since the last step (see
        held_inputs)."""
        fresh, held = self._set_since_step, self._held
        for chain in type(self).taylor_inputs:
            for value, rate in zip(chain, chain[1:]):
                if rate in fresh:
                    held.discard(rate)
                elif value in fresh or value in held:
                    held.add(rate)
        # the same again until an input is set or a step ends: one pass reaches the fixpoint
        self._held_stale = False
        return held

    def extrapolated_inputs(self, dt: float) -> dict[str, float]:
        """Inputs extrapolated by dt from the instant they were set: each `taylor_inputs` chain
        (x, x', x'', ...) by its Taylor polynomial (the last derivative held), others held."""
        u = self.held_inputs()
        if dt == 0.0:              # read at the instant the inputs were set: nothing to add
            return u
        # the terms dt^j / j!, each as (((1 * dt/1) * dt/2) ...), and each sum from 0.0 in the
        # order of the chain: the arithmetic of the loop `total += x * term` written out
        t1 = 1.0 * (dt / 1)
        t2 = t1 * (dt / 2)
        for chain in type(self).taylor_inputs:     # (the others: _taylor, the loop itself)
            if len(chain) == 3:
                x0, x1, x2 = u[chain[0]], u[chain[1]], u[chain[2]]
                u[chain[0]] = 0.0 + x0 * 1.0 + x1 * t1 + x2 * t2
                u[chain[1]] = 0.0 + x1 * 1.0 + x2 * t1
            else:
                _taylor(u, chain, dt)
        return u

    def _nan_input(self) -> str | None:
        # a NaN input comes from an FMU that failed first (or a host's mistake): say where to look
        for name, value in self._inputs.items():
            if not (isinstance(value, float) and math.isfinite(value)):
                return (f"input {name} is {value} at t = {self._time:g} s (the FMU or host that "
                        f"gives it failed first: see its error)")
        return None

    def _bad_input(self) -> str | None:
        nan = self._nan_input()
        if nan:
            return nan
        for name, bound, unit in self._ranges:
            value = self._inputs[name]
            if not -bound <= value <= bound:
                return (f"input {name} = {value:.6g} {unit} at t = {self._time:g} s is outside "
                        f"its range [{-bound:g}, {bound:g}] {unit}: a co-simulation that "
                        f"diverges, or a value in another unit")
        return None

    # --- the life of an instance ---------------------------------------------------------------
    def exit_initialization_mode(self):
        self._initialized = True
        self._cache = None
        try:
            model = self.model()
            bad = self._bad_input()
            if bad:
                raise FmuError(f"at initialization: {bad}")
            self.initialize(model)
        except Exception as err:          # noqa: BLE001
            self._broken = describe(err)
            self._error(f"{self._broken}; every doStep of this instance will be refused")

    def do_step(self, current_time, step_size):
        t, h = float(current_time), float(step_size)
        # the usual case in one expression (this is the hot path); the reasons only when not
        inputs = self._inputs
        usual = (self._initialized and self._broken is None and 0.0 < h < math.inf
                 and abs(t - self._time) <= _TIME_TOLERANCE * max(1.0, abs(t), h)
                 and math.isfinite(sum(inputs.values())))
        if usual:
            for name, bound, _ in self._ranges:
                if not -bound <= inputs[name] <= bound:
                    usual = False
                    break
        if not usual:
            refusal = self._refusal(t, h)
            if refusal:
                self._error(f"doStep({t:g}, {h:g}) refused: {refusal}")
                return False
        stateless = self._stateless
        saved = (None if stateless else self.snapshot(), self._elapsed, self._time)
        try:
            if self._held_stale:
                self._note_held_rates()   # which rates act as zero, from what was set
            model = self._model           # built already but before the first step: no call
            self.advance(model if model is not None else self.model(), t, h)
            self._time = t + h
            self._elapsed += h
            self._cache = None
            # a state that is no longer finite is not a state: the step is not taken (outputs
            # that overflow from finite state are reported by the getters)
            if not (stateless or self.state_is_finite()):
                bad = _non_finite(self.save_internal())
                if bad:
                    raise FmuError(f"{bad} would be {self.save_internal()[bad]} at "
                                   f"t = {t + h:g} s: the model has left the range where it "
                                   f"computes (inputs or parameters too large?)")
        except Exception as err:          # noqa: BLE001 - the step is not taken, whatever failed
            internal, self._elapsed, self._time = saved
            if not stateless:
                self.restore_snapshot(internal)
            self._cache = None
            self._error(f"doStep({t:g}, {h:g}) discarded: {describe(err)}")
            return False
        if self._set_since_step:
            self._set_since_step.clear()
            self._held_stale = bool(self._held)   # (a rate set alone may now be held)
        return True

    def _refusal(self, t: float, h: float) -> str | None:
        """Why a doStep(t, h) cannot be taken at all, or None."""
        if not self._initialized:
            return "called before exitInitializationMode"
        if self._broken:
            return self._broken
        if not (math.isfinite(h) and h > 0.0):
            return f"the step size must be positive and finite, got {h!r}"
        if not (math.isfinite(t) and abs(t - self._time)
                <= _TIME_TOLERANCE * max(1.0, abs(t), h)):
            return (f"the step starts at t = {t!r} s, but the last one ended at "
                    f"t = {self._time!r} s")
        return self._bad_input()

    # --- what each FMU provides ----------------------------------------------------------------
    def build_model(self, params):
        return type(self).model_class(params)

    def initialize(self, model) -> None:
        """Set the internal state from the parameters and the inputs set during initialization."""

    def advance(self, model, t: float, h: float) -> None:
        """Advance the internal state from t to t + h."""

    def current_outputs(self) -> dict[str, Any]:
        raise NotImplementedError

    def output_row(self) -> list | tuple:
        """The outputs and calculated parameters now, in their declared order (what the getters
        read; an FMU may give them without the dict of current_outputs)."""
        outputs = self.current_outputs()
        return [outputs[name] for name in self._row_names]

    def snapshot(self):
        """The internal state to come back to if a step fails (restore_snapshot): no copy where
        the state is immutable."""
        return self.save_internal()

    def restore_snapshot(self, snapshot) -> None:
        self.restore_internal(snapshot)

    def state_is_finite(self) -> bool:
        """Whether the internal state is surely finite (False: look closer, _non_finite)."""
        return not self.save_internal()

    def save_internal(self) -> dict[str, Any]:
        """The internal state as plain JSON-able values."""
        return {}

    def restore_internal(self, saved: dict[str, Any]) -> None:
        pass


def _taylor(u: dict[str, float], chain: tuple[str, ...], dt: float) -> None:
    values = [u[name] for name in chain]
    for k, name in enumerate(chain[:-1]):
        total, term = 0.0, 1.0
        for j, x in enumerate(values[k:]):
            if j:
                term *= dt / j
            total += x * term
        u[name] = total


def _non_finite(values: dict[str, Any]) -> str | None:
    """The first of the values (numbers, or lists of numbers) that is or holds a NaN or an
    infinite float, or None."""
    try:
        if math.isfinite(sum(values.values())):   # the common case, in one C loop
            return None
    except TypeError:                             # lists among the values
        pass
    for key, value in values.items():
        items = value if isinstance(value, (list, tuple)) else (value,)
        if any(isinstance(x, float) and not math.isfinite(x) for x in items):
            return key
    return None


def fields_of(obj) -> dict[str, Any]:
    """A named tuple or a dataclass instance as a plain dict: outputs, or the state to save."""
    return obj._asdict() if isinstance(obj, tuple) else dict(vars(obj))
