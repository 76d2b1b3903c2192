"""Declared model parameters: unit, description, allowed range, validation with a clear error.

Every model keeps its parameters in a frozen dataclass whose fields are made with `parameter()`.
The FMU layer reads the same metadata to declare the FMI variables, so a parameter's unit,
description and default are written exactly once.
"""
from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field, fields, replace
from typing import Any

from .units import DISPLAY_UNITS

# allowed ranges, checked after the finiteness check
POSITIVE = "positive"
NONNEGATIVE = "nonnegative"
ANY = "any"
FRACTION = "fraction"       # 0 < x < 1
CHOICE = "choice"           # an integer from `choices`

_RANGE_TEXT = {POSITIVE: "> 0", NONNEGATIVE: ">= 0", FRACTION: "in (0, 1)"}

# The largest magnitude a parameter of each unit has in a sewing machine's mechanism: a value
# beyond it is a slip of the unit (110 for an angle meant in degrees, 63 for a mass meant in
# grams, 3 for a length meant in millimetres), refused rather than run. It is the declared
# max (min: its negative, or 0 for a positive quantity) in the modelDescription.
MACHINE_SCALE: dict[str, float] = {
    "m": 1.0, "kg": 50.0, "rad": 2 * math.pi, "rad/s": 2000.0, "s": 60.0, "N": 1e4,
    "N/m": 1e9, "N.s/m": 1e6, "N.m2": 1e7, "kg.m2": 10.0,
}
# how a value of that unit is usually meant when it is too large: the hint of the error
_MEANT = {"m": "mm", "kg": "g", "rad": "deg", "rad/s": "rpm"}


class ParameterError(ValueError):
    """A parameter value that the model cannot run with; `.name` is the parameter's name."""

    def __init__(self, name: str, message: str):
        super().__init__(f"parameter {name}: {message}")
        self.name = name


def parameter(default: float, unit: str, description: str, allowed: str = POSITIVE,
              choices: tuple[int, ...] = ()) -> Any:
    """A dataclass field that is a model parameter (SI `unit`)."""
    return field(default=default, metadata=dict(unit=unit, description=description,
                                                allowed=allowed, choices=choices))


@dataclass(frozen=True)
class ParameterInfo:
    name: str
    default: float
    unit: str
    description: str
    allowed: str
    choices: tuple[int, ...]

    @property
    def is_integer(self) -> bool:
        return self.allowed == CHOICE

    @property
    def bounds(self) -> tuple[float | None, float | None]:
        """The declared (min, max): the allowed sign and the machine's scale of the unit."""
        if self.allowed == CHOICE:
            return min(self.choices), max(self.choices)
        if self.allowed == FRACTION:
            return 0.0, 1.0
        scale = MACHINE_SCALE.get(self.unit)
        low = -scale if (self.allowed == ANY and scale is not None) else \
            (None if self.allowed == ANY else 0.0)
        return low, scale


def parameter_info(params_class) -> list[ParameterInfo]:
    """The declared parameters of a parameter dataclass, in declaration order."""
    return [ParameterInfo(f.name, f.default, f.metadata["unit"], f.metadata["description"],
                          f.metadata["allowed"], f.metadata["choices"])
            for f in fields(params_class) if "unit" in f.metadata]


def check_value(info: ParameterInfo, value: Any) -> None:
    """Raise ParameterError if `value` is not allowed for the parameter."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(info.name, f"expected a number, got {value!r}")
    if not math.isfinite(value):
        raise ParameterError(info.name, f"must be finite, got {value}")
    if info.allowed == CHOICE:
        if value not in info.choices:
            raise ParameterError(info.name, f"must be one of {list(info.choices)}, got {value}")
        return
    ok = {POSITIVE: value > 0, NONNEGATIVE: value >= 0, FRACTION: 0 < value < 1,
          ANY: True}[info.allowed]
    if not ok:
        raise ParameterError(info.name, f"must be {_RANGE_TEXT[info.allowed]} {info.unit}, "
                                        f"got {value}")
    low, high = info.bounds
    if high is not None and not (low <= value <= high):
        meant = _MEANT.get(info.unit)
        # offered only where the number, read in that unit, is within the range (9550 rad/s
        # meant as rpm; not 5730, which is too fast in rpm too)
        fits = meant is not None and low <= value / DISPLAY_UNITS[info.unit][meant] <= high
        hint = f" (meant in {meant}? give the unit: \"{value:g} {meant}\")" if fits else ""
        raise ParameterError(info.name, f"must be within [{low:g}, {high:g}] {info.unit} in a "
                                        f"sewing machine's mechanism, got {value:g}{hint}")


def validate(params) -> None:
    """Check every declared parameter of a parameter dataclass instance."""
    for info in parameter_info(type(params)):
        check_value(info, getattr(params, info.name))


def did_you_mean(name: str, known) -> str:
    """ "; did you mean 'x'?" for the closest known name, or nothing."""
    close = difflib.get_close_matches(name, list(known), n=1)
    return f"; did you mean {close[0]!r}?" if close else ""


def with_values(params, **values):
    """A copy of `params` with some values replaced, validated."""
    known = {info.name for info in parameter_info(type(params))}
    for name in values:
        if name not in known:
            raise ParameterError(name, f"unknown parameter of {type(params).__name__}"
                                       f"{did_you_mean(name, sorted(known))} "
                                       f"(known: {', '.join(sorted(known))})")
    new = replace(params, **values)
    validate(new)
    return new
