"""The grammar of values with units, fuzzed: whatever text a user types (--set, --grid, --vary, a
scenario file, the API, the page), the parser answers with a value or with one sewfmu.Error line,
never pint's or Python's own exception (OffsetUnitCalculusError, OverflowError, the int-digits
ValueError, RecursionError...). The texts are arbitrary, and built from the grammar's own pieces
(numbers huge and odd, units, exponents, parentheses, commas, '..') to reach its corners."""
import math
import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import sewfmu
from sewfmu.components.units import UnitError
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.format.quantities import in_declared_unit
from sewfmu.scenarios.format.value_lists import grid_values, range_in_text, values_in_text
from sewfmu.scenarios.format.values import parse_value

FUZZ = settings(max_examples=150, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])

# the pieces the grammar is made of, and the ones that broke it
NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers().map(str),
    st.sampled_from(["1e999999", "-1e400", "10**10**10", "9" * 5000, "nan", "inf", "-Infinity",
                     ".5", "5.", "1_000", "0x10", "1e", "+", "-", "1.2.3", ""]))
PIECES = st.sampled_from([
    "rpm", "N", "kN", "m", "mm", "µm", "s", "ms", "deg", "°", "rad/s", "rev/s", "1/min", "Hz",
    "N/mm", "kg.m2", "m/s2", "degC", "delta_degC", "K", "%", "e", "pi", "furlong", "foo",
    "**", "^", "*", "/", ".", "(", ")", " ", ",", "..", "-", "1000", "1e9", "1e400", "0.5", "²",
    "⁻¹", "⁹" * 30, "\n", "\x00", "'", '"', "[", "]", "=", "#"])
GRAMMAR_LIKE = st.builds(lambda n, parts: n + "".join(parts), NUMBERS,
                         st.lists(PIECES, max_size=10))
TEXTS = st.one_of(st.text(max_size=80), GRAMMAR_LIKE)
UNITS = st.sampled_from(["rad/s", "N", "m", "s", "1", "N/m", "rad", "kg.m2", "N.s/m", "K"])
TARGETS = st.sampled_from(["shaft.omega0", "punch.F30", "punch.c2", "linkage.L_AB",
                           "experiment.step", "experiment.revolutions", "experiment.master"])


@pytest.fixture(scope="module")
def scenario():
    return load("punch_drive")


def _one_line(err: BaseException) -> None:
    message = str(err)
    assert message.strip() and "\n" not in message.strip(), repr(message)
    assert "bug in sewfmu" not in message and "Traceback" not in message


@FUZZ
@given(TEXTS, UNITS)
def test_a_value_in_a_declared_unit_is_a_finite_number_or_one_line(text, unit):
    try:
        value = in_declared_unit(text, unit, "x.y")
    except UnitError as err:         # the format's callers make it a ScenarioError
        _one_line(err)
    else:
        assert isinstance(value, float) and math.isfinite(value)


@FUZZ
@given(TEXTS, TARGETS)
def test_any_typed_value_is_taken_or_refused_in_one_line(scenario, text, target):
    """--set and the page: the text read as the command line reads it, then set."""
    probe = scenario.copy()
    try:
        probe.set_value(target, sewfmu.read_value(text), origin="--set")
    except sewfmu.Error as err:
        _one_line(err)


@FUZZ
@given(TEXTS)
def test_any_text_list_is_values_or_one_line(text):
    try:
        values = values_in_text(text, "--grid x.y")
    except sewfmu.Error as err:
        _one_line(err)
    else:
        assert values and all(isinstance(v, (bool, int, float, str, list, dict)) for v in values)


@FUZZ
@given(TEXTS)
def test_any_text_range_is_two_bounds_or_one_line(text):
    try:
        lo, hi = range_in_text(text, "--vary x.y")
    except sewfmu.Error as err:
        _one_line(err)


@pytest.mark.slow
@FUZZ
@given(TEXTS, TARGETS)
def test_any_text_grid_reaches_its_points_or_one_line(scenario, text, target):
    """A grid as the command line, the API and a scenario file give it: every point's value
    set as the sweep sets it, before anything runs."""
    from sewfmu.scenarios.runs.sweep import points_of

    try:
        points_of(scenario, {target: grid_values(text, f"grid {target}")})
    except sewfmu.Error as err:
        _one_line(err)


anything = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(), st.integers(min_value=2 ** 1023, max_value=2 ** 1100),
              st.floats(), TEXTS, st.binary(max_size=8)),
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.tuples(inner, inner),
                            st.dictionaries(st.text(max_size=4), inner, max_size=3)),
    max_leaves=8)


@FUZZ
@given(anything)
def test_any_python_object_as_a_grid_is_values_or_one_line(scenario, values):
    from sewfmu.scenarios.runs.sweep import points_of

    try:
        points_of(scenario, {"shaft.omega0": grid_values(values, "grid shaft.omega0")})
    except sewfmu.Error as err:
        _one_line(err)


@FUZZ
@given(anything)
def test_any_python_object_as_a_set_value_is_taken_or_one_line(scenario, value):
    try:
        sewfmu.load(scenario, set={"punch.F30": value})
    except sewfmu.Error as err:
        _one_line(err)


@pytest.mark.parametrize("text", ["9" * 5000, "1e999999", "nan", "[1, 2]", "[[[[[[[[", "'x'",
                                  '"unterminated', "1\nx = 2", ""])
def test_reading_a_typed_value_never_raises_python_s_own_errors(text):
    value = parse_value(text, "--set x.y")
    if text == "1\nx = 2":      # one value is one line: not TOML's 1 with a key after it
        assert value == text


@pytest.mark.parametrize("text", [
    "1 1000⁹⁹⁹⁹⁹⁹⁹⁹⁹", "1 kN**99**99", "1 ((((kN**99)**99)**99)**99)**99", "1 N" + "⁹" * 60,
    "1 m" + "*m" * 30, "1 " + "(" * 30 + "m" + ")" * 30, "1 Qm**12", "9" * 100_000 + " N"])
def test_a_unit_pint_would_compute_for_ever_is_refused_at_once(text):
    """pint evaluates the numbers in a unit's text as Python integers: "1000⁹⁹⁹⁹⁹⁹⁹⁹⁹" ran
    for ever (1000 ** 999999999) before any check could see it."""
    in_declared_unit("1 N", "N")             # pint's registry built before the clock starts
    start = time.perf_counter()
    with pytest.raises(UnitError):
        in_declared_unit(text, "N", "punch.F30")
    assert time.perf_counter() - start < 0.5
