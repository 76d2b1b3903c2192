"""An FMU file named in a scenario (`fmu = "path/Motor.fmu"`), whoever made it: found, read and
checked against its modelDescription before anything runs.

- The path is taken relative to the scenario file (a Scenario built in Python: relative to the
  folder the process runs in), so a scenario and its FMUs move together.
- FMI 2.0 and 3.0 co-simulation FMUs; a model-exchange-only FMU or another FMI version is
  refused in one line (the master steps FMUs with doStep).
- Parameters the scenario gives are checked by name, causality, type and declared range here,
  so that a wrong name fails where it is written; the connections (variables, causality, types,
  units) are checked when the system is connected (scenarios/cosim/system.py).
"""
from __future__ import annotations

import math
from pathlib import Path

from sewfmu.components.parameters import did_you_mean
from sewfmu.scenarios.format.values import ScenarioError

SUFFIX = ".fmu"
_INTEGERS = {"Integer", "Enumeration", "Boolean",
             *(f"{sign}Int{bits}" for sign in ("", "U") for bits in (8, 16, 32, 64))}


def is_fmu_file(text: object) -> bool:
    """Whether an instance's `fmu` names a file rather than one of sewfmu's FMUs."""
    return isinstance(text, str) and text.lower().endswith(SUFFIX)


def fmu_path(text: str, base: Path, where: str) -> Path:
    """The FMU file `text` names, relative to `base` (the scenario file's folder)."""
    path = (Path(base) / Path(text).expanduser()).resolve()
    if not path.is_file():
        raise ScenarioError(f"{where}: FMU file {text!r} not found (looked for {path}; a "
                            f"relative path is taken from the scenario file's folder)")
    return path


def read_fmu(path: Path, where: str):
    """The modelDescription of a co-simulation FMU of FMI 2.0 or 3.0, or one ScenarioError."""
    from fmpy import read_model_description  # fmpy: only when an FMU file is read

    try:
        md = read_model_description(str(path))
    except Exception as err:            # noqa: BLE001 - any unreadable FMU is one message
        raise ScenarioError(f"{where}: {path.name} is not a readable FMU "
                            f"({' '.join(str(err).split())})") from None
    if not str(md.fmiVersion).startswith(("2.", "3.")):
        raise ScenarioError(f"{where}: {path.name} is an FMI {md.fmiVersion} FMU; sewfmu runs "
                            f"FMI 2.0 and 3.0 co-simulation FMUs")
    if md.coSimulation is None:
        raise ScenarioError(f"{where}: {path.name} ({md.modelName}) has no co-simulation "
                            f"interface (model exchange only); sewfmu's master steps FMUs "
                            f"with doStep")
    return md


def unit_of(variable) -> str:
    """A variable's unit, its own or its declared type's (FMI 2.0 lets either carry it)."""
    declared = getattr(variable, "declaredType", None)
    return variable.unit or (getattr(declared, "unit", None) if declared else None) or ""


def check_parameter(md, key: str, value, where: str) -> None:
    """A value the scenario gives to `key`: a parameter or an input of the FMU, of a number type,
    within the range it declares (the variable's own, or its declared type's)."""
    variables = {v.name: v for v in md.modelVariables}
    v = variables.get(key)
    if v is None or v.causality not in ("parameter", "input"):
        names = sorted(n for n, x in variables.items() if x.causality in ("parameter", "input"))
        raise ScenarioError(f"{where}: {md.modelName} has no parameter or input {key!r}"
                            f"{did_you_mean(key, names)} (has: {', '.join(names) or 'none'})")
    if v.type == "String" or v.type == "Binary":
        raise ScenarioError(f"{where}: {key} is a {v.type}; a scenario gives numbers")
    if v.type in _INTEGERS and float(value) != math.floor(float(value)):
        raise ScenarioError(f"{where}: {key} is a {v.type}: a whole number, got {value!r}")
    declared = getattr(v, "declaredType", None)
    for bound, limit in (("min", lambda x, b: x < b), ("max", lambda x, b: x > b)):
        text = getattr(v, bound, None) or (getattr(declared, bound, None) if declared else None)
        try:
            number = float(text) if text is not None else None
        except ValueError:              # a bound that is no number says nothing
            number = None
        if number is not None and limit(float(value), number):
            raise ScenarioError(f"{where}: {key} = {value!r} {unit_of(v)} is outside the range "
                                f"{md.modelName} declares ({bound} {number:g})")
