"""A value with a unit, in the declared unit: what an engineer writes ("30 N/mm", "955 rpm",
"2 kgf", "10 lbf/in", "0.25 ms", "300 1/min") as the number in the SI unit a variable declares,
converted by pint's definitions. Every value given as a string (--set, a scenario file, the API's
set=, a sweep grid, an experiment's times) comes through here; a bare number never does: it is
already in the declared unit.

The FMUs' own code (components/) stays standard library only: this module is the host side's.
"""
from __future__ import annotations

import functools
import re

from sewfmu.components.units import UnitError, quoted

# what a variable of each of sewfmu's SI units is, for the one-line refusal of a wrong dimension
KINDS = {
    "1": "number", "s": "time", "m": "length", "m/s": "velocity", "m/s2": "acceleration",
    "m/s3": "jerk", "kg": "mass", "kg.m2": "moment of inertia", "N": "force",
    "N/s": "force rate", "N/m": "stiffness", "N.s/m": "damping", "N.m2": "bending stiffness",
    "rad": "angle", "rad/s": "rotational speed", "rad/s2": "angular acceleration",
    "1/s": "frequency", "kg/s": "mass flow", "N.m": "torque", "Pa": "pressure",
}

# a number, then a unit that starts with a letter (or is per something: "1/min"): "1 2 deg" and
# "2*3 mm" are no values with a unit, though pint's parser would multiply them out
_NUMBER_AND_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)"
                              r"\s*((?:[^\W\d_]|1/).*?)?\s*$")


@functools.lru_cache(maxsize=1)
def _registry():
    # pint and its registry (about a second to build): only when a value comes with a unit
    import pint  # loaded on first use (start-up time)

    registry = pint.UnitRegistry()
    # the machine shop's spellings pint lacks: revolutions, and one stitch per shaft revolution
    registry.define("@alias turn = rev")
    registry.define("stitch = turn = st")
    return registry


def _pint_spelling(unit: str) -> str:
    """FMI's unit syntax ("m/s2", "kg.m2", "N.s/m") as pint reads it ("m/s**2", "kg*m**2")."""
    unit = re.sub(r"(?<=[A-Za-zµμ])\.(?=[A-Za-zµμ])", "*", unit)
    return re.sub(r"(?<=[A-Za-zµμ])(-?\d+)", r"**\1", unit)


def _has_angle(registry, unit) -> bool:
    """pint counts the radian dimensionless; an angle is told by its root units."""
    return "radian" in registry.get_root_units(unit)[1]._units


def _kind(registry, unit) -> str:
    """What a unit measures ("force", "stiffness"), or its dimensions where sewfmu has no name."""
    root = registry.get_root_units(unit)[1]
    for si, name in KINDS.items():
        if registry.get_root_units(registry.Unit(_pint_spelling(si)))[1] == root:
            return name
    return f"of dimension {registry.Unit(unit).dimensionality}"


def _article(kind: str) -> str:
    if kind.startswith("of "):
        return kind
    return f"{'an' if kind[0] in 'aeiou' else 'a'} {kind}"


def split(text: str, target: str = "the value") -> tuple[float, str]:
    """"30 N/mm" -> (30.0, "N/mm"); "0.5" -> (0.5, ""). Raises UnitError for no number."""
    match = _NUMBER_AND_UNIT.match(text)
    if match is None:
        raise UnitError(f"{target} = {quoted(text)}: must be a number, or a number with its unit like "
                        f"\"110 deg\"")
    return float(match.group(1)), match.group(2) or ""


def in_declared_unit(text: str, unit: str, target: str = "the value") -> float:
    """`text` ("30 N/mm", "955 rpm", "0.5") as a number in `unit`, the SI unit `target`
    declares. A string without a unit is already in `unit`. A rotational speed given as turns
    per time without an angle ("300 1/min", "5 Hz") counts revolutions: pint would read 1/min
    as radians per minute. Raises UnitError, one line naming both dimensions where they differ."""
    number, given = split(text, target)
    if given in ("", unit):
        return number
    import pint  # the registry above has loaded it: its errors, to name them

    registry = _registry()
    try:
        have = registry.Quantity(number, _pint_spelling(given))
    except Exception:         # pint's parser fails on malformed text in many ways: not a unit
        raise UnitError(f"{target} = {quoted(text)}: {quoted(given)} is not a unit (e.g. N, kN, lbf, mm, "
                        f"in, rpm, rev/s, deg, N/mm, g, ms)") from None
    try:
        want = registry.Unit(_pint_spelling(unit or "1"))
    except Exception:         # another tool's unit string pint cannot read
        raise UnitError(f"{target} = {quoted(text)}: its FMU declares the unit {unit!r}, which pint "
                        f"does not know; give the number in {unit!r}") from None
    wrong = UnitError(f"{target} = {quoted(text)}: {given} is {_article(_kind(registry, have.units))}, "
                      f"{target} wants {_article(_kind(registry, want))} ({unit or '1'})")
    angle_have, angle_want = _has_angle(registry, have.units), _has_angle(registry, want)
    if angle_want and not angle_have and not have.dimensionless:
        if have.units == registry.Unit("1/s") and "hz" not in given.lower():
            # the papers (and this catalogue's descriptions) write ω in s⁻¹ meaning rad/s, while
            # turns per second is rev/s: either reading would be silently wrong for the other
            raise UnitError(f"{target} = {quoted(text)}: {given} is ambiguous for a rotational speed "
                            f"(ω in s⁻¹ is radians per second; turns per second are rev/s): "
                            f"write \"{number:g} rad/s\" or \"{number:g} rev/s\"")
        have = have * registry.turn          # "300 1/min": turns per minute
    elif angle_have != angle_want:
        raise wrong
    try:
        return float(have.to(want).magnitude)
    except pint.errors.PintError:
        raise wrong from None
