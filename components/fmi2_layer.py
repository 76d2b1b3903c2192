"""The FMI 2.0 layer of a sewfmu FMU, on pythonfmu: the variables registered in FMI 2.0's
terms, its calls named, and a modelDescription that passes `fmpy validate` (pythonfmu's own lacks
the units, InitialUnknowns and output dependencies): units with SI base units, each output's
dependency on the inputs (direct feedthrough or none), a DefaultExperiment."""
from __future__ import annotations

from xml.etree.ElementTree import Element, SubElement

from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability
from pythonfmu.fmi2slave import Fmi2Slave
from pythonfmu.variables import Boolean, Integer, Real

from .slave import SewSlave
from .units import range_attributes, unit_definitions

_TYPES = {"Real": Real, "Integer": Integer, "Boolean": Boolean}


class Fmi2Layer(SewSlave, Fmi2Slave):
    """Joined after a concrete sewfmu slave class: `class MainShaft(MainShaftSlave, Fmi2Layer)`."""

    call_names = {kind: (f"fmi2Get{kind}", f"fmi2Set{kind}")
                  for kind in ("Real", "Integer", "Boolean", "String")}

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        stop, step = type(self).whole_step_experiment()
        self.default_experiment = DefaultExperiment(start_time=0.0, stop_time=stop,
                                                    step_size=step)

    def register_all(self) -> None:
        for v in self.variables:
            if v.causality == "output":
                extra = {"initial": Fmi2Initial.calculated,
                         "variability": (Fmi2Variability.discrete if v.discrete
                                         else Fmi2Variability.continuous)}
            elif v.causality == "calculatedParameter":
                extra = {"initial": Fmi2Initial.calculated, "variability": Fmi2Variability.fixed}
            elif v.causality == "input":
                extra = {"start": v.start, "variability": Fmi2Variability.continuous}
            else:
                extra = {"variability": Fmi2Variability.fixed}
            var = _TYPES[v.kind](v.name, causality=Fmi2Causality[v.causality],
                                 description=v.description, getter=v.getter, setter=v.setter,
                                 **extra)
            self.register_variable(var)
            self.remember(var.value_reference, v)

    def _error(self, message: str) -> None:
        self.log(self.error_line(message), Fmi2Status.error)

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._time = float(start_time)

    # pythonfmu's calls, answered by SewSlave without an exception (the Real ones, made at every
    # step, are SewSlave's own methods under pythonfmu's names: no call in between)
    get_real = SewSlave.get_reals
    set_real = SewSlave.set_reals

    def get_integer(self, vrs):
        return self.get_values(vrs, "Integer")

    def get_boolean(self, vrs):
        return self.get_values(vrs, "Boolean")

    def get_string(self, vrs):
        return self.get_values(vrs, "String")

    def set_integer(self, vrs, values):
        self.set_values(vrs, values, "Integer")

    def set_boolean(self, vrs, values):
        self.set_values(vrs, values, "Boolean")

    def set_string(self, vrs, values):
        self.set_values(vrs, values, "String")

    # --- modelDescription ----------------------------------------------------------------------
    def to_xml(self, model_options: dict[str, str] = dict()) -> Element:
        root = super().to_xml(model_options)
        declared = {v.name: v for v in self.variables}
        used = set()
        # unit attributes on Real variables; start values written exactly (pythonfmu writes 16
        # significant digits, which a host that sets the start values reads back 1 ulp off)
        for sv in root.find("ModelVariables"):
            real = sv.find("Real")
            v = declared.get(sv.get("name"))
            if real is not None and v is not None:
                for key, value in range_attributes(v).items():
                    real.set(key, value)
                used.add(v.unit)
                if real.get("start") is not None:
                    real.set("start", repr(float(v.getter())))
            integer = sv.find("Integer")
            if integer is not None and v is not None:
                for key, value in range_attributes(v).items():
                    integer.set(key, value)
        # UnitDefinitions go right after CoSimulation (FMI 2.0 schema order)
        unit_defs = Element("UnitDefinitions")
        unit_definitions(unit_defs, used)
        index = list(root).index(root.find("CoSimulation")) + 1
        root.insert(index, unit_defs)
        # ModelStructure: outputs with their input dependencies, and the initial unknowns
        root.remove(root.find("ModelStructure"))
        structure = SubElement(root, "ModelStructure")
        index_of = {v.name: i + 1 for i, v in enumerate(self.vars.values())}
        inputs = [v for v in self.variables if v.causality == "input"]
        input_indices = " ".join(str(index_of[v.name]) for v in inputs)

        outputs = [v for v in self.variables if v.causality == "output"]
        if outputs:
            listed = SubElement(structure, "Outputs")
            for v in outputs:
                attrib = {"index": str(index_of[v.name]), "dependencies": "",
                          "dependenciesKind": ""}
                if v.feedthrough and inputs:
                    attrib["dependencies"] = input_indices
                    attrib["dependenciesKind"] = " ".join(["dependent"] * len(inputs))
                SubElement(listed, "Unknown", attrib)
        initial = SubElement(structure, "InitialUnknowns")
        for v in self.variables:
            if v.causality in ("output", "calculatedParameter"):
                # at initialization every unknown may depend on the parameters and inputs
                SubElement(initial, "Unknown", {"index": str(index_of[v.name])})
        return root
