"""The FMI 3.0 layer of a sewfmu FMU, on pythonfmu3: the same variables, units, descriptions,
structure and default experiment as the FMI 2.0 layer, in FMI 3.0's terms (Float64, Int32,
value references in ModelStructure, an independent variable `time`).

pythonfmu3 0.3.4 is used for its binary and its builder only: the variables are not its
objects (its own modelDescription writes every co-simulation option with the value of the last
common one, and its getters raise on a wrong reference, which its binary turns into Fatal).
Its binary drops the arguments of fmi3EnterInitializationMode, so the start time is not known
before the first doStep: that step's communication point is taken as the start (FMI 3.0 has
the first doStep begin at the start time)."""
from __future__ import annotations

import ctypes
import datetime
import math
import os
import uuid
from xml.etree.ElementTree import Element, SubElement

from pythonfmu3.enums import Fmi3Status
from pythonfmu3.fmi3slave import Fmi3Slave, Fmi3StepResult

from .slave import SewSlave, Variable
from .units import range_attributes, unit_definitions

_TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean"}
_STEPPED = Fmi3StepResult(status=Fmi3Status.ok)
_DISCARDED = Fmi3StepResult(status=Fmi3Status.discard)


class Fmi3Layer(SewSlave, Fmi3Slave):
    """Joined after a concrete sewfmu slave class: `class MainShaft(MainShaftSlave, Fmi3Layer)`."""

    call_names = {"Real": ("fmi3GetFloat64", "fmi3SetFloat64"),
                  "Integer": ("fmi3GetInt32", "fmi3SetInt32"),
                  "Boolean": ("fmi3GetBoolean", "fmi3SetBoolean"),
                  "String": ("fmi3GetString", "fmi3SetString"),
                  "Int64": ("fmi3GetInt64", "fmi3SetInt64"),
                  "UInt64": ("fmi3GetUInt64", "fmi3SetUInt64")}

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._start_known = False      # see the module docstring
        self._in_container = _in_fmpy_container(kwargs.get("resources"))

    def register_all(self) -> None:
        # value reference 0 is the independent variable, as in the Modelica Reference FMUs
        self._independent = Variable("time", "Real", "independent", "simulation time [s]", "s",
                                     lambda: self._time)
        self.remember(0, self._independent)
        for vr, v in enumerate(self.variables, start=1):
            self.remember(vr, v)

    def _error(self, message: str) -> None:
        # FMI 3.0 allows no logMessage call with logging off; pythonfmu3's binary passes on a
        # message marked debug only while logging is on (without the mark it passes on all).
        # Inside fmpy's container FMU (sewfmu export-fmu) the line is not marked: the container
        # instantiates its components with its host's flag and has no channel of its own, so
        # with logging off a refusal would reach no host at all; the container passes the line
        # on to its host (docs/fmi.md, "The punch drive as one FMU")
        in_container = getattr(self, "_in_container", False)
        self.log(self.error_line(message), Fmi3Status.error, debug=not in_container)

    def do_step(self, current_time, step_size):
        if not self._start_known and self._initialized and math.isfinite(current_time):
            self._start_known = True
            self._time = float(current_time)
        # pythonfmu3's binary asks the result for `status` and `terminateSimulation`: a bool has
        # neither, and each failed lookup raises (and clears) an AttributeError in C
        return _STEPPED if super().do_step(current_time, step_size) else _DISCARDED

    def save_layer(self):
        return {"start_known": self._start_known}

    def restore_layer(self, saved):
        self._start_known = bool(saved["start_known"])

    # pythonfmu3's calls, answered by SewSlave without an exception (the Float64 ones, made at
    # every step, are SewSlave's own methods under pythonfmu3's names: no call in between)
    get_float64 = SewSlave.get_reals
    set_float64 = SewSlave.set_reals

    def get_int32(self, vrs):
        return self.get_values(vrs, "Integer")

    def get_int64(self, vrs):
        return self.get_values(vrs, "Int64")

    def get_uint64(self, vrs):
        return [ctypes.c_uint64(x) for x in self.get_values(vrs, "UInt64")]

    def get_boolean(self, vrs):
        return self.get_values(vrs, "Boolean")

    def get_string(self, vrs):
        return self.get_values(vrs, "String")

    def set_int32(self, vrs, values):
        self.set_values(vrs, values, "Integer")

    def set_int64(self, vrs, values):
        self.set_values(vrs, values, "Int64")

    def set_uint64(self, vrs, values):
        self.set_values(vrs, values, "UInt64")

    def set_boolean(self, vrs, values):
        self.set_values(vrs, values, "Boolean")

    def set_string(self, vrs, values):
        self.set_values(vrs, values, "String")

    # --- modelDescription ----------------------------------------------------------------------
    def to_xml(self, model_options: dict[str, str] = dict()) -> Element:
        cls = type(self)
        root = Element("fmiModelDescription", {
            "fmiVersion": "3.0", "modelName": self.modelName,
            "instantiationToken": f"{{{uuid.uuid4()}}}", "description": self.description,
            "author": cls.author, "version": str(getattr(cls, "version", "")),
            "license": cls.license, "generationTool": "sewfmu (pythonfmu3 0.3.4)",
            "generationDateAndTime":
                datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "variableNamingConvention": "flat"})
        SubElement(root, "CoSimulation", {
            "modelIdentifier": self.modelName,
            # the FMU embeds the interpreter in the host's process: a library it needs, not a
            # tool it couples to
            "needsExecutionTool": "false", "canBeInstantiatedOnlyOncePerProcess": "false",
            "canGetAndSetFMUState": "true", "canSerializeFMUState": "true",
            "canHandleVariableCommunicationStepSize": "true"})
        variables = [(0, self._independent), *enumerate(self.variables, start=1)]
        unit_defs = SubElement(root, "UnitDefinitions")
        unit_definitions(unit_defs, {v.unit for _, v in variables if v.kind == "Real"})
        categories = SubElement(root, "LogCategories")
        for name, text in cls.log_categories.items():
            SubElement(categories, "Category", name=name, description=text)
        stop, step = cls.whole_step_experiment()
        SubElement(root, "DefaultExperiment", startTime="0.0", stopTime=repr(float(stop)),
                   stepSize=repr(float(step)))
        listed = SubElement(root, "ModelVariables")
        for vr, v in variables:
            SubElement(listed, _TYPES[v.kind], self._attributes(vr, v))
        structure = SubElement(root, "ModelStructure")
        inputs = [str(vr) for vr, v in variables if v.causality == "input"]
        for vr, v in variables:
            if v.causality == "output":
                attrib = {"valueReference": str(vr), "dependencies": "", "dependenciesKind": ""}
                if v.feedthrough and inputs:
                    attrib["dependencies"] = " ".join(inputs)
                    attrib["dependenciesKind"] = " ".join(["dependent"] * len(inputs))
                SubElement(structure, "Output", attrib)
        for vr, v in variables:
            if v.causality in ("output", "calculatedParameter"):
                SubElement(structure, "InitialUnknown", valueReference=str(vr))
        return root

    @staticmethod
    def _attributes(vr: int, v: Variable) -> dict[str, str]:
        attrib = {"name": v.name, "valueReference": str(vr), "description": v.description,
                  "causality": v.causality}
        if v.causality == "independent":
            attrib["variability"] = "continuous"
        elif v.causality == "output":
            attrib["variability"] = "discrete" if v.discrete else "continuous"
            attrib["initial"] = "calculated"
        elif v.causality == "calculatedParameter":
            attrib["variability"] = "fixed"
            attrib["initial"] = "calculated"
        elif v.causality == "input":
            attrib["variability"] = "continuous"
        else:
            attrib["variability"] = "fixed"
        attrib.update(range_attributes(v))
        if v.causality in ("input", "parameter"):
            start = v.getter()
            attrib["start"] = ("true" if start else "false") if v.kind == "Boolean" \
                else repr(int(start) if v.kind == "Integer" else float(start))
        return attrib


def _in_fmpy_container(resources: str | None) -> bool:
    """Whether this instance is a component of fmpy's container FMU: the container unpacks each
    component FMU into its own resources/<name>/, beside its configuration container.json, so a
    component's resources folder is <container>/resources/<name>/resources."""
    if not resources:
        return False
    return os.path.isfile(os.path.join(resources, os.pardir, os.pardir, "container.json"))
