"""The values a scenario is written with: the error every mistake raises, instance names
checked, numbers and times read (a time may carry its unit), --set values parsed, labels and
"did you mean" hints. The scenario format (scenarios/format/scenario.py) and everything that reads
scenarios use these.
"""
from __future__ import annotations

import math
import tomllib
from typing import Any

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


def plain(value: Any) -> Any:
    """numpy scalars and 0-d arrays as the Python numbers they are (np.float32, np.int64, ...);
    every other value unchanged."""
    if getattr(value, "shape", None) == () and callable(getattr(value, "item", None)):
        return value.item()
    return value


def label_of(target: str, value: Any) -> str:
    """`instance.parameter=value` as a short label (a folder name, a legend)."""
    if isinstance(value, float):
        # short where that is exact, every digit where it is not: two values, two labels
        text = f"{value:g}"
        return f"{target}={text if float(text) == value else repr(value)}"
    return f"{target}={value}"


def short(value: Any) -> str:
    """A value for a message: huge integers cut to their first and last digits."""
    try:
        text = repr(value)
    except ValueError:          # an int beyond Python's 4300 digits for its text
        return f"an integer of about {int(value.bit_length() * 0.30103)} digits"
    return text if len(text) <= 40 else f"{text[:12]}...{text[-6:]} ({len(text)} digits)"


def positive(value: Any, where: str) -> float:
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
        from sewfmu.components.units import UnitError  # loaded on first use (start-up time)
        from sewfmu.scenarios.format.quantities import in_declared_unit  # pint: on first use
        # where ends with the key ("file: experiment.step"); the message names the key itself
        origin, _, key = where.rpartition(" ")
        try:
            value = in_declared_unit(value, unit, key)
        except UnitError as err:
            raise ScenarioError(f"{origin} {err}" if origin else str(err)) from None
    return positive(value, where)


def parse_value(text: str, where: str) -> Any:
    """A value typed as text (--set, --grid, the page): a TOML scalar (a number, true or false,
    a quoted string), else the text itself: a value with its unit ("955 rpm", read by
    format/quantities.py) or a word, for the caller to say what it expected."""
    if not isinstance(text, str):
        raise ScenarioError(f"{where}: expected a text, got {type(text).__name__}")
    if "\n" in text or "\r" in text:   # one value is one line ("1\nx = 2" is TOML's 1 and more)
        return text
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except RecursionError:
        raise ScenarioError(f"{where}: nested too deeply to be a value") from None
    except ValueError:        # not TOML, or an integer beyond Python's 4300 digits
        if text.lower() in ("nan", "+nan", "-nan", "inf", "+inf", "-inf"):
            return float(text)
        return text           # a bare word: let the caller say what it expected
