"""The parameters a user may set, as a table: of one of sewfmu's FMUs by name (from its slave's
declared parameters: no FMU needs to be built), or of every instance of a scenario (an FMU file
from elsewhere: from its modelDescription). `sewfmu show NAME --parameters` and
`sewfmu.parameters(NAME)` print and return it.

Columns: instance, parameter, default (the FMU's), value (what the scenario gives, else the
default), unit, range (as the FMU declares it), meaning.
"""
from __future__ import annotations

import importlib

from sewfmu.components.parameters import CHOICE, FRACTION, NONNEGATIVE, POSITIVE, parameter_info
from sewfmu.components.registry import FMUS
from sewfmu.scenarios.format.fmu_file import read_fmu, unit_of
from sewfmu.scenarios.format.scenario import Scenario

COLUMNS = ("instance", "parameter", "default", "value", "unit", "range", "meaning")


class ParameterTable(list):
    """Rows (dicts keyed by COLUMNS); str() is the table as the command line prints it."""

    def __str__(self) -> str:
        cells = [[_cell(row[c]) for c in COLUMNS] for row in self]
        widths = [max([len(c)] + [len(r[k]) for r in cells]) for k, c in enumerate(COLUMNS)]
        lines = ["  ".join(c.ljust(w) for c, w in zip(COLUMNS, widths)).rstrip()]
        lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in cells]
        return "\n".join(lines) + "\n"


def _cell(value) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def slave_class(fmu: str):
    """The slave class of one of sewfmu's FMUs (components/registry.py)."""
    module, slave = FMUS[fmu]
    return getattr(importlib.import_module(f"sewfmu.components.{module}"), slave)


def range_text(info) -> str:
    """The range the FMU declares, with the sign it allows (a positive parameter excludes 0)."""
    low, high = info.bounds
    if info.allowed == CHOICE:
        return "one of " + ", ".join(str(c) for c in info.choices)
    if info.allowed == FRACTION:
        return "(0, 1)"
    if info.allowed == POSITIVE:
        return f"(0, {high:g}]" if high is not None else "> 0"
    if info.allowed == NONNEGATIVE:
        return f"[0, {high:g}]" if high is not None else ">= 0"
    return f"[{low:g}, {high:g}]" if high is not None else "any"


def component_rows(fmu: str, instance: str = "", given: dict | None = None) -> ParameterTable:
    """The parameters of one of sewfmu's FMUs (an instance of it, with the values it is given)."""
    cls, given, instance = slave_class(fmu), given or {}, instance or fmu
    infos = parameter_info(cls.params_class) if cls.params_class else []
    return ParameterTable(
        {"instance": instance, "parameter": i.name, "default": float(i.default),
         "value": given.get(i.name, float(i.default)), "unit": i.unit, "range": range_text(i),
         "meaning": i.description} for i in infos)


def file_rows(md, instance: str, given: dict) -> ParameterTable:
    """The parameters of an FMU from elsewhere, from its modelDescription."""
    rows = ParameterTable()
    for v in md.modelVariables:
        if v.causality != "parameter":
            continue
        low, high = v.min, v.max
        declared = f"[{low or '-inf'}, {high or 'inf'}]" if low or high else "any"
        start = _number(v.start)
        rows.append({"instance": instance, "parameter": v.name, "default": start,
                     "value": given.get(v.name, start), "unit": unit_of(v), "range": declared,
                     "meaning": v.description or ""})
    return rows


def _number(text):
    try:
        return float(text)
    except (TypeError, ValueError):       # no start value, or a string parameter
        return "" if text is None else text


def scenario_rows(scenario: Scenario) -> ParameterTable:
    """Every instance's parameters, in the order of the scenario's instances."""
    rows = ParameterTable()
    for name, inst in scenario.instances.items():
        if inst.fmu in scenario.fmu_files:
            md = read_fmu(scenario.fmu_files[inst.fmu], f"{scenario.source}: instances.{name}")
            rows += file_rows(md, name, inst.parameters)
        elif inst.fmu in FMUS:
            rows += component_rows(inst.fmu, name, inst.parameters)
    return rows


def component_text(fmu: str) -> str:
    """What `sewfmu show COMPONENT` prints: the FMU's line, its inputs, outputs, parameters."""
    cls = slave_class(fmu)
    doc = (cls.__doc__ or "").strip().splitlines()
    lines = [f"{fmu}: {doc[0] if doc else ''}".rstrip(), "", "inputs:"]
    lines += [f"  {p.name} [{p.unit}]  {p.description}" for p in cls.inputs] or ["  none"]
    lines += ["outputs:"]
    lines += [f"  {p.name} [{p.unit}]  {p.description}" for p in cls.outputs] or ["  none"]
    lines += ["parameters:", ""]
    return "\n".join(lines) + "\n" + str(component_rows(fmu))
