"""Export a scenario as an SSP 1.0 archive (.ssp) that other co-simulation tools run unchanged.

The archive holds SystemStructure.ssd at its root and the FMUs under resources/. Each component
lists its connectors (inputs and outputs, with units) and binds the scenario's parameter values
inline (ssd:ParameterBindings / ssv:ParameterSet); the connections are the scenario's; the
DefaultExperiment carries the start and stop time. The communication step is not part of SSP 1.0:
a host takes it as its own setting (`sewfmu crosscheck` passes the scenario's); sewfmu's own
annotation in the DefaultExperiment carries it for `sewfmu run FILE.ssp`.
"""
from __future__ import annotations

import sys
import tempfile
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

from sewfmu.components.units import UNITS
from sewfmu.scenarios.cosim.algorithms import ALGORITHMS
from sewfmu.scenarios.cosim.fmi_calls import kind_of
from sewfmu.scenarios.fmu_build.native_current import without_windows_line
from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
from sewfmu.scenarios.format.experiment import ssp_settings
from sewfmu.scenarios.format.fmu_file import model_description
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.ssp_import import ANNOTATION, SEWFMU

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
# every component's inline parameter set carries this name, so that a host that applies one
# named set to the whole system (ecos: init(parameter_set=...)) applies all of them
PARAMETER_SET = "sewfmu"
# OMSimulator's annotations (its command-line tool refuses a system without its step)
OMS = "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd"
ET.register_namespace("sewfmu", SEWFMU)
ET.register_namespace("oms", OMS)
ET.register_namespace("ssd", SSD)
ET.register_namespace("ssc", SSC)
ET.register_namespace("ssv", SSV)


def _q(ns: str, tag: str) -> str:
    return f"{{{ns}}}{tag}"


def system_structure(scenario: Scenario, fmu_paths: dict[str, Path]) -> ET.ElementTree:
    root = ET.Element(_q(SSD, "SystemStructureDescription"),
                      {"version": "1.0", "name": scenario.name})
    system = ET.SubElement(root, _q(SSD, "System"), {"name": scenario.name,
                                                     "description": scenario.description})
    elements = ET.SubElement(system, _q(SSD, "Elements"))
    used_units = set()
    for inst in scenario.instances.values():
        md = model_description(fmu_paths[inst.fmu], "")
        comp = ET.SubElement(elements, _q(SSD, "Component"), {
            "name": inst.name, "type": "application/x-fmu-sharedlibrary",
            "source": f"resources/{inst.fmu}.fmu"})
        connectors = ET.SubElement(comp, _q(SSD, "Connectors"))
        for v in md.modelVariables:
            if v.causality not in ("input", "output"):
                continue
            con = ET.SubElement(connectors, _q(SSD, "Connector"),
                                {"name": v.name, "kind": v.causality})
            attrib = {"unit": v.unit} if v.unit else {}
            ET.SubElement(con, _q(SSC, kind_of(v)), attrib)     # SSP 1.0: Real for Float64
            if v.unit:
                used_units.add(v.unit)
        if inst.parameters:
            types = {v.name: kind_of(v) for v in md.modelVariables}
            bindings = ET.SubElement(comp, _q(SSD, "ParameterBindings"))
            binding = ET.SubElement(bindings, _q(SSD, "ParameterBinding"))
            values = ET.SubElement(binding, _q(SSD, "ParameterValues"))
            pset = ET.SubElement(values, _q(SSV, "ParameterSet"),
                                 {"version": "1.0", "name": PARAMETER_SET})
            params = ET.SubElement(pset, _q(SSV, "Parameters"))
            for key, value in inst.parameters.items():
                p = ET.SubElement(params, _q(SSV, "Parameter"), {"name": key})
                kind = types.get(key, "Real")
                text = str(int(value)) if kind == "Integer" else repr(float(value))
                ET.SubElement(p, _q(SSV, kind), {"value": text})
    connections = ET.SubElement(system, _q(SSD, "Connections"))
    for con in scenario.connections:
        ET.SubElement(connections, _q(SSD, "Connection"), {
            "startElement": con.src, "startConnector": con.src_var,
            "endElement": con.dst, "endConnector": con.dst_var})
    # the step that meets the stop time in whole, even steps: a fixed-step tool ends there
    # (a variable-step master's step is its first step, not a grid)
    step = scenario.step if ALGORITHMS[scenario.master].variable_step \
        else scenario.even_steps()[1]
    # the step where OMSimulator reads it (fmpy's SSP parser reads it too, though its
    # simulate_ssp takes the step as an argument: docs/fmi.md)
    oms = ET.SubElement(ET.SubElement(ET.SubElement(system, _q(SSD, "Annotations")),
                                      _q(SSC, "Annotation"), {"type": "org.openmodelica"}),
                        _q(OMS, "Annotations"))
    ET.SubElement(ET.SubElement(oms, _q(OMS, "SimulationInformation")),
                  _q(OMS, "FixedStepMaster"), {"description": "oms-ma", "stepSize": repr(step)})
    units = ET.SubElement(root, _q(SSD, "Units"))
    for name in sorted(used_units):
        unit = ET.SubElement(units, _q(SSC, "Unit"), {"name": name})
        ET.SubElement(unit, _q(SSC, "BaseUnit"), {k: str(v) for k, v in UNITS[name].items()})
    experiment = ET.SubElement(root, _q(SSD, "DefaultExperiment"),
                               {"startTime": "0", "stopTime": repr(scenario.end_time())})
    # the communication step is not part of SSP 1.0: sewfmu's annotation carries it, and
    # scenarios/format/ssp_import.py reads it back
    notes = ET.SubElement(experiment, _q(SSD, "Annotations"))
    note = ET.SubElement(notes, _q(SSC, "Annotation"), {"type": ANNOTATION})
    settings = ssp_settings(scenario, step)
    carried = ET.SubElement(note, _q(SEWFMU, "Experiment"),
                            {k: _text(v) for k, v in settings.items()})
    # a narrowed record, one column each (a variable's name may hold any character)
    for column in scenario.record or ():
        ET.SubElement(carried, _q(SEWFMU, "Record"), {"column": column})
    ET.indent(root)
    return ET.ElementTree(root)


def _text(value) -> str:
    """A setting as --set takes it back (scenarios/format/values.parse_value: TOML)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value) if isinstance(value, float) else str(value)


def export_ssp(scenario: Scenario, path: Path, fmu_paths: dict[str, Path]) -> Path:
    """Write the scenario as an .ssp archive; returns its path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tree = system_structure(scenario, fmu_paths)
    with tempfile.NamedTemporaryFile(suffix=".ssd", delete=False) as f:
        tree.write(f, encoding="UTF-8", xml_declaration=True)
        ssd = f.name
    staged = path.with_name(f".{path.name}.tmp")
    with zipfile.ZipFile(staged, "w", zipfile.ZIP_DEFLATED) as z:
        z.write(ssd, "SystemStructure.ssd")
        for name in sorted({inst.fmu for inst in scenario.instances.values()}):
            z.write(fmu_paths[name], f"resources/{name}.fmu")
    Path(ssd).unlink()
    staged.replace(path)
    return path


def export(scenario: Scenario, path: Path, fmu_dir: Path | None = None) -> Path:
    """The scenario as an SSP 1.0 archive for other co-simulation tools."""
    paths = fmus_for(scenario, fmu_dir)
    if scenario.fmus == "native" and (line := without_windows_line(paths, "export-ssp")):
        print(f"sewfmu: {line}", file=sys.stderr)
    return export_ssp(scenario, Path(path), paths)
