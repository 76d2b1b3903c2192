"""Reference files are user input (scenarios/references/reference_files.py): every .opt value and
every CSV property is checked with one line naming the file and what is wrong, a nan or inf in a
reference never masks a deviation, a modelName never leads a write out of the folder given, and
whatever the bytes, reading gives a reference or a ScenarioError, nothing else.

The FMU tests check sewfmu's Fabric FMU and a copy whose F2 is doubled (built from a modified
copy of the model code, as tests/references/test_references.py changes gravity) against a reference of the
original's."""
import math
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sewfmu.cli import main
from sewfmu.scenarios.fmu_build.build import MODEL_CODE_DIR, build_fmu
from sewfmu.scenarios.format.values import ScenarioError
from sewfmu.scenarios.references import fmu_reference, reference_check
from sewfmu.scenarios.references.fmu_reference import Experiment, Reference, compare
from sewfmu.scenarios.references.reference_files import (
    MAX_STEPS,
    inside,
    parse_csv,
    parse_options,
    plain_name,
)
from tests.foreign_fmus import rewritten

GOOD = "time,x,y\n0,1,2\n0.5,1.5,2.5\n1,2,3\n"


def _refused(call, *fragments) -> str:
    """The ScenarioError of the call: one line, holding every fragment."""
    with pytest.raises(ScenarioError) as caught:
        call()
    message = str(caught.value)
    assert "\n" not in message, message
    for fragment in fragments:
        assert fragment in message, message
    return message


# --- the CSV ----------------------------------------------------------------------------------
def test_a_good_csv_is_read_with_its_text_columns_left_out():
    text = '\ufefftime,"x", s ,flag\r\n0,1,a,true\r\n1,nan,b,false\r\n2,-inf,c,TRUE\r\n\r\n'
    columns, text_columns = parse_csv(text.encode(), "r.csv")
    assert list(columns) == ["time", "x", "flag"] and text_columns == ["s"]
    assert np.array_equal(columns["time"], [0, 1, 2])
    assert math.isnan(columns["x"][1]) and columns["x"][2] == -math.inf
    assert list(columns["flag"]) == [1.0, 0.0, 1.0]


@pytest.mark.parametrize("text, fragments", [
    ("time,x,x\n0,1,2\n1,1,2\n", ["r.csv, line 1", "'x' appears twice (columns 2 and 3)"]),
    ("time,x\n0,1\n2,1\n1,1\n", ["r.csv, line 4", "the time 1 s follows 2 s (line 3)"]),
    ("time,x\n0,1\n0,2\n", ["r.csv, line 3", "each time once"]),
    ("time,x,y\n0,1,2\n1,1\n", ["r.csv, line 3: 2 cells, the header has 3"]),
    ("time,x\n0,1\n1,1,\n", ["r.csv, line 3: 3 cells, the header has 2"]),
    ("x,time\n0,1\n1,1\n", ["r.csv, line 1", "the first column is 'x'", "starts with time"]),
    ("time,,y\n0,1,2\n1,1,2\n", ["r.csv, line 1, column 2: a column without a name"]),
    ("time,x\n0,1\n1,1o\n", ["r.csv, line 3, column x: '1o' is not a number, and the column's"]),
    ("time,x\n0,1\nnan,1\n", ["r.csv, line 3, column time: 'nan'", "finite number"]),
    ("time,x\n0,1\n1e999,1\n", ["r.csv, line 3, column time"]),
    ("time,x\n0,1\n1,1_0\n", ["r.csv, line 3, column x: '1_0' is not a number"]),
    ("time,s\n0,a\n1,b\n", ["r.csv, line 1: no column of numbers beside time ('s': text)"]),
    ("time\n0\n1\n", ["r.csv, line 1: no column of numbers beside time"]),
    ("time,x\n0,1\n", ["r.csv: 1 rows of values", "two or more"]),
    ("", ["r.csv: empty"]),
    ("\n\n", ["r.csv: empty"]),
    ('time,x\n0,"' + "9" * 200_000 + '"\n', ["r.csv, line 2: not CSV (field larger"]),
    ("time,x\n0,1\n1,\0\n", ["r.csv, line 3: a NUL character"]),
])
def test_a_damaged_csv_is_refused_in_one_line(text, fragments):
    _refused(lambda: parse_csv(text.encode(), "r.csv"), *fragments)


def test_bytes_that_are_not_utf8_are_refused_with_their_line():
    _refused(lambda: parse_csv(b"time,x\n0,1\n1,\xff\xfe\n", "r.csv"),
             "r.csv, line 3: byte 0xff is not UTF-8 text")


def test_inputs_are_finite_numbers_and_may_jump():
    columns, _ = parse_csv(b"time,u\n0,1\n1,1\n1,2\n2,2\n", "in.csv", inputs=True)
    assert list(columns["time"]) == [0, 1, 1, 2]          # a jump at t = 1 s, as fmpy reads it
    _refused(lambda: parse_csv(b"time,u\n0,1\n1,nan\n", "in.csv", inputs=True),
             "in.csv, line 3, column u: 'nan'; an input is a finite number")
    _refused(lambda: parse_csv(b"time,u,s\n0,1,a\n", "in.csv", inputs=True),
             "in.csv, line 2, column s: 'a' is not a number")
    _refused(lambda: parse_csv(b"time,u\n1,1\n0,1\n", "in.csv", inputs=True), "never decreases")


# --- the .opt ---------------------------------------------------------------------------------
def test_a_good_opt_is_read():
    text = b"StartTime, 0.0\r\n\r\nStopTime,2\nStepSize , 1e-3\nRelTol, 1e-6\n"
    assert parse_options(text, "r.opt") == {"StartTime": 0.0, "StopTime": 2.0,
                                            "StepSize": 1e-3, "RelTol": 1e-6}


@pytest.mark.parametrize("text, fragments", [
    ("RelTol, inf", ["r.opt, line 1: RelTol is 'inf'; a finite number"]),
    ("RelTol, nan", ["r.opt, line 1: RelTol is 'nan'"]),
    ("RelTol, 1e300", ["r.opt, line 1: RelTol is 1e+300; a relative tolerance between 0 and 1"]),
    ("RelTol, 0", ["RelTol is 0; a relative tolerance between 0 and 1"]),
    ("RelTol, 1", ["RelTol is 1; a relative tolerance between 0 and 1"]),
    ("StartTime, 0\nStepSize, 0", ["r.opt, line 2: StepSize is 0; a step longer than 0 s"]),
    ("StepSize, -1e-3", ["StepSize is -0.001"]),
    ("StopTime, 1e999", ["StopTime is '1e999'; a finite number"]),
    ("StopTime, true", ["StopTime is 'true'; a finite number"]),
    ("StopTime 2", ["r.opt, line 1: 'StopTime 2' is not `Name, value`"]),
    ("Stoptime, 2", ["r.opt, line 1: unknown option 'Stoptime'", "StartTime, StopTime"]),
    ("StopTime, 2\nStopTime, 3", ["r.opt, line 2: StopTime again (first on line 1)"]),
    ("StopTime, 2, 3", ["StopTime is '2, 3'"]),
])
def test_a_damaged_opt_is_refused_in_one_line(text, fragments):
    _refused(lambda: parse_options(text.encode(), "r.opt"), *fragments)


def _folder(csv: str, opt: str | None = None, inputs: str | None = None) -> Path:
    folder = Path(tempfile.mkdtemp(prefix="sewfmu_refs_"))
    (folder / "M").mkdir()
    (folder / "M" / "M_ref.csv").write_text(csv)
    if opt is not None:
        (folder / "M" / "M_ref.opt").write_text(opt)
    if inputs is not None:
        (folder / "M" / "M_in.csv").write_text(inputs)
    return folder


@pytest.mark.parametrize("opt, fragments", [
    ("StartTime, 0\nStopTime, 1e12\nStepSize, 0.01\n", ["M_ref.opt (with M_ref.csv)",
                                                        "1e+14 steps; at most 1e+07"]),
    ("StopTime, 0\n", ["StopTime 0 s is not after StartTime 0 s"]),
    ("StopTime, 1\nStepSize, 2\n", ["StepSize 2 s; a step longer than 0 and at most the run"]),
    ("StartTime, 1e12\nStopTime, 1e12+1\n", ["StopTime is '1e12+1'"]),
    ("StartTime, 1e12\nStopTime, 1000000000001\nStepSize, 1e-7\n", ["below what times near"]),
    ("StartTime, 0.5\n", ["the reference's rows run from 0 to 1 s, outside the run from "
                          "StartTime 0.5"]),
    ("StopTime, 0.5\n", ["outside the run"]),
])
def test_the_experiment_of_a_reference_is_checked(opt, fragments):
    folder = _folder(GOOD, opt)
    _refused(lambda: fmu_reference.read_cross_check(folder, "M"), *fragments)


def test_a_reference_without_an_opt_runs_on_its_own_time_grid():
    reference = fmu_reference.read_cross_check(_folder(GOOD), "M")
    assert (reference.experiment.start, reference.experiment.stop,
            reference.experiment.step) == (0.0, 1.0, 0.5)
    # a grid of 10^8 steps (its median step) is refused as a run, as an .opt giving it would be
    dense = "time,x\n" + "".join(f"{k * 1e-8!r},0\n" for k in range(5)) + "1,0\n"
    _refused(lambda: fmu_reference.read_cross_check(_folder(dense), "M"),
             "M_ref.csv: StepSize 1e-08 s from 0 to 1 s is 1e+08 steps")


def test_max_steps_is_the_bound_on_a_run():
    folder = _folder(GOOD, f"StopTime, 1\nStepSize, {1 / MAX_STEPS!r}\n")
    assert fmu_reference.read_cross_check(folder, "M").experiment.step == 1 / MAX_STEPS


# --- nan never masks a deviation --------------------------------------------------------------
def _reference(**columns) -> Reference:
    t = np.arange(5.0)
    return Reference("M", "M_ref.csv", {"time": t, **{k: np.array(v, float)
                                                      for k, v in columns.items()}},
                     Experiment(0.0, 4.0, 1.0))


@pytest.mark.parametrize("spoiler", [math.nan, math.inf, -math.inf])
def test_a_non_finite_reference_value_masks_no_other_deviation(spoiler):
    reference = _reference(x=[spoiler, 1, 2, 3, 4])
    # the FMU reproduces the spoiler, and doubles x from t = 2 s: caught at t = 2 s
    got = {"time": np.arange(5.0), "x": np.array([spoiler, 1, 4, 6, 8])}
    (deviation,) = compare("M", got, reference)
    assert (deviation.time, deviation.value, deviation.expected) == (2.0, 4.0, 2.0)
    assert deviation.allowed == pytest.approx(1e-12 + 1e-6 * 4)   # of the finite values
    # where the FMU gives a number, the reference's nan (or inf) is itself a deviation
    (deviation,) = compare("M", {"time": got["time"], "x": np.arange(5.0)}, reference)
    assert deviation.time == 0.0 and not math.isfinite(deviation.expected)
    assert "the reference " in str(deviation)


def test_the_fmu_giving_nan_or_inf_where_the_reference_has_a_number_deviates():
    reference = _reference(x=[0, 1, 2, 3, 4])
    for bad in (math.nan, math.inf):
        (deviation,) = compare("M", {"time": np.arange(5.0), "x": np.array([0, 1, bad, 3, 4])},
                               reference)
        assert deviation.time == 2.0
    assert compare("M", {"time": np.arange(5.0), "x": np.arange(5.0)}, reference) == []


# --- names from inside an FMU -----------------------------------------------------------------
@pytest.mark.parametrize("name", ["../../escaped", "/tmp/abs", "a/b", "a\\b", "..", ".", "",
                                  ".hidden", "C:x", "x\n", " x", "x" * 201, None])
def test_a_model_name_that_is_not_a_plain_file_name_is_refused(name):
    _refused(lambda: plain_name(name, "X.fmu"), "X.fmu: the modelName", "not a plain file name")


def test_plain_model_names_pass():
    for name in ("Spring", "Modelica.Blocks.Examples.PID_Controller", "Näh-Maschine 2"):
        assert plain_name(name, "X.fmu") == name


def test_a_link_out_of_the_folder_is_refused(tmp_path):
    refs, outside = tmp_path / "refs", tmp_path / "outside"
    refs.mkdir()
    outside.mkdir()
    (refs / "M").symlink_to(outside)
    assert inside(refs, refs / "N" / "N_ref.csv", "X.fmu") == refs / "N" / "N_ref.csv"
    _refused(lambda: inside(refs, refs / "M" / "M_ref.csv", "X.fmu"),
             f"outside {refs} (a link?)")
    _refused(lambda: fmu_reference.plot_file(refs, "../M", "X.fmu"), "not a plain file name")


# --- fuzzing: a reference or a ScenarioError, whatever the bytes ------------------------------
# these parsers are fast: many more examples than the profile's default
FUZZ = settings(max_examples=max(300, settings.default.max_examples), deadline=None)
_CELLS = st.sampled_from(["time", "x", "y", "0", "1", "-1", "0.5", "1e3", "1e999", "nan",
                          "inf", "-inf", "true", "false", "abc", "", " ", '"', '"a,b"', "1_0",
                          "\u0661", "\0", "\ufeff", "\r", "x\ny"])
_NUMBERS = st.one_of(st.integers(-3, 3).map(str), st.floats().map(repr),
                     st.sampled_from(["1e3", "true", "nan", "-inf"]))


@st.composite
def _tables(draw) -> str:
    """Well-formed tables, half of them with one damage: most examples get past the header, so
    that the checks of rows, cells and times are reached, and some are read."""
    names = ["time", *draw(st.lists(st.sampled_from(["x", "y", "s"]), min_size=1, max_size=3,
                                    unique=True))]
    times = sorted(draw(st.lists(st.floats(0, 10), min_size=2, max_size=8, unique=True)))
    rows = [[repr(t), *(draw(_NUMBERS) for _ in names[1:])] for t in times]
    damage = draw(st.integers(0, 9))
    if damage == 5:
        rows[draw(st.integers(0, len(rows) - 1))].append(draw(_CELLS))     # a ragged row
    elif damage == 6:
        rows[draw(st.integers(0, len(rows) - 1))][draw(st.integers(0, len(names) - 1))] = \
            draw(_CELLS)                                                  # a cell of text
    elif damage == 7:
        rows.reverse()                                                    # out of order
    elif damage == 8:
        names.append(draw(st.sampled_from(["x", "time", "", " "])))      # a name twice, or none
        for row in rows:
            row.append(draw(_NUMBERS))
    elif damage == 9:
        rows = [row for row in rows for _ in (0, 1)]                      # each time twice
    return "\n".join(",".join(row) for row in [names, *rows])


@st.composite
def _opts(draw) -> str:
    value = st.one_of(st.floats(-1, 20).map(repr), st.floats().map(repr), _CELLS)
    lines = [f"{name}, {draw(value)}" for name in ("StartTime", "StopTime", "StepSize", "RelTol")
             if draw(st.booleans())]
    if draw(st.integers(0, 3)) == 0:                    # a line of another shape
        lines.insert(draw(st.integers(0, len(lines))),
                     f"{draw(st.sampled_from(['Other', 'StopTime', '']))}"
                     f"{draw(st.sampled_from([',', ';', '']))}{draw(_CELLS)}")
    return "\n".join(lines)


_ROWS = st.lists(st.lists(_CELLS, min_size=1, max_size=4), max_size=6)
_CSV_TEXT = st.one_of(_tables(), _tables(), _ROWS.map(lambda rs: "\n".join(",".join(r) for r in rs)),
                      st.text(max_size=60))
_OPT_TEXT = st.one_of(_opts(), _opts(), st.text(max_size=60))


def _parsed_or_refused(call):
    try:
        return call()
    except ScenarioError as err:
        assert "\n" not in str(err), str(err)
        return None


def _sound(columns: dict, text_columns: list, inputs: bool = False) -> None:
    """What a parsed CSV promises the comparison."""
    times = columns["time"]
    assert len(times) >= (1 if inputs else 2) and np.all(np.isfinite(times))
    assert np.all(np.diff(times) >= 0) if inputs else np.all(np.diff(times) > 0)
    assert len(set(columns) | set(text_columns)) == len(columns) + len(text_columns)
    assert all(len(v) == len(times) for v in columns.values()) and len(columns) >= 2


@pytest.mark.slow
@FUZZ
@given(st.one_of(st.binary(max_size=200), _CSV_TEXT.map(str.encode)), st.booleans())
def test_any_bytes_give_a_csv_or_a_scenario_error(raw, inputs):
    parsed = _parsed_or_refused(lambda: parse_csv(raw, "r.csv", inputs=inputs))
    if parsed is not None:
        _sound(*parsed, inputs)


@FUZZ
@given(st.one_of(st.binary(max_size=120), _OPT_TEXT.map(str.encode)))
def test_any_bytes_give_options_or_a_scenario_error(raw):
    options = _parsed_or_refused(lambda: parse_options(raw, "r.opt"))
    if options is not None:
        assert set(options) <= {"StartTime", "StopTime", "StepSize", "RelTol"}
        assert all(math.isfinite(v) for v in options.values())
        assert options.get("StepSize", 1) > 0 and 0 < options.get("RelTol", 0.5) < 1


@pytest.mark.slow
@settings(FUZZ, max_examples=max(150, settings.default.max_examples))    # files: slower
@given(_CSV_TEXT, st.one_of(st.none(), _OPT_TEXT), st.one_of(st.none(), st.none(), _CSV_TEXT))
def test_any_reference_folder_gives_a_reference_or_a_scenario_error(csv, opt, inputs):
    folder = _folder(csv, opt, inputs)
    try:
        reference = _parsed_or_refused(lambda: fmu_reference.read_cross_check(folder, "M"))
    finally:
        shutil.rmtree(folder)
    if reference is not None:
        _sound(reference.columns, reference.not_compared)
        e = reference.experiment
        assert e.stop > e.start and 0 < e.step and (e.stop - e.start) / e.step <= MAX_STEPS
        assert 0 < e.rel_tol < 1


# --- with FMUs: the Fabric, and a copy whose F2 is doubled -------------------------------------
@pytest.fixture(scope="module")
def doubled_f2(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("doubled")
    source = folder / "components"
    shutil.copytree(MODEL_CODE_DIR, source, ignore=shutil.ignore_patterns("__pycache__"))
    code = (source / "punch_fmu.py").read_text()
    assert code.count("return (f2, fabric.force_rate(") == 1      # the Fabric's F2 output
    (source / "punch_fmu.py").write_text(code.replace("return (f2, fabric.force_rate(",
                                                      "return (2.0 * f2, fabric.force_rate("))
    return build_fmu("Fabric", folder / "fmus", source=source)


@pytest.fixture
def recorded(fmu_paths, tmp_path) -> Path:
    """The original Fabric's reference (its regression case: the punch lands, F2 rises)."""
    refs = tmp_path / "refs"
    reference_check.record(fmu_paths["Fabric"], refs)
    return refs


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text, (old, text[:200])
    path.write_text(text.replace(old, new, 1))


def test_the_doubled_f2_is_caught_and_the_original_passes(fmu_paths, doubled_f2, recorded):
    (original,) = reference_check.check(fmu_paths["Fabric"], recorded)
    assert original.deviations == []
    (doubled,) = reference_check.check(doubled_f2, recorded)
    assert "F2" in [d.variable for d in doubled.deviations]


@pytest.mark.parametrize("rel_tol", ["inf", "nan", "1e300"])
def test_a_tolerance_that_would_pass_the_doubled_f2_is_refused(doubled_f2, recorded, rel_tol):
    opt = recorded / "Fabric" / "Fabric_ref.opt"
    _edit(opt, "RelTol, 1e-09", f"RelTol, {rel_tol}")
    _refused(lambda: reference_check.check(doubled_f2, recorded), f"{opt}, line 4: RelTol is")


@pytest.mark.parametrize("old, new, fragment", [
    ("StepSize, 0.0001", "StepSize, 0", "line 3: StepSize is 0; a step longer than 0 s"),
    ("StopTime, 0.025", "StopTime, 1e12", "1e+16 steps; at most 1e+07"),
])
def test_run_options_that_would_fail_or_never_end_are_refused(fmu_paths, recorded, old, new,
                                                              fragment):
    _edit(recorded / "Fabric" / "Fabric_ref.opt", old, new)
    _refused(lambda: reference_check.check(fmu_paths["Fabric"], recorded), "Fabric_ref.opt",
             fragment)


def test_a_nan_in_the_reference_hides_no_deviation(fmu_paths, doubled_f2, recorded):
    result = recorded / "Fabric" / "Fabric_ref.csv"
    lines = result.read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[3].split(",")
    cells[header.index("F2")] = "nan"                 # the FMU gives 0 there, before contact
    lines[3] = ",".join(cells)
    result.write_text("\n".join(lines) + "\n")
    (doubled,) = reference_check.check(doubled_f2, recorded)
    f2 = next(d for d in doubled.deviations if d.variable == "F2")
    assert math.isnan(f2.expected) and f2.value == 0.0     # the nan itself deviates
    (original,) = reference_check.check(fmu_paths["Fabric"], recorded)
    assert [d.variable for d in original.deviations] == ["F2"]


@pytest.mark.parametrize("damage, fragment", [
    (lambda lines: [lines[0].replace("F2_dot", "F2")] + lines[1:], "'F2' appears twice"),
    (lambda lines: lines[:2] + [lines[3], lines[2]] + lines[4:], "line 4: the time"),
    (lambda lines: lines[:2] + [lines[2].rsplit(",", 1)[0]] + lines[3:], "line 3: 5 cells"),
])
def test_a_damaged_recorded_reference_is_refused(fmu_paths, recorded, damage, fragment):
    result = recorded / "Fabric" / "Fabric_ref.csv"
    result.write_text("\n".join(damage(result.read_text().splitlines())) + "\n")
    _refused(lambda: reference_check.check(fmu_paths["Fabric"], recorded), str(result), fragment)


@pytest.mark.parametrize("model_name", ["../../escaped", "{outside}/abs", "..", "a/b"])
def test_a_model_name_never_leads_a_recording_out_of_the_folder(fmu_paths, tmp_path, capsys,
                                                                model_name):
    work, outside = tmp_path / "work", tmp_path / "outside"
    refs = work / "a" / "refs"
    refs.mkdir(parents=True)
    outside.mkdir()
    fmu = rewritten(fmu_paths["Fabric"], tmp_path, modelName=model_name.format(outside=outside))
    assert main(["references", "--fmu", str(fmu), "--refs", str(refs), "--regenerate"]) == 1
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1 and "is not a plain file name" in error, error
    written = [p for p in tmp_path.rglob("*") if p.is_file() and p != fmu]
    assert written == [], written
    # checking with that folder reads nothing outside it either
    assert main(["references", "--fmu", str(fmu), "--refs", str(refs)]) == 1
    assert "is not a plain file name" in capsys.readouterr().err


def test_a_recording_through_a_link_out_of_the_folder_is_refused(fmu_paths, tmp_path):
    refs, outside = tmp_path / "refs", tmp_path / "outside"
    refs.mkdir()
    outside.mkdir()
    (refs / "Fabric").symlink_to(outside)
    _refused(lambda: reference_check.record(fmu_paths["Fabric"], refs), "(a link?)")
    assert list(outside.iterdir()) == []


@pytest.mark.parametrize("attributes, fragment", [
    ({"stopTime": "1e12"}, "DefaultExperiment: StepSize 5e-05 s from 0 to 1e+12 s is 2e+16 steps"),
    ({"stepSize": "0"}, "DefaultExperiment: StepSize 0 s; a step longer than 0"),
    ({"stopTime": "nan"}, "DefaultExperiment: StopTime is nan; a finite number"),
    ({"stepSize": "fast"}, "DefaultExperiment stepSize='fast'; a number"),
])
def test_a_default_experiment_that_cannot_run_is_refused_before_recording(fmu_paths, tmp_path,
                                                                          attributes, fragment):
    # another modelName: not one of sewfmu's, so its DefaultExperiment is what is recorded
    fmu = rewritten(fmu_paths["Fabric"], tmp_path, modelName="Other", **attributes)
    _refused(lambda: reference_check.record(fmu, tmp_path / "refs"), str(fmu), fragment)
    assert not (tmp_path / "refs").exists()
