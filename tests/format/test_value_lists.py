"""One grammar for values with units, at every door: a unit after a list (or a range) applies to
every value of it, as pint itself converts each (computed here apart from sewfmu's registry);
every value may carry its own; a list that gives a unit to some values and not to others is
refused as ambiguous, in --grid, a scenario file, the API's grid and --vary alike. Bad values
(the brief's list) are one line at --set, in a scenario file and as a study's target."""
import math

import pint
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

import sewfmu
from sewfmu.scenarios.design.space import constraints_of, goal_of
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.format.value_lists import grid_values, range_in_text
from sewfmu.scenarios.runs.sweep import parse_grid_option, points_of

UREG = pint.UnitRegistry()          # pint's own definitions, apart from sewfmu's registry

# (target, unit as written, the same unit as pint spells it, the declared SI unit in pint's words)
UNITS = [("shaft.omega0", "rpm", "revolution/minute", "radian/second"),
         ("shaft.omega0", "deg/s", "degree/second", "radian/second"),
         ("punch.F30", "kN", "kilonewton", "newton"),
         ("punch.F30", "lbf", "pound_force", "newton"),
         ("punch.c2", "N/mm", "newton/millimeter", "newton/meter"),
         ("linkage.L_AB", "mm", "millimeter", "meter")]
# whole and fractional, negative and tiny and large values; each written as Python writes it
NUMBERS = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False).filter(
    lambda v: v == 0 or abs(v) > 1e-6)
# what a sweep runs: values its parameters' declared ranges take (a sweep refuses the others)
SWEPT = st.floats(min_value=1e-3, max_value=100.0)


@pytest.fixture(scope="module")
def scenario():
    return load("punch_drive")


def _pint(value: float, unit: str, si: str) -> float:
    return UREG.Quantity(value, unit).to(si).magnitude


def _swept(scenario, target: str, values: list) -> list[float]:
    """The values a sweep runs; drawn values outside the parameter's declared range are not this
    test's (a sweep refuses them: tests/format/test_values_as_typed.py)."""
    try:
        points = points_of(scenario, {target: values})
    except sewfmu.ScenarioError as err:
        assume("outside the range" not in str(err))
        raise
    return [dict(p.values)[target] for p in points]


@pytest.mark.slow
@given(st.sampled_from(UNITS), st.lists(SWEPT, min_size=1, max_size=5, unique=True))
def test_a_unit_after_a_list_multiplies_every_value(scenario, case, values):
    target, unit, pints, si = case
    text = ", ".join(repr(v) for v in values) + f" {unit}"
    name, parsed = parse_grid_option(f"{target}={text}")              # --grid
    expected = [_pint(v, pints, si) for v in values]
    assert _swept(scenario, name, parsed) == pytest.approx(expected, rel=1e-13, abs=1e-300)
    assert _swept(scenario, target, grid_values(text, "grid")) == \
        pytest.approx(expected, rel=1e-13, abs=1e-300)                 # the API's grid=


@given(st.sampled_from(UNITS), NUMBERS, NUMBERS)
def test_a_unit_after_a_range_applies_to_both_bounds(scenario, case, lo, hi):
    target, unit, pints, si = case
    bounds = range_in_text(f"{lo!r}..{hi!r} {unit}", "--vary")
    probe = scenario.copy()
    inst, _, key = target.partition(".")
    got = []
    for bound in bounds:
        probe.set_value(target, bound)
        got.append(probe.instances[inst].parameters[key])
    assert got == pytest.approx([_pint(lo, pints, si), _pint(hi, pints, si)], rel=1e-13,
                                abs=1e-300)


@pytest.mark.slow
@given(st.lists(st.tuples(SWEPT, st.sampled_from(UNITS[:2])), min_size=1, max_size=4,
                unique_by=lambda vu: vu[0]))
def test_every_value_may_keep_its_own_unit(scenario, pairs):
    text = ", ".join(f"{v!r} {unit}" for v, (_, unit, _, _) in pairs)
    _, parsed = parse_grid_option(f"shaft.omega0={text}")
    expected = [_pint(v, pints, si) for v, (_, _, pints, si) in pairs]
    assert _swept(scenario, "shaft.omega0", parsed) == pytest.approx(expected, rel=1e-13,
                                                                      abs=1e-300)


@given(st.lists(st.booleans(), min_size=2, max_size=6).filter(
    lambda has: any(has) and not all(has) and has != [False] * (len(has) - 1) + [True]))
def test_some_values_with_a_unit_and_some_without_are_refused_as_ambiguous(has_unit):
    text = ", ".join(f"{i + 1}{' rpm' if has else ''}" for i, has in enumerate(has_unit))
    with pytest.raises(sewfmu.ScenarioError, match="ambiguous"):
        parse_grid_option(f"shaft.omega0={text}")


def test_the_brief_s_grid_runs_both_values_in_rpm(scenario):
    _, parsed = parse_grid_option("shaft.omega0=100,200 rpm")
    assert _swept(scenario, "shaft.omega0", parsed) == pytest.approx(
        [100 * 2 * math.pi / 60, 200 * 2 * math.pi / 60], rel=1e-15)
    with pytest.raises(sewfmu.ScenarioError, match="ambiguous.*a unit after the last value"):
        parse_grid_option("shaft.omega0=100 rpm, 200")


def test_a_scenario_file_s_grid_takes_the_same_text_and_refuses_a_mixed_array(tmp_path):
    text = sewfmu.show("punch_drive")
    path = tmp_path / "grid.toml"
    path.write_text(text + '\n[sweep]\ngrid = { "shaft.omega0" = "100, 200 rpm" }\n')
    assert [dict(p.values)["shaft.omega0"] for p in points_of(load(str(path)))] == \
        pytest.approx([100 * 2 * math.pi / 60, 200 * 2 * math.pi / 60], rel=1e-15)
    path.write_text(text + '\n[sweep]\ngrid = { "shaft.omega0" = [100, "200 rpm"] }\n')
    with pytest.raises(sewfmu.ScenarioError,
                       match=r"sweep\.grid\.shaft\.omega0: \[100, '200 rpm'\] mixes bare numbers"):
        load(str(path))
    path.write_text(text + '\n[compare]\nparameter = "shaft.omega0"\nvalues = [100, "200 rpm"]\n')
    with pytest.raises(sewfmu.ScenarioError, match=r"compare\.values: .* mixes bare numbers"):
        load(str(path))


def test_the_api_s_grid_refuses_a_mixed_list_before_anything_runs(tmp_path):
    with pytest.raises(sewfmu.ScenarioError, match="mixes bare numbers"):
        sewfmu.sweep("punch_drive", grid={"shaft.omega0": [100.0, "200 rpm"]}, out=tmp_path)
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize("text, says", [
    ("800 rpm..1200", "ambiguous: a unit after the upper bound applies to both"),
    ("800..1200..1500", "expected LO..HI"), ("1...2 mm", "expected LO..HI"),
    ("fast..slow", "expected LO..HI"), ("..2", "expected LO..HI")])
def test_a_range_follows_the_rule_of_lists(text, says):
    with pytest.raises(sewfmu.ScenarioError, match=says):
        range_in_text(text, "--vary shaft.omega0")


# the brief's bad values, and what each is refused for
BAD = [("10 degC", "degC is a temperature"),
       ("1 N**1000", "exponent beyond any unit's \\(whole numbers from -12 to 12"),
       ("1 kN**100", "exponent beyond any unit's"), ("1 kN**13", "exponents are whole numbers"),
       ("1 m**2**3", "a power follows a unit or a parenthesis, once"),
       ("1 (kN**12)**12", "exponents are whole numbers from -12 to 12"),
       ("1 N" + "⁹" * 40, "exponent beyond any unit's"), ("1 1000⁹⁹⁹⁹⁹⁹", "is not a unit"),
       ("1e999999", "range of a float"), ("1e999999 N", "beyond the range of a float"),
       ("10**10**10", "'\\*\\*10\\*\\*10' is not a unit"),
       ("1 m**1e9", "exponents are whole numbers"),
       ("1 N**1e400", "is not a unit: '400' cannot follow"), ("1 N**0.5", "exponent beyond"),
       ("9" * 5000, "range of a float"),
       ("nan", "not a finite number|finite number"), ("inf N", "not a finite number"),
       ("", "empty"), ("   ", "empty"),
       ("1 (N", "unbalanced parentheses"), ("1 N)", "unbalanced parentheses"),
       ("1 " + "(" * 400 + "N" + ")" * 400, "longer than any unit"),
       ("1 " + "*".join(["N"] * 3000), "longer than any unit"),
       ("3 furlongs_per_fortnight", "is not a unit"),
       ("100, 200 N", "one value here: a list")]


@pytest.mark.parametrize("text, says", BAD, ids=[b[0][:20] or "empty" for b in BAD])
def test_a_bad_value_is_one_line_at_every_door(tmp_path, text, says):
    # --set (as the command line reads it) and the API's set=
    with pytest.raises(sewfmu.ScenarioError, match=says) as typed:
        sewfmu.load("punch_drive", set={"punch.F30": sewfmu.read_value(text)})
    with pytest.raises(sewfmu.ScenarioError, match=says):
        sewfmu.load("punch_drive", set={"punch.F30": text})
    # a scenario file
    path = tmp_path / "bad.toml"
    quoted = text.replace("\\", "\\\\").replace('"', '\\"')
    path.write_text(sewfmu.show("punch_drive").replace(
        'fmu = "PunchContact"', f'fmu = "PunchContact"\nparameters = {{ F30 = "{quoted}" }}'))
    with pytest.raises(sewfmu.ScenarioError, match=says) as filed:
        sewfmu.load(path)
    # a design study's target and constraint (a key figure in N)
    with pytest.raises(sewfmu.ScenarioError, match=says) as target:
        goal_of({"F2_peak": "N"}, target={"F2_peak": text})
    with pytest.raises(sewfmu.ScenarioError, match=says):
        constraints_of({"F2_peak": "N"}, [("F2_peak", "<=", text)])
    for err in (typed, filed, target):
        assert "\n" not in str(err.value) and len(str(err.value)) < 400


def test_degrees_celsius_for_a_speed_is_a_wrong_dimension_not_pint_s_offset_error():
    """pint raised OffsetUnitCalculusError multiplying degC by a turn (for "300 1/min")."""
    with pytest.raises(sewfmu.ScenarioError,
                       match=r"degC is a temperature, shaft.omega0 wants a rotational speed"):
        sewfmu.load("punch_drive", set={"shaft.omega0": "10 degC"})


def test_a_scenario_file_with_a_5000_digit_integer_is_one_line(tmp_path):
    path = tmp_path / "digits.toml"
    path.write_text(sewfmu.show("punch_drive").replace("revolutions = 10",
                                                       "revolutions = " + "9" * 5000))
    with pytest.raises(sewfmu.ScenarioError, match="more than 4300 digits"):
        sewfmu.load(path)
    with pytest.raises(sewfmu.ScenarioError, match="range of a float.*about 5000 digits"):
        sewfmu.load("punch_drive", set={"punch.F30": 10 ** 5000})


def test_the_page_reads_a_typed_value_with_the_public_parser():
    from sewfmu.app.values import value_of

    assert value_of("100") == 100 and value_of("true") is True
    assert value_of("955 rpm") == "955 rpm" and value_of("9" * 5000) == "9" * 5000
    assert sewfmu.read_value('"955 rpm"') == "955 rpm"
    with pytest.raises(sewfmu.ScenarioError, match="expected a text"):
        sewfmu.read_value(5)
