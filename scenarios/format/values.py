"""The values a scenario is written with: the error every mistake raises, instance names
checked, numbers and times read (a time may carry its unit), --set values parsed, labels and
"did you mean" hints. The scenario format (scenarios/format/scenario.py) and everything that reads
scenarios use these.
"""
from __future__ import annotations

import decimal
import math
import numbers
import re
import tomllib
from typing import Any

from sewfmu.components.units import UnitError
from sewfmu.errors import Error, ScenarioError  # noqa: F401 (ScenarioError: where the wings import it from)


def check_instance_name(name: str) -> None:
    """An instance name becomes part of column names (instance.variable) and of folder names
    (`instance.parameter=value`): a letter or '_' first, then letters, digits, '_' or '-', at
    most 64 characters, and not 'experiment'. Raises ValueError saying so."""
    # letters of any script: an engineer may name the instances in the machine shop's language
    if not isinstance(name, str) or not 0 < len(name) <= 64 or name == "experiment" \
            or not (name[0].isalpha() or name[0] == "_") \
            or not all(ch.isalnum() or ch in "_-" for ch in name):
        raise ValueError(f"an instance name starts with a letter or '_' and holds only letters, "
                         f"digits, '_' and '-' (no '.', path separators or spaces; at most 64; "
                         f"not 'experiment'), got {name!r}")


# a scenario's name becomes file and folder names (NAME.png, NAME_sweep.png, results/NAME/)
LONGEST_NAME = 200              # bytes in UTF-8: NAME_sweep.png stays within a file name's 255


def check_scenario_name(name: Any) -> None:
    """A scenario's name becomes part of paths (results/NAME/, NAME.png in the output folder):
    a text that is one file name, no path. Raises ScenarioError saying so."""
    if not isinstance(name, str):
        raise ScenarioError(f"a scenario's name is a text (it names its files), got "
                            f"{type(name).__name__}")
    if not name or name in (".", "..") or any(ch in name for ch in "/\\") \
            or not name.isprintable() or len(name.encode("utf-8", "replace")) > LONGEST_NAME:
        raise ScenarioError(f"a scenario's name names its files (NAME.png, results/NAME/): one "
                            f"file name, not empty, '.' or '..', without '/', '\\' or control "
                            f"characters, at most {LONGEST_NAME} bytes; got {short(name)}")


def plain(value: Any) -> Any:
    """numpy scalars and 0-d arrays as the Python numbers they are (np.float32, np.int64, ...);
    every other value unchanged."""
    if getattr(value, "shape", None) == () and callable(getattr(value, "item", None)):
        try:
            value = value.item()
        except Exception:            # noqa: BLE001 - a user's object: left as it is
            return value
    return value


def real(value: Any) -> Any:
    """A real number of another type (Fraction, numpy's longdouble: any numbers.Real; Decimal)
    as the float it is (inf beyond a float's range, NaN for a NaN: for the caller to refuse);
    a bool, an int, a float or anything else unchanged."""
    value = plain(value)
    if isinstance(value, (bool, int, float)) \
            or not isinstance(value, (numbers.Real, decimal.Decimal)):
        return value
    try:
        return float(value)
    except OverflowError:
        return math.inf
    except Exception:               # noqa: BLE001 - a signaling NaN, a user's number that fails
        return math.nan


def exact(value: Any) -> Any:
    """A value as a plain Python one: numpy's and other real numbers as Python's (plain, real),
    a subclass of str, int or float as the str, int or float it holds, so that none of its own
    methods (repr, split, format, which may raise or lie) runs later; anything else
    unchanged."""
    value = real(value)
    if type(value) in (str, int, float, bool):
        return value
    if isinstance(value, str):
        return str.__str__(value)
    if isinstance(value, int) and not isinstance(value, bool):
        return int.__int__(value)
    if isinstance(value, float):
        return float.__float__(value)
    return value


def label_of(target: str, value: Any) -> str:
    """`instance.parameter=value` as a short label (a folder name, a legend)."""
    if isinstance(value, float):
        # short where that is exact, every digit where it is not: two values, two labels
        text = f"{value:g}"
        return f"{target}={text if float(text) == value else repr(value)}"
    return f"{target}={value}"


# the types a message shows by their value (repr); any other object is named by its type
_SHOWN = (str, bytes, int, float, complex, bool, type(None), list, tuple, dict, set, frozenset)


def short(value: Any) -> str:
    """A value for a message: a long text or list cut, its length said in characters; a huge
    integer cut, its length said in digits; an object of another type named by its type (its
    repr may be anything, or raise)."""
    value = plain(value)
    if not isinstance(value, _SHOWN) and type(value).__module__ not in (
            "decimal", "fractions", "pathlib", "numpy"):
        return f"an object of type {type(value).__name__}"
    if isinstance(value, int) and not isinstance(value, bool):
        try:
            text = int.__repr__(value)      # a subclass's own repr is not asked
        except ValueError:          # an int beyond Python's 4300 digits for its text
            return f"an integer of about {int(value.bit_length() * 0.30103)} digits"
        return text if len(text) <= 40 else f"{text[:12]}...{text[-6:]} ({len(text)} digits)"
    try:
        text = (str.__repr__(value) if isinstance(value, str) else
                float.__repr__(value) if isinstance(value, float) else repr(value))
    except Exception:               # noqa: BLE001 - an item whose repr fails
        return f"an object of type {type(value).__name__}"
    if not isinstance(text, str):
        return f"an object of type {type(value).__name__}"
    return text if len(text) <= 40 else f"{text[:28]}...{text[-6:]} ({len(text)} characters)"


def positive(value: Any, where: str) -> float:
    value = real(value)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ScenarioError(f"{where}: must be a number, got {short(value)}")
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number) or number <= 0:
        raise ScenarioError(f"{where}: must be a positive finite number, got {short(value)}")
    return number


def seconds(value: Any, where: str) -> float:
    """A positive time: a number of seconds, or a string with a unit ("0.25 ms")."""
    return positive_in(value, "s", where)


def positive_in(value: Any, unit: str, where: str) -> float:
    """A positive number in `unit`, or a string with a unit that converts to it ("2 rev",
    "720 deg" of shaft revolutions)."""
    if isinstance(value, str):
        from sewfmu.scenarios.format.quantities import in_declared_unit  # pint: on first use
        # where ends with the key ("file: experiment.step"); the message names the key itself
        origin, _, key = where.rpartition(" ")
        try:
            value = in_declared_unit(value, unit, key)
        except UnitError as err:
            raise ScenarioError(f"{origin} {err}" if origin else str(err)) from None
    return positive(value, where)


# the grammar's scalars typed as text (docs/scenarios.md, "Values with units"): a decimal
# number as Python and TOML write one (no leading zeros, no '_', no 0x, 0o, 0b), true or false,
# a string in double or single quotes on one line. Anything else is handed on as the text
# itself: a number with its unit, or a word the caller checks. No TOML beyond these: "100 # rpm"
# is no 100 with a comment, and "0x64" no hexadecimal (the API's set= reads them so too).
DECIMAL = re.compile(r"[-+]?(?:(?:0|[1-9]\d*)(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?")
_QUOTED = re.compile(r'"(?:[^"\\\x00-\x1f\x7f]|\\(?:[btnfr"\\]|u[0-9A-Fa-f]{4}'
                     r'|U[0-9A-Fa-f]{8}))*"|\'[^\'\x00-\x08\x0a-\x1f\x7f]*\'')
_NOT_FINITE_WORDS = ("nan", "+nan", "-nan", "inf", "+inf", "-inf")


def parse_value(text: str, where: str) -> Any:
    """A value typed as text (--set, --grid, the page): a decimal number (int or float), true
    or false, a quoted string, else the text itself: a value with its unit ("955 rpm", read by
    format/quantities.py, which refuses what is no number of the grammar) or a word, for the
    caller to say what it expected."""
    if not isinstance(text, str):
        raise ScenarioError(f"{where}: expected a text, got {type(text).__name__}")
    text = str.strip(text)
    if text in ("true", "false"):
        return text == "true"
    if DECIMAL.fullmatch(text):
        try:
            return float(text) if any(c in text for c in ".eE") else int(text)
        except ValueError:          # an integer beyond Python's 4300 digits: the text, refused
            return text
    if _QUOTED.fullmatch(text):
        try:
            return tomllib.loads(f"v = {text}")["v"]
        except ValueError:          # an escape of no character ("\\ud800"): refused as text
            return text
    if text.lower() in _NOT_FINITE_WORDS:
        return float(text)          # for the caller to refuse as no finite number
    return text                     # a number with its unit, or a word
