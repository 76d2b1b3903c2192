"""The shared FMU layer: what every sewfmu FMU needs and pythonfmu does not give.

A concrete FMU subclasses `SewSlave` and declares, as class attributes, its parameter dataclass,
its inputs, outputs and calculated parameters; it implements `build_model`, `initialize`,
`advance` and `current_outputs`, which forward to the plain-Python model. This class gives:

- a modelDescription that passes `fmpy validate`: units with SI base units, outputs and initial
  unknowns in ModelStructure, each output's dependency on the inputs declared (direct
  feedthrough or none);
- parameters checked when the model is built: a bad value or a linkage that cannot assemble is
  logged at status fmi2Error naming the parameter, and the call fails;
- inputs that are refused when NaN or infinite;
- FMU state (get/set/serialize) that holds the model's internal state, so that a restored state
  repeats the following steps bit for bit;
- the co-simulation contract every sewfmu FMU follows:
    inputs set before doStep(t, h) are values at t;
    outputs after doStep(t, h) are values at t + h;
    outputs read after inputs were set reflect those inputs (declared direct feedthrough);
    inside a step, inputs are extrapolated from the derivative inputs the FMU is given (Taylor),
  so that a plain Jacobi master of another tool gets the same physics;
- no module-level mutable state: everything lives on the instance.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Callable, Sequence
from xml.etree.ElementTree import Element, SubElement

from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability
from pythonfmu.fmi2slave import Fmi2Slave
from pythonfmu.variables import Boolean, Integer, Real

from .kinematics import AssemblyError
from .parameters import ParameterError, parameter_info

# SI base-unit exponents of every unit a sewfmu variable uses (FMI 2.0 BaseUnit attributes)
UNITS: dict[str, dict[str, int]] = {
    "1": {},
    "s": {"s": 1},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "m/s3": {"m": 1, "s": -3},
    "kg": {"kg": 1},
    "kg.m2": {"kg": 1, "m": 2},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N/m": {"kg": 1, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "N.m2": {"kg": 1, "m": 3, "s": -2},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "rad/s2": {"rad": 1, "s": -2},
}


@dataclass(frozen=True)
class Port:
    """An input, output or calculated parameter of an FMU."""
    name: str
    unit: str
    description: str
    start: float = 0.0             # inputs only
    feedthrough: bool = False      # outputs only: depends on the inputs at the same instant
    kind: str = "Real"             # "Real" or "Boolean"


# the main shaft's motion: the inputs of every linkage, extrapolated inside a step
SHAFT_INPUTS = (
    Port("phi", "rad", "shaft angle, cumulative (the crank angle of the linkage)"),
    Port("omega", "rad/s", "shaft speed"),
    Port("epsilon", "rad/s2", "shaft angular acceleration"),
)
SHAFT_TAYLOR = (("phi", "omega", "epsilon"),)


class FmuError(RuntimeError):
    """A call the FMU refuses: a bad parameter, a linkage that cannot assemble, a NaN input."""


class SewSlave(Fmi2Slave):
    """Base of every sewfmu FMU; see the module docstring for what it adds to pythonfmu."""

    author = "sewfmu"
    license = "MIT"
    params_class: type | None = None
    inputs: Sequence[Port] = ()
    outputs: Sequence[Port] = ()
    calculated: Sequence[Port] = ()
    model_name = ""                # the FMU's modelName / modelIdentifier
    # input chains (value, its rate[, its acceleration]) extrapolated inside a step by Taylor
    taylor_inputs: Sequence[tuple[str, ...]] = ()

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.modelName = type(self).model_name or type(self).__name__
        self.description = (type(self).__doc__ or "").strip().splitlines()[0]
        cls = type(self)
        self._param_info = parameter_info(cls.params_class) if cls.params_class else []
        self._params = {p.name: p.default for p in self._param_info}
        self._inputs = {p.name: float(p.start) for p in cls.inputs}
        self._elapsed = 0.0            # time since the inputs were last set (for extrapolation)
        self._time = 0.0
        self._model = None
        self._cache: dict[str, Any] | None = None
        self._register_all()
        # value reference -> getter / setter, for the batched calls of every step
        self._real_get = {vr: v.getter for vr, v in self.vars.items() if isinstance(v, Real)}
        self._real_set = {vr: v.setter for vr, v in self.vars.items()
                          if isinstance(v, Real) and v.setter is not None}

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
                self._cache = self._checked(self.current_outputs())
            return self._cache[name]
        return get_output

    def _checked(self, outputs: dict[str, Any]) -> dict[str, Any]:
        """Refuse to hand out a NaN or infinite output: never a silently wrong number."""
        for key, value in outputs.items():
            if isinstance(value, float) and not math.isfinite(value):
                self._fail(f"output {key} is {value} at t = {self._time:g} s: the model has left "
                           f"the range where it computes (inputs or parameters too large?)")
        return outputs

    # --- the model -----------------------------------------------------------------------------
    def model(self):
        """The plain-Python model for the current parameter values (built, and checked, once)."""
        if self._model is None:
            values = {}
            for info in self._param_info:
                value = self._params[info.name]
                values[info.name] = int(value) if info.is_integer else float(value)
            try:
                params = replace(type(self).params_class(), **values)
                self._model = self.build_model(params)
            except (ParameterError, AssemblyError) as err:
                self._fail(str(err))
        return self._model

    def _fail(self, message: str) -> None:
        """Log at status fmi2Error and raise: pythonfmu turns the exception into a failed call."""
        self.log(message, Fmi2Status.error)
        raise FmuError(message)

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

    def _check_inputs(self) -> None:
        for name, value in self._inputs.items():
            if not math.isfinite(value):
                self._fail(f"input {name} is {value} at t = {self._time:g} s; refusing to step")

    # --- FMI calls -----------------------------------------------------------------------------
    # pythonfmu's get_real/set_real check every variable's type on every call; these look the
    # getter up directly (the hot path of a co-simulation step)
    def get_real(self, vrs):
        try:
            getters = [self._real_get[vr] for vr in vrs]
        except KeyError as err:
            raise TypeError(f"variable with valueReference={err.args[0]} is not a Real") from None
        return [float(get()) for get in getters]

    def set_real(self, vrs, values):
        try:
            setters = [self._real_set[vr] for vr in vrs]
        except KeyError as err:
            raise TypeError(f"variable with valueReference={err.args[0]} is not a settable "
                            f"Real") from None
        for set_value, value in zip(setters, values):
            set_value(value)

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._time = float(start_time)

    def exit_initialization_mode(self):
        self._check_inputs()
        self.initialize(self.model())
        self._cache = None

    def do_step(self, current_time, step_size):
        self._check_inputs()
        self.advance(self.model(), float(current_time), float(step_size))
        self._time = float(current_time) + float(step_size)
        self._elapsed += float(step_size)
        self._cache = None
        return True

    # --- FMU state: the model's internal state is part of it -----------------------------------
    def _get_fmu_state(self) -> dict[str, Any]:
        return {"params": dict(self._params), "inputs": dict(self._inputs),
                "elapsed": self._elapsed, "time": self._time, "internal": self.save_internal()}

    def _set_fmu_state(self, state: dict[str, Any]) -> None:
        if state["params"] != self._params:
            self._model = None
        self._params = dict(state["params"])
        self._inputs = dict(state["inputs"])
        self._elapsed = state["elapsed"]
        self._time = state["time"]
        self.restore_internal(state["internal"])
        self._cache = None

    # --- what each FMU provides ----------------------------------------------------------------
    def build_model(self, params):
        raise NotImplementedError

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


def fields_of(obj) -> dict[str, Any]:
    """A (frozen) dataclass instance as a plain dict: outputs, or internal state to save."""
    return dict(vars(obj))
