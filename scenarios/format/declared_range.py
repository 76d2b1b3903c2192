"""A parameter's value against the range its FMU declares, where a unit was converted: "400
grad" is 2π in exact arithmetic and 6.283185307179587 rad (one rounding above 2π) in floats,
so a converted value within a relative ROUNDING of a declared bound is that bound; and a value
refused is shown with as many digits as it takes to differ from the bound it passes
(2000.000715, not a "2000" outside [0, 2000])."""
from __future__ import annotations

import math

from sewfmu.components.units import DISPLAY_UNITS

ROUNDING = 1e-12        # relative: a few roundings of a unit's factor, far below any tolerance


def snapped(value: float, low: float | None, high: float | None) -> float:
    """`value`, or the declared bound it lies within ROUNDING of (either side)."""
    if isinstance(value, bool) or not isinstance(value, float) or not math.isfinite(value):
        return value
    for bound in (low, high):
        if bound is not None and math.isfinite(bound) and value != bound \
                and abs(value - bound) <= ROUNDING * max(abs(bound), abs(value)):
            return float(bound)
    return value


def apart(value: float, bound: float) -> tuple[str, str]:
    """The value and a bound it passes as texts that differ as the numbers do: the value to 10
    significant digits (every digit where those equal the bound's), the bound short where that
    is exact (2000, 1e+09) and to as many digits as the value otherwise (6.283185307, not a
    6.28319 that the value seems to lie within)."""
    value_text, bound_text = f"{value:.10g}", f"{bound:.10g}"
    if value_text == bound_text:
        value_text, bound_text = repr(float(value)), repr(float(bound))
    return value_text, (f"{bound:g}" if float(f"{bound:g}") == bound else bound_text)


def bounds_of_own(fmu: str, key: str) -> tuple[float | None, float | None]:
    """The range one of sewfmu's FMUs declares for a parameter (components/parameters.py, read
    from format/declared_units.py's table), (None, None) where it declares none."""
    from sewfmu.scenarios.format.declared_units import parameter_bounds  # only for a unit given

    return parameter_bounds(fmu).get(key, (None, None))


def out_of_range(where: str, target: str, value: float, unit: str, low: float | None,
                 high: float | None, declares: str, given: str | None) -> str:
    """The one line refusing `value` of `target` outside [low, high] (`declares`: who declares
    the range, "shaft (MainShaft)"): the value with the digits that set it apart from the bound
    it passes, the text it was given as where it carried a unit, and, for a number given
    without one, the unit it may have been meant in where it fits the range."""
    above = high is not None and value > high
    shown, passed = apart(float(value), high if above else low)
    span = (f"[{_bound(low, '-inf')}, {passed}]" if above else f"[{passed}, {_bound(high, 'inf')}]")
    hint = _unit_hint(unit, value, shown, low, high) if above and given is None else ""
    return (f"{where} {target}: parameter {target.partition('.')[2]} = {shown} {unit or ''} "
            f"is outside the range {span} {declares}{hint}"
            f"{f' (given as {given!r})' if given else ''}")


def _bound(bound: float | None, unbounded: str) -> str:
    return unbounded if bound is None else f"{bound:g}"


def _unit_hint(unit: str | None, value: float, shown: str, low: float | None,
               high: float) -> str:
    """How a number given without a unit and out of range may have been meant: its number in
    the unit users think in (the first display unit: rpm for rad/s, mm for m), where that is
    within the range (9550 rad/s meant as rpm; not 104720 rad/s, which was 1e6 rpm and is too
    fast in any unit)."""

    for display, factor in list(DISPLAY_UNITS.get(unit or "", {}).items())[:1]:
        if (low is None or value / factor >= low) and value / factor <= high:
            return f" (meant in {display}? give the unit: \"{shown} {display}\")"
    return ""
