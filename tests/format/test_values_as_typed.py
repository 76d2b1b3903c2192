"""The attack on the value grammar (docs/scenarios.md, "Values with units"), one test per finding:
the command line and the API read one grammar (a TOML comment, hex, '_' were numbers on one and
refused by the other), a list that reads as thousands is refused, a value exactly at a declared
bound passes whatever the rounding of its unit, refusals name the option the value came from and
the cause (a shaft too slow, not the step), real numbers of other types are taken, a folder and
a long path are named as what they are, and [compare] takes a text list as the doc says."""
import decimal
import fractions
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import sewfmu
from sewfmu.cli import main
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.format.value_lists import range_in_text, values_in_text
from sewfmu.scenarios.format.values import parse_value, short

RPM = 2 * math.pi / 60              # rad/s per rpm, independent of pint


def _through_the_cli(text):
    """The number --set gives shaft.omega0 for `text`, or the refusal's line."""
    sc = load("punch_drive")
    try:
        sc.set_value("shaft.omega0", parse_value(text, f"--set shaft.omega0={text}"))
    except sewfmu.Error as err:
        return "refused", str(err)
    return sc.instances["shaft"].parameters["omega0"], ""


def _through_the_api(text):
    try:
        sc = sewfmu.load("punch_drive", set={"shaft.omega0": text})
    except sewfmu.Error as err:
        return "refused", str(err)
    return sc.instances["shaft"].parameters["omega0"], ""


@pytest.mark.parametrize("text, says", [
    ("100 # rpm", "'#' starts no comment"),          # ran at 100 rad/s from the command line
    ("0x64", "hexadecimal, octal and binary"),
    ("0b1100100", "hexadecimal, octal and binary"),
    ("0o144", "hexadecimal, octal and binary"),
    ("1_00", "'_' between digits"),
    ("007", "starts with 0 only where it is 0"),
    ("[100]", "must be a number"),
])
def test_what_toml_alone_reads_is_refused_by_the_command_line_and_the_api_alike(text, says):
    cli, api = _through_the_cli(text), _through_the_api(text)
    assert cli[0] == api[0] == "refused", (cli, api)
    for line in (cli[1], api[1]):
        assert says in line and "\n" not in line, line


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(st.one_of(st.text(max_size=30), st.builds(
    lambda sign, digits, tail: sign + digits + tail, st.sampled_from(["", "-", "+"]),
    st.from_regex(r"[0-9_.xobeE]{1,8}", fullmatch=True),
    st.sampled_from(["", " rpm", "rpm", " # rpm", " rad/s", "e3", ",5", " 1/min"]))))
def test_the_command_line_and_the_api_read_every_text_alike(text):
    """Whatever the text (not a quoted TOML string, which the API's set= takes as the Python
    string it is): both doors give the same number, or both refuse."""
    if text.strip()[:1] in ("'", '"') or text.strip() in ("true", "false"):
        return
    cli, api = _through_the_cli(text), _through_the_api(text)
    assert (cli[0] == "refused") == (api[0] == "refused"), (text, cli, api)
    if cli[0] != "refused":
        assert cli[0] == api[0], (text, cli, api)


@pytest.mark.parametrize("text, rad_s", [
    ("100", 100.0), ("1e2", 100.0), ("+100", 100.0), ("100.", 100.0), (".5", 0.5),
    ("955 rpm", 955 * RPM), ("955rpm", 955 * RPM), ("0.5 rev/s", 0.5 * 2 * math.pi),
])
def test_what_the_grammar_reads_is_the_same_number_on_both_doors(text, rad_s):
    cli, api = _through_the_cli(text), _through_the_api(text)
    assert cli[0] == pytest.approx(rad_s, rel=1e-12) and api[0] == pytest.approx(rad_s, rel=1e-12)


def test_a_quoted_string_is_a_string_and_a_word_is_handed_on():
    assert parse_value('"gauss-seidel"', "x") == "gauss-seidel"
    assert parse_value("'jacobi'", "x") == "jacobi"
    assert parse_value('"a" # b', "x") == '"a" # b'        # no comment after a string either
    assert parse_value("true", "x") is True and parse_value("1979-05-27", "x") == "1979-05-27"


@pytest.mark.parametrize("text", ["1,000 N", "2,500", "1,000,000 N", "12,000", "1,050"])
def test_a_list_that_reads_as_thousands_is_refused_with_the_number_it_meant(text):
    with pytest.raises(sewfmu.ScenarioError, match="thousands separators") as bad:
        values_in_text(text, "--grid punch.F30")
    meant = text.split()[0].replace(",", "")
    assert f"({meant})" in str(bad.value) and "\n" not in str(bad.value)
    assert main(["sweep", "punch_drive", "--grid", f"punch.F30={text}"]) == 1


@pytest.mark.parametrize("text, values", [
    ("1, 500 N", ["1 N", "500 N"]), ("100,200 rpm", ["100 rpm", "200 rpm"]),
    ("90,100", [90, 100]), ("400,500", [400, 500]),
])
def test_lists_with_spaces_or_of_three_digit_values_stay_lists(text, values):
    assert values_in_text(text, "--grid x") == values


def test_a_leading_zero_in_a_spaced_list_is_refused_where_it_is_read():
    assert values_in_text("100, 050", "--grid punch.F30") == [100, "050"]
    with pytest.raises(sewfmu.ScenarioError, match="starts with 0 only"):
        sewfmu.load("punch_drive", set={"punch.F30": "050"})


@pytest.mark.parametrize("text", ["nan..1200 rpm", "800..nan", "-inf..1200", "800..Infinity"])
def test_a_range_with_a_nan_bound_names_it(text):
    with pytest.raises(sewfmu.ScenarioError, match="is not a finite number") as bad:
        range_in_text(text, "--vary shaft.omega0")
    assert "expected LO..HI" not in str(bad.value)


def test_a_value_at_a_declared_bound_through_its_unit_is_that_bound():
    """400 grad is 2π rad exactly, the declared maximum of an angle (MACHINE_SCALE); pint's
    factor puts it one rounding above. 0.5 rev is π."""
    sc = sewfmu.check("punch_drive", set={"linkage.angle_BO2C": "400 grad"})
    assert sc.instances["linkage"].parameters["angle_BO2C"] == 2 * math.pi
    sc = sewfmu.check("punch_drive", set={"linkage.angle_BO2C": "360 deg"})
    assert sc.instances["linkage"].parameters["angle_BO2C"] == 2 * math.pi
    below = sewfmu.load("punch_drive", set={"linkage.angle_BO2C": "399.99 grad"})
    assert below.instances["linkage"].parameters["angle_BO2C"] == \
        pytest.approx(399.99 * math.pi / 200, rel=1e-14)          # not moved to the bound


def test_a_value_beyond_a_bound_shows_the_digits_that_differ_and_no_unit_for_one_given():
    with pytest.raises(sewfmu.ScenarioError) as with_unit:
        sewfmu.check("punch_drive", set={"shaft.omega0": "19098.6 rpm"})
    line = str(with_unit.value)                  # 19098.6 rpm is 2000.000715 rad/s
    assert f"{19098.6 * RPM:.10g} rad/s is outside the range [0, 2000]" in line, line
    assert "meant in" not in line and "19098.6 rpm" in line and line.startswith("set ")
    with pytest.raises(sewfmu.ScenarioError) as bare:
        sewfmu.check("punch_drive", set={"shaft.omega0": 2000.0000001})
    assert "2000.0000001 rad/s is outside the range [0, 2000]" in str(bare.value)
    with pytest.raises(sewfmu.ScenarioError) as ulp:
        sewfmu.check("punch_drive", set={"linkage.angle_BO2C": math.nextafter(2 * math.pi, 7)})
    assert f"{math.nextafter(2 * math.pi, 7)!r} rad is outside the range [0, " \
           f"{2 * math.pi!r}]" in str(ulp.value)
    with pytest.raises(sewfmu.ScenarioError) as swept:      # a sweep's points too
        sewfmu.sweep("punch_drive", grid={"shaft.omega0": "100, 19098.6 rpm"})
    assert "meant in" not in str(swept.value) and "given as '19098.6 rpm'" in str(swept.value)
    with pytest.raises(sewfmu.Error) as run:     # the run's own check of the shaft, too
        sewfmu.run("punch_drive", set={"shaft.omega0": "19098.6 rpm"})
    assert "meant in" not in str(run.value) and "2000.000715" in str(run.value)


def test_a_speed_so_small_the_run_never_ends_is_named_not_the_step():
    for speed in ("5e-324 rad/s", "1e-300 rad/s"):
        with pytest.raises(sewfmu.ScenarioError) as bad:
            sewfmu.check("punch_drive", set={"shaft.omega0": speed})
        line = str(bad.value)
        assert line.startswith("set shaft.omega0") and "so slow" in line, line
        assert "experiment.step" not in line
    with pytest.raises(sewfmu.ScenarioError, match="experiment.step 1e-30 s makes more than"):
        sewfmu.check("punch_drive", set={"experiment.step": "1e-30 s"})


def test_a_refused_value_names_the_option_it_came_from_not_the_catalogue_file(capsys):
    assert main(["run", "punch_drive", "--set", "shaft.omega0=-5"]) == 1
    line = capsys.readouterr().err.strip()
    assert line.startswith("sewfmu: error: --set shaft.omega0:") and "catalogue" not in line
    assert main(["sweep", "punch_drive", "--grid", "shaft.omega0=-5, 100"]) == 1
    line = capsys.readouterr().err.strip()
    assert line.startswith("sewfmu: error: --grid (grid=) shaft.omega0:"), line
    with pytest.raises(sewfmu.ScenarioError) as bad:
        sewfmu.sweep("punch_drive", grid={"shaft.omega0": [-5.0, 100.0]})
    assert str(bad.value).startswith("--grid (grid=) shaft.omega0:")


@pytest.mark.parametrize("number", [decimal.Decimal("300"), fractions.Fraction(300),
                                    np.longdouble(300), np.float16(300)])
def test_real_numbers_of_other_types_are_taken(number):
    sc = sewfmu.check("punch_drive", set={"shaft.omega0": number})
    assert sc.instances["shaft"].parameters["omega0"] == 300.0
    assert type(sc.instances["shaft"].parameters["omega0"]) is float


def test_a_real_number_beyond_a_float_is_refused_in_one_line():
    with pytest.raises(sewfmu.ScenarioError, match="finite number"):
        sewfmu.load("punch_drive", set={"shaft.omega0": decimal.Decimal("1e999")})


def test_a_folder_is_named_a_folder_and_a_long_text_is_counted_in_characters(tmp_path):
    (tmp_path / "dir.toml").mkdir()
    for folder in (tmp_path / "dir.toml", tmp_path):
        with pytest.raises(sewfmu.ScenarioError, match="is a folder, not a scenario"):
            sewfmu.load(str(folder))
    assert "(5000 characters)" in short("x" * 4998)
    assert "digits" in short(10 ** 60) and "characters" not in short(10 ** 60)

    class Odd:
        def __repr__(self):
            raise RuntimeError("no")
    assert short(Odd()) == "an object of type Odd"


def test_compare_takes_a_text_list_as_the_doc_says(tmp_path):
    from sewfmu.scenarios.runs.variants import variants  # the runs a [compare] makes

    text = sewfmu.show("punch_drive") + '\n[compare]\nparameter = "shaft.omega0"\n' \
                                        'values = "955, 1910 rpm"\n'
    (tmp_path / "cmp.toml").write_text(text)
    runs = variants(sewfmu.load(str(tmp_path / "cmp.toml")))
    assert [label for label, _ in runs] == ["shaft.omega0=955 rpm", "shaft.omega0=1910 rpm"]
    assert [sc.instances["shaft"].parameters["omega0"] for _, sc in runs] == \
        pytest.approx([955 * RPM, 1910 * RPM], rel=1e-12)
