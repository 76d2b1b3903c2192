"""What every sewfmu FMU does, whichever FMI version carries it.

A concrete FMU subclasses `SewSlave` (or `LinkageSlave`) and declares, as class attributes, its
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

import json
import math
from dataclasses import dataclass, replace
from typing import Any, Callable, Sequence

from .kinematics import AssemblyError
from .parameters import ParameterError, parameter_info
from .ports import SHAFT_TAYLOR, Port, held_note, input_bound, input_ranges, shaft_inputs
from .pythonfmu_quirks import (
    ExceptionFreeAccess,
    describe,
    forget_resources_path,
    release_state_at_exit,
)

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


class SewSlave(ExceptionFreeAccess):
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
        self.description = (cls.__doc__ or "").strip().splitlines()[0]
        self._param_info = parameter_info(cls.params_class) if cls.params_class else []
        self._params = {p.name: p.default for p in self._param_info}
        self._inputs = {p.name: float(p.start) for p in cls.inputs}
        self._ranges = input_ranges(cls.inputs)
        # rate inputs the host does not give: see held_inputs
        self._set_since_step: set[str] = set()    # inputs set since the last step taken
        self._held: set[str] = set()              # rates that act as zero
        self._elapsed = 0.0            # time since the inputs were last set (for extrapolation)
        self._time = 0.0
        self._initialized = False      # exitInitializationMode has run
        self._broken: str | None = None   # why this instance cannot run (bad parameters)
        self._model = None
        self._cache: dict[str, Any] | None = None
        self._last_error = ""             # the getters log an error once, not at every call
        self.variables = self._declare()
        # value reference -> getter / setter / kind, filled by the layer's register_all
        self._getters: dict[int, Callable[[], Any]] = {}
        self._setters: dict[int, Callable[[Any], None]] = {}
        self._kinds: dict[int, str] = {}
        self._names: dict[int, str] = {}
        self.register_all()
        # the Real ones apart: the batched calls of every step look them up directly
        self._real_getters = {vr: get for vr, get in self._getters.items()
                              if self._kinds[vr] == "Real"}
        self._real_setters = {vr: set_ for vr, set_ in self._setters.items()
                              if self._kinds[vr] == "Real"}

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
            self._elapsed = 0.0
            self._cache = None
        return set_input

    def _output_getter(self, name: str) -> Callable[[], Any]:
        def get_output():
            if self._cache is None:
                self._cache = self._outputs_or_nan()
            return self._cache[name]
        return get_output

    def _outputs_or_nan(self) -> dict[str, Any]:
        """The outputs now; where the model cannot give them (bad parameters, inputs it cannot
        take), NaN with an Error log line saying why: a getter has no other way to refuse."""
        try:
            outputs = self.current_outputs()
        except Exception as err:          # noqa: BLE001 - any failure is reported, none escapes
            # a NaN input is the cause, not what the model then fails on (a linkage given a NaN
            # angle finds pivots that coincide): name it, to lead to the FMU that failed first
            self._error_once(f"outputs unavailable: {self._nan_input() or describe(err)}")
            return {p.name: (False if p.kind == "Boolean" else math.nan)
                    for p in (*type(self).outputs, *type(self).calculated)}
        bad = _non_finite(outputs)
        if bad:
            cause = self._nan_input() or ("the model has left the range where it computes "
                                          "(inputs or parameters too large?)")
            self._error_once(f"output {bad} is {outputs[bad]} at t = {self._time:g} s: {cause}",
                             key=f"output {bad} is {outputs[bad]}")
        return outputs

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
        held = self._note_held_rates()
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
        return held

    def extrapolated_inputs(self, dt: float) -> dict[str, float]:
        """Inputs extrapolated by dt from the instant they were set: each `taylor_inputs` chain
        (x, x', x'', ...) by its Taylor polynomial (the last derivative held), others held."""
        u = self.held_inputs()
        if dt == 0.0:              # read at the instant the inputs were set: nothing to add
            return u
        for chain in type(self).taylor_inputs:
            values = [u[name] for name in chain]
            for k, name in enumerate(chain[:-1]):
                total, term = 0.0, 1.0
                for j, x in enumerate(values[k:]):
                    if j:
                        term *= dt / j
                    total += x * term
                u[name] = total
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
        if not (self._initialized and self._broken is None and 0.0 < h < math.inf
                and abs(t - self._time) <= _TIME_TOLERANCE * max(1.0, abs(t), h)
                and math.isfinite(sum(self._inputs.values()))
                and all(-bound <= self._inputs[name] <= bound
                        for name, bound, _ in self._ranges)):
            refusal = self._refusal(t, h)
            if refusal:
                self._error(f"doStep({t:g}, {h:g}) refused: {refusal}")
                return False
        saved = (self.save_internal(), self._elapsed, self._time)
        try:
            self._note_held_rates()       # which rates act as zero, from what was set
            self.advance(self.model(), t, h)
            self._time = t + h
            self._elapsed += h
            self._cache = None
            # a state that is no longer finite is not a state: the step is not taken (outputs
            # that overflow from finite state are reported by the getters)
            bad = _non_finite(self.save_internal())
            if bad:
                raise FmuError(f"{bad} would be {self.save_internal()[bad]} at t = {t + h:g} s: "
                               f"the model has left the range where it computes (inputs or "
                               f"parameters too large?)")
        except Exception as err:          # noqa: BLE001 - the step is not taken, whatever failed
            internal, self._elapsed, self._time = saved
            self.restore_internal(internal)
            self._cache = None
            self._error(f"doStep({t:g}, {h:g}) discarded: {describe(err)}")
            return False
        self._set_since_step.clear()
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

    # --- FMU state: the model's internal state is part of it -----------------------------------
    def _get_fmu_state(self) -> dict[str, Any]:
        return {"params": dict(self._params), "inputs": dict(self._inputs),
                "elapsed": self._elapsed, "time": self._time, "initialized": self._initialized,
                "broken": self._broken, "internal": self.save_internal(),
                "layer": self.save_layer(),
                "rates": [sorted(self._set_since_step), sorted(self._held)]}

    def _set_fmu_state(self, state: dict[str, Any]) -> None:
        try:
            if state["params"] != self._params:
                self._model = None
            internal, layer = state["internal"], state["layer"]   # a foreign state fails here
            fresh, held = state["rates"]
            self._params = dict(state["params"])
            self._inputs = dict(state["inputs"])
            self._elapsed = state["elapsed"]
            self._time = state["time"]
            self._initialized = state["initialized"]
            self._broken = state["broken"]
            self.restore_internal(internal)
            self.restore_layer(layer)
            self._set_since_step, self._held = set(fresh), set(held)
            self._cache = None
        except Exception as err:          # noqa: BLE001 - a damaged or foreign state
            self._error(f"SetFMUState: not a state of this FMU ({describe(err)}); the "
                        f"instance is left as it was")

    @staticmethod
    def _fmu_state_to_bytes(state: dict[str, Any]) -> bytes:
        return json.dumps(state).encode("utf-8")

    @staticmethod
    def _fmu_state_from_bytes(state: bytes) -> dict[str, Any]:
        try:
            return json.loads(state.decode("utf-8"))
        except Exception as err:          # noqa: BLE001 - refused by _set_fmu_state
            return {"unreadable": describe(err)}

    def save_layer(self) -> dict[str, Any]:
        """What the FMI layer keeps of its own, as plain JSON-able values."""
        return {}

    def restore_layer(self, saved: dict[str, Any]) -> None:
        pass

    # --- what each FMU provides ----------------------------------------------------------------
    def build_model(self, params):
        return type(self).model_class(params)

    def initialize(self, model) -> None:
        """Set the internal state from the parameters and the inputs set during initialization."""

    def advance(self, model, t: float, h: float) -> None:
        """Advance the internal state from t to t + h."""

    def current_outputs(self) -> dict[str, Any]:
        raise NotImplementedError

    def save_internal(self) -> dict[str, Any]:
        """The internal state as plain JSON-able values."""
        return {}

    def restore_internal(self, saved: dict[str, Any]) -> None:
        pass


class LinkageSlave(SewSlave):
    """An FMU of a linkage driven by the main shaft: its model's `motion(φ, ω, ε)` at the
    extrapolated shaft inputs gives every output (all direct feedthrough), each read from the
    motion where its port's `source` says. A linkage FMU only declares."""

    taylor_inputs = SHAFT_TAYLOR
    speed = 100.0                  # rad/s: the start value of the input omega

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        cls.inputs = shaft_inputs(cls.speed)
        # each output's path into the motion, split once
        cls._paths = tuple((port.name, tuple((port.source or port.name).split(".")))
                           for port in cls.outputs)

    def current_outputs(self):
        u = self.extrapolated_inputs(self._elapsed)
        motion = self.model().motion(u["phi"], u["omega"], u["epsilon"])
        return {name: float(_pick(motion, path)) for name, path in type(self)._paths}


def _pick(value, path: tuple[str, ...]):
    for key in path:
        value = value[key] if isinstance(value, dict) else getattr(value, key)
    return value


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
    """A (frozen) dataclass instance as a plain dict: outputs, or internal state to save."""
    return dict(vars(obj))
