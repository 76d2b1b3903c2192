"""Lists and ranges of values, and the one rule for their units (docs/scenarios.md, "Values
with units"). Each value is what --set takes (format/values.py parse_value: a TOML scalar, else
a text with its unit for format/quantities.py); a list or a range only says which unit each of
its values carries:

    "100, 200, 300 rpm"     a unit after the last value applies to every value of the list
    "100 rpm, 2 rev/s"      every value carries its own unit: each keeps its own
    "100, 200"              no unit anywhere: the declared unit
    "100 rpm, 200"          some with a unit, some without, otherwise: refused as ambiguous
    "800..1200 rpm"         a range (--vary, --free): the same rule, for its two bounds

A typed list (a TOML array, a Python list or tuple) holds one value per element, so no unit is
shared; but it may not mix bare numbers with values that carry a unit either ([100, "200 rpm"]
is refused as "100, 200 rpm" would be read otherwise: a bare 100 is rad/s, not rpm).
"""
from __future__ import annotations

import re
from typing import Any

from sewfmu.components.units import quoted
from sewfmu.scenarios.format.quantities import NOT_FINITE, NUMBER_AND_REST, UNIT_START
from sewfmu.scenarios.format.values import ScenarioError, exact, parse_value, plain, short

LIST_RULE = ("a unit after the last value applies to all (\"100, 200 rpm\"); otherwise give "
             "every value its own (\"100 rad/s, 200 rpm\") or none (the declared unit)")
RANGE_RULE = ("a unit after the upper bound applies to both (\"800..1200 rpm\"); otherwise give "
              "each its own (\"800 rpm..20 rev/s\") or none (the declared unit)")
LARGEST_INT = 2 ** 1024          # beyond it, no float: refused before any label or hash is made


def unit_of(value: Any) -> str | None:
    """"" for a bare number (a number, or a text that is only one); the unit of a text that is
    a number with its unit; None for anything else (a word, true, a table)."""
    value = plain(value)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return ""
    if not isinstance(value, str):
        return None
    match = NUMBER_AND_REST.match(value)
    if match is None:
        return None
    rest = match.group(2)
    return rest if not rest or UNIT_START.match(rest) else None


def _shared(items: list[str], text: str, where: str, rule: str = LIST_RULE) -> list[str]:
    """The texts of a list's values, the unit after the last given to the bare ones before it;
    refused where some carry a unit and some do not otherwise."""
    units = [unit_of(item) for item in items]
    carried = [i for i, u in enumerate(units) if u]
    bare = [i for i, u in enumerate(units) if u == ""]
    if not carried or not bare:
        return items
    if carried == [len(items) - 1] and len(bare) == len(items) - 1:
        return [f"{item} {units[-1]}" if i in bare else item for i, item in enumerate(items)]
    raise ScenarioError(f"{where}: {quoted(text)} gives a unit to some values and not to "
                        f"others, which is ambiguous: {rule}")


# a list that reads as a number with thousands separators ("1,500 N", "2,500,000"): a first
# value of one digit, then groups of exactly three digits, without spaces
_THOUSANDS = re.compile(r"\s*[-+]?\d(?:,\d{3})+(?![\d.,])")
# a value of a list that starts with a zero followed by a digit ("000", "050 N")
_LEADING_ZERO = re.compile(r"[-+]?0\d")
_DIGIT_GROUPS = re.compile(r"\s*([-+]?\d+(?:,\d+)+)")


def values_in_text(text: str, where: str) -> list:
    """"100, 200 rpm" -> ["100 rpm", "200 rpm"]; "jacobi, gauss-seidel" -> the two words;
    "1e-4, 2e-4" -> [0.0001, 0.0002]: each value as --set parses it. A text that reads as one
    number with thousands separators ("1,000 N", "2,500") is refused: as a list it would be
    two values (1 and 0)."""
    items = [item.strip() for item in str.split(text, ",")]
    if any(not item for item in items):
        raise ScenarioError(f"{where}: {quoted(text)} has an empty value: values are separated "
                            f"by single commas, like \"100, 200, 300 rpm\"")
    zero = any(_LEADING_ZERO.match(item) for item in items[1:])
    digits = _DIGIT_GROUPS.match(text)
    if digits and (zero or _THOUSANDS.match(text)):
        raise ScenarioError(f"{where}: {quoted(text)} reads as one number with thousands "
                            f"separators, but a comma separates a list's values (it would be "
                            f"{len(items)} values: {', '.join(items[:3])}"
                            f"{', ...' if len(items) > 3 else ''}): write one number without "
                            f"separators ({digits.group(1).replace(',', '')[:40]}), or a list "
                            f"with a "
                            f"space after each comma (\"1, 500 N\")")
    return [parse_value(item, where) for item in _shared(items, text, where)]


def range_in_text(text: str, where: str) -> tuple[Any, Any]:
    """"800..1200 rpm" -> ("800 rpm", "1200 rpm"); "15..40" -> (15, 40); "1 mm..2 in" each its
    own. Raises ScenarioError for anything but two numbers with the units of a list."""
    parts = [part.strip() for part in str.split(text, "..")] if "..." not in text else []
    odd = next((p for p in parts if NOT_FINITE.match(p)), None)
    if odd is not None:
        raise ScenarioError(f"{where}: {quoted(text)}: the bound {quoted(odd)} is not a finite "
                            f"number (NaN and infinity are no bounds); give two numbers, like "
                            f"\"800..1200 rpm\"")
    if len(parts) != 2 or not all(parts) or None in map(unit_of, parts):
        raise ScenarioError(f"{where}: {quoted(text)}: expected LO..HI with an optional unit, "
                            f"like \"800..1200 rpm\" or \"15..40\"")
    lo, hi = (parse_value(part, where) for part in _shared(parts, text, where, RANGE_RULE))
    return lo, hi


def check_units_agree(values: list, where: str) -> None:
    """A typed list: bare numbers and values with a unit not mixed (see the module's rule)."""
    units = [unit_of(v) for v in values]
    if any(units) and "" in units:
        raise ScenarioError(f"{where}: {short(values)} mixes bare numbers (in the declared unit) "
                            f"with values that carry a unit; give every value its unit, like "
                            f"[\"100 rpm\", \"200 rpm\"], or none")


def grid_values(values: Any, where: str) -> list:
    """A grid's values for one parameter: a text list ("100, 200 rpm"), a list, tuple, range,
    numpy array or other iterable of values, or one value; each a number, true or false, or a
    text (numpy numbers as Python's)."""
    values = exact(values)
    if isinstance(values, str):
        return values_in_text(values, where)
    if hasattr(values, "tolist"):
        values = values.tolist()
    if isinstance(values, (bytes, bytearray, dict)) or hasattr(values, "keys"):
        raise ScenarioError(f"{where}: expected a list of values, got {type(values).__name__}")
    if not hasattr(values, "__iter__"):
        values = [values]
    out = []
    for value in values:
        value = exact(value)                # a float subclass's own repr is never asked
        if not isinstance(value, (bool, int, float, str)):
            raise ScenarioError(f"{where}: a value is a number, true or false, or a text with its "
                                f"unit, got {type(value).__name__}")
        if isinstance(value, int) and not -LARGEST_INT < value < LARGEST_INT:
            raise ScenarioError(f"{where}: {short(value)} is beyond the range of a float (about "
                                f"±1.8e308)")
        out.append(value)
        if len(out) > 1_000_000:
            raise ScenarioError(f"{where}: more than a million values")
    if not out:
        raise ScenarioError(f"{where}: no values")
    check_units_agree(out, where)
    return out
