"""The units of sewfmu's variables, with their SI base-unit exponents (FMI 2.0 and SSP
BaseUnit attributes): one table for the FMUs' modelDescription and the SSP export."""
import math
import re

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
    "N/s": {"kg": 1, "m": 1, "s": -3},
    "N/m": {"kg": 1, "s": -2},
    "N.s/m": {"kg": 1, "s": -1},
    "N.m2": {"kg": 1, "m": 3, "s": -2},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "rad/s2": {"rad": 1, "s": -2},
}

# Display units (FMI 2.0/3.0 DisplayUnit: display value = factor · value) of the units a user
# thinks in at the machine; the first is each variable's displayUnit. Scenario values given
# with a unit ("110 deg", "955 rpm", "63 g") are converted by the same definitions.
DISPLAY_UNITS: dict[str, dict[str, float]] = {
    "rad": {"deg": 180.0 / math.pi, "rev": 1.0 / (2.0 * math.pi)},
    # one stitch per revolution of the main shaft: stitches per minute are revolutions per minute
    "rad/s": {"rpm": 60.0 / (2.0 * math.pi), "st/min": 60.0 / (2.0 * math.pi),
              "deg/s": 180.0 / math.pi},
    "rad/s2": {"deg/s2": 180.0 / math.pi},
    "m": {"mm": 1e3, "um": 1e6, "cm": 1e2},
    "m/s": {"mm/s": 1e3},
    "m/s2": {"mm/s2": 1e3},
    "kg": {"g": 1e3},
    "kg.m2": {"g.mm2": 1e9, "kg.mm2": 1e6},
    "s": {"ms": 1e3},
    "N/m": {"N/mm": 1e-3},
    "N.s/m": {"N.s/mm": 1e-3},
    "N.m2": {"N.mm2": 1e6},
}


_VALUE_WITH_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(\S*)\s*$")


class UnitError(ValueError):
    """A value whose unit does not fit the quantity it is given for."""


def quoted(text: str, longest: int = 60) -> str:
    """A typed text for a message: quoted, a long one cut, so that the message still ends with
    what is wrong (a page shows the first few hundred characters of it)."""
    return repr(text) if len(text) <= longest else \
        f"{text[:longest - 20]!r}...{text[-8:]!r} ({len(text)} characters)"


def in_unit(text: str, unit: str) -> float:
    """A value written with its unit ("110 deg", "955 rpm", "63 g", "0.5") in `unit`, converted
    by the display units above. Raises UnitError saying which units fit."""
    match = _VALUE_WITH_UNIT.match(text)
    if match is None:
        raise UnitError(f"must be a number, or a number with its unit like \"110 deg\"; got "
                        f"{quoted(text)}")
    value, given = float(match.group(1)), match.group(2)
    given = given.strip()
    if given in ("", unit):
        return value
    factors = DISPLAY_UNITS.get(unit, {})
    if given not in factors:
        fitting = ", ".join([unit or "1", *factors])
        raise UnitError(f"{quoted(text)}: {quoted(given)} is not a unit of this {unit} value "
                        f"(units that fit: {fitting})")
    return value / factors[given]


def unit_definitions(parent, used) -> None:
    """<Unit> elements (FMI 2.0 and 3.0 alike) under `parent` for the units used: the SI base
    units and the display units."""
    from xml.etree.ElementTree import SubElement  # only when writing a modelDescription

    for name in sorted(used):
        unit = SubElement(parent, "Unit", name=name)
        SubElement(unit, "BaseUnit", {k: str(v) for k, v in UNITS[name].items()})
        for display, factor in DISPLAY_UNITS.get(name, {}).items():
            SubElement(unit, "DisplayUnit", name=display, factor=repr(factor))


def range_attributes(variable) -> dict[str, str]:
    """The unit, displayUnit, min and max attributes of a variable (parameters and inputs carry
    a range; a Real its unit and, where the unit has one, the display unit users think in)."""
    attrib = {}
    if variable.kind == "Real":
        attrib["unit"] = variable.unit
        displays = DISPLAY_UNITS.get(variable.unit)
        if displays:
            attrib["displayUnit"] = next(iter(displays))
    for key in ("min", "max"):
        value = getattr(variable, key)
        if value is not None and variable.kind in ("Real", "Integer"):
            attrib[key] = repr(float(value)) if variable.kind == "Real" else str(int(value))
    return attrib
