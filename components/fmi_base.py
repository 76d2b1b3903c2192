"""The shared FMU layer: what every sewfmu FMU needs and pythonfmu does not give.

A concrete FMU subclasses `SewSlave` and declares, as class attributes, its parameter dataclass,
its inputs, outputs and calculated parameters and its default experiment; it implements
`build_model`, `initialize`, `advance` and `current_outputs`, which forward to the plain-Python
model. This class gives:

- a modelDescription that passes `fmpy validate`: units with SI base units, outputs and initial
  unknowns in ModelStructure, each output's dependency on the inputs declared (direct
  feedthrough or none), a DefaultExperiment;
- statuses as FMI 2.0 means them, within what pythonfmu 0.7.0 allows. pythonfmu turns every
  Python exception into fmi2Fatal (and 0.7.0 then keeps the interpreter lock), after which a host
  may call nothing, not even fmi2FreeInstance. So no exception leaves this class: a step the
  model cannot take (a NaN input, too many contact switches, a step too long for the switch
  search, a non-finite result, a call out of the standard's order) returns False from do_step,
  which pythonfmu reports as fmi2Discard, with an fmi2Error log line naming the cause, and the
  instance stays as it was before the step (the host may restore a state, terminate, free);
- parameters checked when the model is built at exitInitializationMode: a bad value or a linkage
  that cannot assemble is logged at fmi2Error naming the parameter (or the crank angle), and
  every later doStep is refused the same way (pythonfmu could only say so at exitInitialization-
  Mode through an exception, i.e. fmi2Fatal; see README "In other FMI tools");
- FMU state (get/set/serialize) that holds the model's internal state, so that a restored state
  repeats the following steps bit for bit;
- the co-simulation contract every sewfmu FMU follows:
    inputs set before doStep(t, h) are values at t;
    outputs after doStep(t, h) are values at t + h;
    outputs read after inputs were set reflect those inputs (declared direct feedthrough);
    inside a step, inputs are extrapolated from the derivative inputs the FMU is given (Taylor),
  so that a plain Jacobi master of another tool gets the same physics;
- no module-level mutable state: everything lives on the instance; the standard library only.
"""
from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, replace
from typing import Any, Callable, Sequence
from xml.etree.ElementTree import Element, SubElement

from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability
from pythonfmu.fmi2slave import Fmi2Slave
from pythonfmu.variables import Boolean, Integer, Real

from .kinematics import AssemblyError
from .parameters import ParameterError, parameter_info
from .units import UNITS

@dataclass(frozen=True)
class Port:
    """An input, output or calculated parameter of an FMU."""
    name: str
    unit: str
    description: str
    start: float = 0.0             # inputs only
    feedthrough: bool = False      # outputs only: depends on the inputs at the same instant
    kind: str = "Real"             # "Real" or "Boolean"
    source: str = ""               # linkage outputs: where in the model's motion the value is
                                   # ("E.x", "joints.M.vy"); default: the port's name


def shaft_inputs(omega: float) -> tuple[Port, Port, Port]:
    """The main shaft's motion, the inputs of every linkage (extrapolated inside a step), starting
    at the setup position φ = 0 and turning at `omega`: the mechanism's own default speed, so
    that a host that starts the inputs at their start values runs it at that speed."""
    return (
        Port("phi", "rad", "shaft angle, cumulative (the crank angle of the linkage)"),
        Port("omega", "rad/s", "shaft speed", start=omega),
        Port("epsilon", "rad/s2", "shaft angular acceleration"),
    )


SHAFT_TAYLOR = (("phi", "omega", "epsilon"),)

# a step must start where the last one ended, to within this fraction of max(1 s, |t|, h)
_TIME_TOLERANCE = 1e-9


class FmuError(RuntimeError):
    """A call the FMU refuses: a bad parameter, a linkage that cannot assemble, a NaN input."""


class SewSlave(Fmi2Slave):
    """Base of every sewfmu FMU; see the module docstring for what it adds to pythonfmu."""

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

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        if "logger" in kwargs:         # instantiated by pythonfmu's binary, not by its builder
            _forget_resources_path(kwargs.get("resources"))
        cls = type(self)
        self.modelName = cls.model_name or cls.__name__
        self.description = (cls.__doc__ or "").strip().splitlines()[0]
        self.default_experiment = DefaultExperiment(start_time=0.0, stop_time=cls.experiment[0],
                                                    step_size=cls.experiment[1])
        self._param_info = parameter_info(cls.params_class) if cls.params_class else []
        self._params = {p.name: p.default for p in self._param_info}
        self._inputs = {p.name: float(p.start) for p in cls.inputs}
        self._elapsed = 0.0            # time since the inputs were last set (for extrapolation)
        self._time = 0.0
        self._initialized = False      # exitInitializationMode has run
        self._broken: str | None = None   # why this instance cannot run (bad parameters)
        self._model = None
        self._cache: dict[str, Any] | None = None
        self._last_error = ""             # the getters log an error once, not at every call
        self._register_all()
        # value reference -> getter / setter, for the batched calls of every step
        self._getters = {vr: v.getter for vr, v in self.vars.items()}
        self._setters = {vr: v.setter for vr, v in self.vars.items() if v.setter is not None}
        self._types = {vr: type(v) for vr, v in self.vars.items()}
        self._real_getters = {vr: get for vr, get in self._getters.items()
                              if self._types[vr] is Real}
        self._real_setters = {vr: set_ for vr, set_ in self._setters.items()
                              if self._types[vr] is Real}

    # --- declaration ---------------------------------------------------------------------------
    def _register_all(self) -> None:
        for info in self._param_info:
            var_type = Integer if info.is_integer else Real
            self.register_variable(var_type(
                info.name, causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed,
                description=f"{info.description} [{info.unit}]",
                getter=self._param_getter(info.name), setter=self._param_setter(info.name)))
        for port in type(self).inputs:
            self.register_variable(Real(
                port.name, causality=Fmi2Causality.input, variability=Fmi2Variability.continuous,
                start=port.start, description=f"{port.description} [{port.unit}]",
                getter=self._input_getter(port.name), setter=self._input_setter(port.name)))
        for port in type(self).outputs:
            var_type = Boolean if port.kind == "Boolean" else Real
            variability = (Fmi2Variability.discrete if port.kind == "Boolean"
                           else Fmi2Variability.continuous)
            self.register_variable(var_type(
                port.name, causality=Fmi2Causality.output, variability=variability,
                initial=Fmi2Initial.calculated, description=f"{port.description} [{port.unit}]",
                getter=self._output_getter(port.name)))
        for port in type(self).calculated:
            self.register_variable(Real(
                port.name, causality=Fmi2Causality.calculatedParameter,
                variability=Fmi2Variability.fixed, initial=Fmi2Initial.calculated,
                description=f"{port.description} [{port.unit}]",
                getter=self._output_getter(port.name)))

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
        take), NaN with an fmi2Error log line saying why: a getter has no other way to refuse."""
        try:
            outputs = self.current_outputs()
        except Exception as err:          # noqa: BLE001 - any failure is reported, none escapes
            self._error_once(f"outputs unavailable: {_describe(err)}")
            return {p.name: (False if p.kind == "Boolean" else math.nan)
                    for p in (*type(self).outputs, *type(self).calculated)}
        bad = _non_finite(outputs)
        if bad:
            self._error_once(f"output {bad} is {outputs[bad]} at t = {self._time:g} s: the model "
                             f"has left the range where it computes (inputs or parameters too "
                             f"large?)", key=f"output {bad} is {outputs[bad]}")
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
        self.log(message, Fmi2Status.error)

    def _error_once(self, message: str, key: str | None = None) -> None:
        """Log an error, but not the same one (the same `key`) again at every getter call of a
        host's loop."""
        key = key or message
        if key != self._last_error:
            self._last_error = key
            self._error(message)

    def extrapolated_inputs(self, dt: float) -> dict[str, float]:
        """Inputs extrapolated by dt from the instant they were set: each `taylor_inputs` chain
        (x, x', x'', ...) by its Taylor polynomial (the last derivative held), others held."""
        u = dict(self._inputs)
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

    def _bad_input(self) -> str | None:
        for name, value in self._inputs.items():
            if not (isinstance(value, float) and math.isfinite(value)):
                return f"input {name} is {value} at t = {self._time:g} s"
        return None

    # --- FMI calls: none lets an exception reach pythonfmu -------------------------------------
    # pythonfmu's get_real/set_real check every variable's type on every call and raise on a
    # wrong one; these look the getter up directly (the hot path of a co-simulation step) and
    # answer an unknown value reference with a log line
    def get_real(self, vrs):
        try:
            return [float(self._real_getters[vr]()) for vr in vrs]
        except Exception:                 # noqa: BLE001 - an unknown reference: answered below
            return [self._get(vr, Real, float, math.nan) for vr in vrs]

    def get_integer(self, vrs):
        return [self._get(vr, Integer, int, 0) for vr in vrs]

    def get_boolean(self, vrs):
        return [self._get(vr, Boolean, bool, False) for vr in vrs]

    def get_string(self, vrs):
        return [self._get(vr, None, str, "") for vr in vrs]

    def _get(self, vr, kind, convert, missing):
        if self._types.get(vr) is not kind:
            self._error_once(f"fmi2Get{_KIND_NAME.get(kind, 'String')}: no such variable "
                             f"(value reference {vr})")
            return missing
        try:
            return convert(self._getters[vr]())
        except Exception as err:          # noqa: BLE001
            self._error_once(f"value reference {vr}: {_describe(err)}")
            return missing

    def set_real(self, vrs, values):
        try:
            setters = [self._real_setters[vr] for vr in vrs]
        except KeyError:                  # not a settable Real: answered below
            self._set(vrs, values, Real)
            return
        for set_value, value in zip(setters, values):
            set_value(value)

    def set_integer(self, vrs, values):
        self._set(vrs, values, Integer)

    def set_boolean(self, vrs, values):
        self._set(vrs, values, Boolean)

    def set_string(self, vrs, values):
        self._set(vrs, values, None)

    def _set(self, vrs, values, kind) -> None:
        for vr, value in zip(vrs, values):
            setter = self._setters.get(vr)
            if setter is None or self._types.get(vr) is not kind:
                name = self.vars[vr].name if vr in self.vars else f"value reference {vr}"
                self._error(f"fmi2Set{_KIND_NAME.get(kind, 'String')}: {name} cannot be set "
                            f"this way (value {value!r} ignored)")
                continue
            setter(value)

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._time = float(start_time)

    def exit_initialization_mode(self):
        self._initialized = True
        self._cache = None
        try:
            model = self.model()
            bad = self._bad_input()
            if bad:
                raise FmuError(f"{bad} at initialization")
            self.initialize(model)
        except Exception as err:          # noqa: BLE001
            self._broken = _describe(err)
            self._error(f"{self._broken}; every doStep of this instance will be refused")

    def do_step(self, current_time, step_size):
        t, h = float(current_time), float(step_size)
        # the usual case in one expression (this is the hot path); the reasons only when not
        if not (self._initialized and self._broken is None and 0.0 < h < math.inf
                and abs(t - self._time) <= _TIME_TOLERANCE * max(1.0, abs(t), h)
                and math.isfinite(sum(self._inputs.values()))):
            refusal = self._refusal(t, h) or "an input is not a finite number"
            self._error(f"doStep({t:g}, {h:g}) refused: {refusal}")
            return False
        saved = (self.save_internal(), self._elapsed, self._time)
        try:
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
            self._error(f"doStep({t:g}, {h:g}) discarded: {_describe(err)}")
            return False
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
                "broken": self._broken, "internal": self.save_internal()}

    def _set_fmu_state(self, state: dict[str, Any]) -> None:
        try:
            if state["params"] != self._params:
                self._model = None
            internal = state["internal"]
            self._params = dict(state["params"])
            self._inputs = dict(state["inputs"])
            self._elapsed = state["elapsed"]
            self._time = state["time"]
            self._initialized = state["initialized"]
            self._broken = state["broken"]
            self.restore_internal(internal)
            self._cache = None
        except Exception as err:          # noqa: BLE001 - a damaged or foreign state
            self._error(f"fmi2SetFMUstate: not a state of this FMU ({_describe(err)}); the "
                        f"instance is left as it was")

    @staticmethod
    def _fmu_state_from_bytes(state: bytes) -> dict[str, Any]:
        try:
            return json.loads(state.decode("utf-8"))
        except Exception as err:          # noqa: BLE001 - refused by _set_fmu_state
            return {"unreadable": _describe(err)}

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

    # --- modelDescription ----------------------------------------------------------------------
    def _port_units(self) -> dict[str, str]:
        units = {p.name: p.unit for p in self._param_info}
        for port in (*type(self).inputs, *type(self).outputs, *type(self).calculated):
            units[port.name] = port.unit
        return units

    def to_xml(self, model_options: dict[str, str] = dict()) -> Element:
        root = super().to_xml(model_options)
        units = self._port_units()
        used = set()
        # unit attributes on Real variables
        for sv in root.find("ModelVariables"):
            real = sv.find("Real")
            unit = units.get(sv.get("name"))
            if real is not None and unit is not None:
                real.set("unit", unit)
                used.add(unit)
        # UnitDefinitions go right after CoSimulation (FMI 2.0 schema order)
        unit_defs = Element("UnitDefinitions")
        for name in sorted(used):
            unit = SubElement(unit_defs, "Unit", name=name)
            SubElement(unit, "BaseUnit", {k: str(v) for k, v in UNITS[name].items()})
        index = list(root).index(root.find("CoSimulation")) + 1
        root.insert(index, unit_defs)
        # ModelStructure: outputs with their input dependencies, and the initial unknowns
        root.remove(root.find("ModelStructure"))
        structure = SubElement(root, "ModelStructure")
        index_of = {v.name: i + 1 for i, v in enumerate(self.vars.values())}
        input_indices = " ".join(str(index_of[p.name]) for p in type(self).inputs)
        n_inputs = len(type(self).inputs)

        def unknown(parent, port: Port) -> None:
            attrib = {"index": str(index_of[port.name])}
            if port.feedthrough and n_inputs:
                attrib["dependencies"] = input_indices
                attrib["dependenciesKind"] = " ".join(["dependent"] * n_inputs)
            else:
                attrib["dependencies"] = ""
                attrib["dependenciesKind"] = ""
            SubElement(parent, "Unknown", attrib)

        if type(self).outputs:
            outputs = SubElement(structure, "Outputs")
            for port in type(self).outputs:
                unknown(outputs, port)
        initial = SubElement(structure, "InitialUnknowns")
        for port in sorted((*type(self).outputs, *type(self).calculated),
                           key=lambda p: index_of[p.name]):
            # at initialization every unknown may depend on the parameters and inputs: no list
            SubElement(initial, "Unknown", {"index": str(index_of[port.name])})
        return root


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


_KIND_NAME = {Real: "Real", Integer: "Integer", Boolean: "Boolean"}


def _describe(err: Exception) -> str:
    """An exception as the one line a log needs: the model's own message, or what kind of
    failure it was."""
    text = str(err)
    # the models' own exceptions (parameters, assembly, step too long, chatter) say it for users
    if type(err).__module__.rpartition(".")[0] == __name__.rpartition(".")[0] and text:
        return text
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


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


def _forget_resources_path(resources: str | None) -> None:
    """pythonfmu puts the instance's resources folder first on sys.path at every instantiation
    (to import the FMU's script) and never takes it out: sys.path would grow with every instance,
    and the host's later imports would find the FMU's copies first. The FMU's modules are
    imported by now, so the entry is removed again."""
    if resources and resources in sys.path:
        sys.path.remove(resources)


def fields_of(obj) -> dict[str, Any]:
    """A (frozen) dataclass instance as a plain dict: outputs, or internal state to save."""
    return dict(vars(obj))
