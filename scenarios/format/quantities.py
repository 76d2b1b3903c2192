"""A value with a unit, in the declared unit: what an engineer writes ("30 N/mm", "955 rpm",
"2 kgf", "10 lbf/in", "0.25 ms", "300 1/min") as the number in the SI unit a variable declares,
converted by pint's definitions. Every value given as a string (--set, a scenario file, the API's
set=, a sweep grid, an experiment's times, a design study's bounds, targets and constraints)
comes through here; a bare number never does: it is already in the declared unit. Lists and
ranges of values are split by format/value_lists.py, which hands each value here.

The grammar (docs/scenarios.md, "Values with units"): a number as Python and TOML write a
decimal one (no leading zeros, no '_' between digits, no 0x, 0o, 0b, no '#' comment after it),
then optionally a unit: pint's names and FMI's spellings ("m/s2", "kg.m2", "N.s/m"),
joined by * / . or a space, with whole exponents from -12 to 12, parentheses balanced, at most
64 characters. Whatever the text, the answer is the number or a UnitError of one line.

The FMUs' own code (components/) stays standard library only: this module is the host side's.
"""
from __future__ import annotations

import functools
import math
import re

from sewfmu.components.units import UnitError, quoted

# what a variable of each of sewfmu's SI units is, for the one-line refusal of a wrong dimension
KINDS = {
    "1": "number", "s": "time", "m": "length", "m/s": "velocity", "m/s2": "acceleration",
    "m/s3": "jerk", "kg": "mass", "kg.m2": "moment of inertia", "N": "force",
    "N/s": "force rate", "N/m": "stiffness", "N.s/m": "damping", "N.m2": "bending stiffness",
    "rad": "angle", "rad/s": "rotational speed", "rad/s2": "angular acceleration",
    "1/s": "frequency", "kg/s": "mass flow", "N.m": "torque", "Pa": "pressure",
    "K": "temperature",
}

# a number as Python and TOML write a decimal one
NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
# a number, then whatever follows it (the unit, checked below)
NUMBER_AND_REST = re.compile(rf"^\s*({NUMBER})\s*(.*?)\s*$", re.DOTALL)
# how a unit may begin: a letter, a parenthesis, a degree or per cent sign, or "1/" ("1/min");
# "1 2 deg" and "2*3 mm" are no values with a unit, though pint's parser would multiply them out
UNIT_START = re.compile(r"^(?:[^\W\d_]|[(°%]|1\s*/)")
NOT_FINITE = re.compile(r"^\s*[-+]?(?:nan|inf|infinity)\b", re.IGNORECASE)
LONGEST_UNIT = 64               # characters: "kg.m2/s2" is 8; pint's parser recurses on more
LARGEST_EXPONENT = 12           # m**3, s**-2, N.m2; kN**103 is beyond a float
EXAMPLES = "e.g. N, kN, lbf, mm, in, rpm, rev/s, deg, N/mm, g, ms"


@functools.lru_cache(maxsize=1)
def _registry():
    # pint and its registry (about a second to build): only when a value comes with a unit
    import pint

    registry = pint.UnitRegistry()
    # the machine shop's spellings pint lacks: revolutions, and one stitch per shaft revolution
    registry.define("@alias turn = rev")
    registry.define("stitch = turn = st")
    return registry


def _pint_spelling(unit: str) -> str:
    """FMI's unit syntax ("m/s2", "kg.m2", "N.s/m") as pint reads it ("m/s**2", "kg*m**2"); the
    exponent of a number ("1e9") is left as it is."""
    unit = re.sub(r"(?<=[A-Za-zµμ])\.(?=[A-Za-zµμ])", "*", unit)
    return re.sub(r"(?<![\d.][eE])(?<=[A-Za-zµμ])(-?\d+)", r"**\1", unit)


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


# what Python or TOML would read as a number but the grammar does not: one grammar for --set,
# the API's set=, a file and the page (docs/scenarios.md), and no comment in a value
_NOT_DECIMAL = (
    (re.compile(r"[-+]?0[xXoObB]"), "hexadecimal, octal and binary numbers are not read: "
                                    "write the number in decimal"),
    (re.compile(r"[-+]?[\d.]*\d_"), "'_' between digits is not read: write the digits "
                                     "alone (1000, not 1_000)"),
    (re.compile(r"[-+]?0\d"), "a number starts with 0 only where it is 0 or 0.something: "
                              "write it without the leading zeros"),
    (re.compile(r"[^#]*#"), "'#' starts no comment in a value: give the number and its unit "
                           "alone (\"100 rpm\")"),
)


def _not_decimal(text: str) -> str | None:
    """Why a text that begins like a number is none of the grammar's, or None."""
    for pattern, why in _NOT_DECIMAL:
        if pattern.match(text):
            return why
    return None


def split(text: str, target: str = "the value") -> tuple[float, str]:
    """"30 N/mm" -> (30.0, "N/mm"); "0.5" -> (0.5, ""). Raises UnitError, one line, for a text
    that is no finite number with an optional unit."""
    if not isinstance(text, str):
        raise UnitError(f"{target}: expected a number or a text like \"110 deg\", got "
                        f"{type(text).__name__}")
    # tabs, newlines, no-break spaces: one space each, so that a message quoting the unit stays
    # one line (and "955\xa0rpm" pasted from a document is "955 rpm")
    match = NUMBER_AND_REST.match(" ".join(text.split()))
    if not text.strip():
        raise UnitError(f"{target} = {quoted(text)}: empty: give a number, or a number with its "
                        f"unit like \"110 deg\"")
    if match is None:
        if NOT_FINITE.match(text):
            raise UnitError(f"{target} = {quoted(text)}: not a finite number (NaN and infinity "
                            f"are no values here)")
        hint = ("; one value here: a list (\"100, 200 rpm\") is a sweep's grid"
                if "," in text else "")
        raise UnitError(f"{target} = {quoted(text)}{hint}: must be a number, or a number with "
                        f"its unit like \"110 deg\"")
    problem = _not_decimal(" ".join(text.split()))
    if problem:
        raise UnitError(f"{target} = {quoted(text)}: {problem}")
    number, rest = float(match.group(1)), match.group(2)
    if rest.startswith(","):
        raise UnitError(f"{target} = {quoted(text)}: one value here: a list (\"100, 200 rpm\") "
                        f"is a sweep's grid")
    if rest and not UNIT_START.match(rest):
        raise UnitError(f"{target} = {quoted(text)}: {quoted(rest)} is not a unit: a number is "
                        f"followed by nothing or by its unit ({EXAMPLES})")
    if not math.isfinite(number):
        raise UnitError(f"{target} = {quoted(text)}: the number is beyond the range of a float "
                        f"(about ±1.8e308)")
    return number, rest


# a unit's pieces: names (letters, '_', °, %), FMI's exponent after a name ("m2", "s-2"), "1"
# of "1/min", parentheses, a power of at most two digits ("**2", "^-1", "²", "⁻¹") and the
# operators * / . · (a space multiplies too). Nothing else: pint evaluates numbers in a unit's
# text as Python integers, and "1000⁹⁹⁹⁹⁹⁹⁹⁹⁹" would run for ever before any check of it.
_SUPERSCRIPT = "⁰¹²³⁴⁵⁶⁷⁸⁹"
_UNIT_TOKEN = re.compile(rf"""\s*(?:
    (?P<name>(?:(?![{_SUPERSCRIPT}⁻⁺])[^\W\d]|[°%])+)(?:-?\d{{1,2}}(?![\d{_SUPERSCRIPT}]))? |
    (?P<one>1)(?=\s*/) |
    (?P<open>\() | (?P<close>\)) |
    (?P<power>(?:\*\*|\^)\s*[-+]?\d{{1,2}}(?![\d.{_SUPERSCRIPT}])
              | [⁻⁺]?[{_SUPERSCRIPT}]{{1,2}}(?![\d{_SUPERSCRIPT}])) |
    (?P<op>\*(?!\*)|/|·|\.(?=\s*(?:[^\W\d]|\()))
)""", re.VERBOSE)
_DEEPEST = 4                    # parentheses within parentheses
_LONG_POWER = re.compile(rf"\s*(?:(?:\*\*|\^)\s*[-+]?[\d.]|[⁻⁺]?[{_SUPERSCRIPT}])")


def unit_problem(unit: str) -> str | None:
    """What makes a unit's text no unit of the grammar, before pint reads it, or None."""
    if len(unit) > LONGEST_UNIT:
        return f"is longer than any unit ({LONGEST_UNIT} characters at most)"
    if not unit.isprintable():
        return "holds a control character, which no unit has"
    if unit.count("(") != unit.count(")"):
        return "has unbalanced parentheses"
    at, depth, operand, powered = 0, 0, True, False     # operand: an atom is expected next
    while at < len(unit.rstrip()):
        token = _UNIT_TOKEN.match(unit, at)
        if token is None or token.end() == at:
            if _LONG_POWER.match(unit, at):
                return (f"has an exponent beyond any unit's (whole numbers from "
                        f"-{LARGEST_EXPONENT} to {LARGEST_EXPONENT})")
            return f"is not a unit: {quoted(unit[at:].strip()[:12])} cannot follow there"
        kind = token.lastgroup
        if kind == "power" and not powered:
            return (f"is not a unit: a power follows a unit or a parenthesis, once (exponents "
                    f"are whole numbers from -{LARGEST_EXPONENT} to {LARGEST_EXPONENT})")
        if kind in ("op", "close") and operand:
            return f"is not a unit: {quoted(token.group().strip())} lacks a unit before it"
        if kind == "open":
            depth += 1
            if depth > _DEEPEST:
                return f"has parentheses more than {_DEEPEST} deep"
        elif kind == "close":
            depth -= 1
            if depth < 0:
                return "has unbalanced parentheses"
        operand = kind in ("open", "op")
        powered = kind in ("name", "close")
        at = token.end()
    if operand:
        return "is not a unit: it ends without one"
    return None


def in_declared_unit(text: str, unit: str, target: str = "the value") -> float:
    """`text` ("30 N/mm", "955 rpm", "0.5") as a number in `unit`, the SI unit `target`
    declares. A string without a unit is already in `unit`. A rotational speed given as turns
    per time without an angle ("300 1/min", "5 Hz") counts revolutions: pint would read 1/min
    as radians per minute. Raises UnitError, one line naming both dimensions where they differ,
    for anything else (never pint's or Python's own exceptions)."""
    number, given = split(text, target)
    if given in ("", unit):
        return number
    import pint  # the registry below loads it: its errors, to name them

    where = f"{target} = {quoted(text)}"
    problem = unit_problem(given)
    if problem:
        raise UnitError(f"{where}: {quoted(given)} {problem}")
    registry = _registry()
    try:
        # symbolic only (no factor computed yet): the exponents are checked before any power
        units = registry.parse_units(_pint_spelling(given))
    except Exception:         # pint's parser fails on malformed text in many ways: not a unit
        raise UnitError(f"{where}: {quoted(given)} is not a unit ({EXAMPLES})") from None
    for name, power in units._units.items():
        if not (abs(power) <= LARGEST_EXPONENT and power == round(power)):    # NaN, inf too
            raise UnitError(f"{where}: {name} ** {power:g}: a unit's exponents are whole numbers "
                            f"from -{LARGEST_EXPONENT} to {LARGEST_EXPONENT}")
    have = registry.Quantity(number, units)
    try:
        want = registry.Unit(_pint_spelling(unit or "1"))
    except Exception:         # another tool's unit string pint cannot read
        raise UnitError(f"{where}: its FMU declares the unit {unit!r}, which pint does not know; "
                        f"give the number in {unit!r}") from None
    try:
        return _converted(registry, have, want, given, number, unit, where, target)
    except UnitError:
        raise
    except (pint.errors.PintError, ArithmeticError, ValueError):
        # an offset unit (degC) multiplied, a factor beyond a float: not this variable's unit
        raise UnitError(f"{where}: {given} does not convert to {target}'s unit "
                        f"{unit or '1'}") from None


def _converted(registry, have, want, given: str, number: float, unit: str, where: str,
               target: str) -> float:
    import pint  # loaded by the caller already: its errors, to name them

    wrong = UnitError(f"{where}: {given} is {_article(_kind(registry, have.units))}, "
                      f"{target} wants {_article(_kind(registry, want))} ({unit or '1'})")
    angle_have, angle_want = _has_angle(registry, have.units), _has_angle(registry, want)
    if angle_want and not angle_have and not have.dimensionless:
        if have.dimensionality != registry.Unit("1/s").dimensionality:
            raise wrong                          # "3 mm", "10 degC" for a speed
        if have.units == registry.Unit("1/s") and "hz" not in given.lower():
            # the papers (and this catalogue's descriptions) write ω in s⁻¹ meaning rad/s, while
            # turns per second is rev/s: either reading would be silently wrong for the other
            raise UnitError(f"{where}: {given} is ambiguous for a rotational speed "
                            f"(ω in s⁻¹ is radians per second; turns per second are rev/s): "
                            f"write \"{number:g} rad/s\" or \"{number:g} rev/s\"")
        have = have * registry.turn          # "300 1/min": turns per minute
    elif angle_have != angle_want:
        raise wrong
    try:
        value = float(have.to(want).magnitude)
    except pint.errors.DimensionalityError:
        raise wrong from None
    if not math.isfinite(value):
        raise UnitError(f"{where}: {value} in {unit or '1'}, beyond the range of a float (about "
                        f"±1.8e308)")
    return value
