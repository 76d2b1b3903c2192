"""A design study's folder and records: a fit run again resumes from its record and follows the
first fit's path exactly; a record of another study is set aside under a fresh name, never over a
file that is there; two studies or sweeps into one folder at once: the second is refused in one
line, and the first's record stays whole; `vary` given as numpy arrays or in a wrong shape."""
import csv
import multiprocessing
import time
from pathlib import Path

import numpy as np
import pytest

import sewfmu
from sewfmu.scenarios.files.outputs import OutputError, held, set_aside

SHORT = {"experiment.revolutions": 1}


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


def _trace(path: Path, **parameters) -> None:
    r = sewfmu.run("punch_drive", set={**SHORT, **parameters})
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows([["time", "punch.F2 [N]"],
                                 *zip(r.series["time"].tolist(), r.series["punch.F2"].tolist())])


@pytest.mark.slow
def test_a_fit_run_again_resumes_from_its_record(tmp_path):
    _trace(tmp_path / "trace.csv", **{"punch.b2": 70.0})
    out = tmp_path / "fit"
    first = sewfmu.fit("punch_drive", data=tmp_path / "trace.csv", free={"punch.b2": "20..300"},
                       out=out)
    assert first.converged and first.evaluations > 2
    record = (out / "fit_evaluations.jsonl").read_text().splitlines()
    assert len(record) == 1 + first.evaluations             # a header, then a line a run
    again = sewfmu.fit("punch_drive", data=tmp_path / "trace.csv", free={"punch.b2": "20..300"},
                       out=out)
    # nothing run again but the optimum's series, drawn for the plot
    assert again.summary["computed"] == 1 and again.summary["reused_evaluations"] >= \
        first.evaluations and again.evaluations == 1 + again.summary["reused_evaluations"]
    assert again.estimates == first.estimates                 # the same path, bit for bit
    assert again.standard_errors == first.standard_errors
    # killed after three runs, its last line torn (what a fit killed in a new folder leaves:
    # its record listed before its first run, then appended to): the rest runs, the same answer
    killed = _killed_record(tmp_path / "killed", "fit_evaluations.jsonl",
                            "\n".join(record[:4]) + "\n" + record[4][:40])
    resumed = sewfmu.fit("punch_drive", data=tmp_path / "trace.csv",
                         free={"punch.b2": "20..300"}, out=killed)
    assert resumed.estimates == first.estimates
    assert resumed.summary["computed"] == first.evaluations - 3   # the optimum among them


@pytest.mark.slow
def test_a_fit_to_other_data_sets_the_old_record_aside(tmp_path):
    _trace(tmp_path / "a.csv", **{"punch.b2": 70.0})
    _trace(tmp_path / "b.csv", **{"punch.b2": 90.0})
    out = tmp_path / "fit"
    sewfmu.fit("punch_drive", data=tmp_path / "a.csv", free={"punch.b2": "20..300"}, out=out)
    b = sewfmu.fit("punch_drive", data=tmp_path / "b.csv", free={"punch.b2": "20..300"}, out=out)
    assert b.estimates["punch.b2"] == pytest.approx(90.0, rel=1e-5)   # not a's runs
    assert (out / "fit_evaluations.previous.jsonl").exists()


def test_setting_aside_never_overwrites(tmp_path):
    (tmp_path / "evaluations.previous.csv").write_text("the user's own file\n")
    for generation in range(3):
        (tmp_path / "evaluations.csv").write_text(f"record {generation}\n")
        set_aside(tmp_path / "evaluations.csv")
    assert (tmp_path / "evaluations.previous.csv").read_text() == "the user's own file\n"
    assert [(tmp_path / f"evaluations.previous-{n}.csv").read_text() for n in (2, 3, 4)] == \
        ["record 0\n", "record 1\n", "record 2\n"]
    assert not (tmp_path / "evaluations.csv").exists()


def test_another_studys_record_is_kept_every_generation(tmp_path):
    for vary in ({"punch.F10": "15..40 N"}, {"punch.b2": "50..90"}, {"punch.F10": "15..40 N"}):
        sewfmu.optimize("punch_drive", vary=vary, minimize="F2_peak", set=SHORT,
                        max_evaluations=2, out=tmp_path)
    kept = sorted(p.name for p in tmp_path.glob("evaluations*.csv"))
    assert kept == ["evaluations.csv", "evaluations.previous-2.csv", "evaluations.previous.csv"]


def _hold(folder: str, ready, release) -> None:
    with held(Path(folder)):
        ready.set()
        release.wait(60)


def test_a_second_study_into_a_folder_in_use_is_refused(tmp_path):
    ctx = multiprocessing.get_context("spawn")
    ready, release = ctx.Event(), ctx.Event()
    other = ctx.Process(target=_hold, args=(str(tmp_path), ready, release))
    other.start()
    try:
        assert ready.wait(60)
        with pytest.raises(OutputError, match="another sewfmu command .a run, sweep or study. is writing"):
            with held(tmp_path):
                pass
        for study in (lambda: sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"},
                                              minimize="F2_peak", set=SHORT, out=tmp_path),
                      lambda: sewfmu.sweep("punch_drive", grid={"punch.F10": [20.0, 30.0]},
                                           set=SHORT, out=tmp_path)):
            with pytest.raises(sewfmu.Error, match="writing into this folder now"):
                study()
        assert not list(tmp_path.iterdir())                 # nothing written by the refused
    finally:
        release.set()
        other.join(60)
    with held(tmp_path):                          # free again once it has ended
        pass


def test_a_killed_holder_frees_the_folder(tmp_path):
    ctx = multiprocessing.get_context("spawn")
    ready, release = ctx.Event(), ctx.Event()
    other = ctx.Process(target=_hold, args=(str(tmp_path), ready, release))
    other.start()
    assert ready.wait(60)
    other.kill()
    other.join(60)
    deadline = time.monotonic() + 30
    while True:                                  # the kernel drops the lock with the process
        try:
            with held(tmp_path):
                break
        except OutputError:
            assert time.monotonic() < deadline
            time.sleep(0.1)


@pytest.mark.parametrize("bounds", [np.array([15.0, 40.0]), [np.float64(15), np.int64(40)],
                                    (np.float32(15), np.float32(40)), ["15 N", "0.04 kN"]])
def test_bounds_as_numpy_and_lists(bounds):
    from sewfmu.scenarios.design import space

    sc = sewfmu.load("punch_drive")
    from sewfmu.api import _design_scenario

    _, _, described = _design_scenario("punch_drive", None)
    (v,) = space.variables(sc, {"punch.F10": bounds}, described)
    assert (v.lo, v.hi, v.unit) == (15.0, 40.0, "N")


@pytest.mark.parametrize("vary, said", [
    ([("punch.F10", 15, 40)], "expected {\"instance.parameter\": (low, high)}"),
    ({"punch.F10": np.array([15.0, 40.0, 50.0])}, "expected (low, high)"),
    ({"punch.F10": np.array([[15.0, 40.0]])}, "expected (low, high)"),
    ({}, "nothing to vary"),
    # a bare number beside one with its unit: ambiguous (docs/scenarios.md, values with units)
    ({"punch.F10": (np.float32(15), "40 N")}, "mixes bare numbers"),
])
def test_a_vary_of_the_wrong_shape_is_one_line(vary, said):
    with pytest.raises(sewfmu.ScenarioError) as err:
        sewfmu.optimize("punch_drive", vary=vary, minimize="F2_peak", set=SHORT)
    assert said in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("given", [0, -3, 1.5, True, "10"])
def test_a_budget_that_is_not_a_whole_number_from_1_is_refused_not_defaulted(given, tmp_path):
    for study in (lambda: sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"},
                                          minimize="F2_peak", set=SHORT, max_evaluations=given),
                  lambda: sewfmu.fit("punch_drive", data=_trace_file(tmp_path),
                                     free={"punch.b2": "20..300"}, max_evaluations=given)):
        with pytest.raises(sewfmu.ScenarioError, match="max_evaluations: a whole number >= 1"):
            study()


def test_a_budget_of_one_is_one_evaluation(capsys):
    from sewfmu.cli import main

    found = sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"}, minimize="F2_peak",
                            set=SHORT, max_evaluations=np.int64(1))
    assert len(found.evaluations) == 1 and not found.converged
    with pytest.raises(SystemExit) as exit_:
        main(["optimize", "punch_drive", "--vary", "punch.F10=15..40 N", "--minimize",
              "F2_peak", "--max-evaluations", "0"])
    assert exit_.value.code == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--max-evaluations" in err[0] and ">= 1" in err[0]


def _trace_file(tmp_path: Path) -> Path:
    path = tmp_path / "trace.csv"
    if not path.exists():
        _trace(path)
    return path


class _Terminal:
    """stderr as a terminal: tqdm draws its bar (it stays silent where stderr is a file)."""

    def __init__(self):
        self.text = ""

    def write(self, text):
        self.text += text

    def flush(self):
        pass

    def isatty(self):
        return True


def test_optimize_and_fit_show_their_runs_on_a_terminal(monkeypatch, tmp_path):
    terminal = _Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    # a line appears once the work has taken a second (runs/progress.py); these take less
    monkeypatch.setattr("sewfmu.scenarios.runs.progress.QUIET_FOR", 0.0)
    sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"}, minimize="F2_peak",
                    set=SHORT, max_evaluations=3, progress=True)
    assert "optimize punch_drive" in terminal.text and "/3 [" in terminal.text
    terminal.text = ""
    sewfmu.fit("punch_drive", data=_trace_file(tmp_path), free={"punch.b2": "20..300"},
               max_evaluations=2, progress=True)
    assert "fit punch_drive" in terminal.text and "run" in terminal.text


def test_data_that_carry_nothing_of_a_parameter_give_no_standard_error(tmp_path):
    r = sewfmu.run("punch_drive", set=SHORT)
    zero = {"time": r.series["time"], "punch.F2": np.zeros(len(r.series))}
    fit = sewfmu.fit("punch_drive", data=zero, free={"punch.c2": "2e4..1.5e5 N/m"})
    # the fit runs to the stiffness's lower bound: said, and never an error of exactly 0
    assert fit.standard_errors["punch.c2"] > 0
    assert any("ends at its lower bound 20000 N/m" in w for w in fit.summary["warnings"])


def test_a_parameter_the_residuals_do_not_change_with_has_an_infinite_error():
    from sewfmu.scenarios.design.fit import _identifiability
    from sewfmu.scenarios.design.space import Variable

    free = [Variable("a.x", 0.0, 1.0, "m", 0.5), Variable("a.y", 0.0, 1.0, "m", 0.5)]
    flat = _identifiability(np.array([[1.0, 0.0], [2.0, 0.0]]), free, np.array([0.5, 0.5]))
    assert flat["undetermined"] and "a.y" in flat["warnings"][0]
    together = _identifiability(np.array([[1.0, 2.0], [2.0, 4.0]]), free, np.array([0.5, 0.5]))
    assert together["undetermined"] and "only together" in together["warnings"][0]
    fine = _identifiability(np.array([[1.0, 0.0], [0.0, 1.0]]), free, np.array([0.5, 0.0]))
    assert not fine["undetermined"] and "a.y ends at its lower bound 0 m" in fine["warnings"][0]


@pytest.mark.parametrize("data, said", [
    ({"time": [0.0, 0.01, 0.02], "punch.F2": [0.0, 1.0]}, "differ in length"),
    ({"time": [0.0, 0.01], "punch.F2": [[0.0, 1.0], [1.0, 2.0]]}, "one row of numbers"),
    ({"time": [0.0, 0.01], "punch.F2": [0.0, np.inf]}, "infinite value"),
    ({"time": [0.0, 0.01], "punch.F2": [0.0, 1e308]}, "beyond any measurement"),
    ({"time": 0.0, "punch.F2": 1.0}, "one row of numbers, got shape ()"),
    ("no_such_file.csv", "no such file"),
])
def test_a_table_is_checked_as_a_file_is(data, said):
    with pytest.raises(sewfmu.ScenarioError) as err:
        sewfmu.fit("punch_drive", data=data, free={"punch.c2": "2e4..1.5e5 N/m"})
    assert said in str(err.value) and "\n" not in str(err.value)


def test_numpy_goals_and_a_single_constraint_text():
    found = sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"},
                            target={"F2_weld_mean": np.float32(25)}, set=SHORT,
                            max_evaluations=np.int64(2))
    assert found.summary["target"] == {"F2_weld_mean": 25.0}
    found = sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"}, minimize="F2_peak",
                            constraints="F2_weld_mean>=20 N", set=SHORT, max_evaluations=2)
    assert found.summary["constraints"] == ["F2_weld_mean>=20 N"] or \
        len(found.summary["constraints"]) == 1


def test_a_target_given_twice_is_refused(capsys):
    from sewfmu.cli import main

    assert main(["optimize", "punch_drive", "--vary", "punch.F10=15..40 N", "--target",
                 "F2_weld_mean=25 N", "--target", "F2_weld_mean=24 N"]) == 1
    assert "--target F2_weld_mean: given twice" in capsys.readouterr().err


def _killed_record(folder, name: str, text: str):
    """A folder as a study killed in it leaves it: its record listed in the manifest before
    the first run (outputs.claim), then `text` appended to it as the study appends."""
    from sewfmu.scenarios.files.outputs import Record, claim  # as the study writes it

    folder.mkdir()
    claim(folder, [name])
    with Record(folder / name) as record:
        record.write(text)
    return folder


def test_a_torn_last_line_is_cut_off_before_the_record_goes_on(tmp_path):
    out = tmp_path / "s"
    first = sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"},
                            target={"F2_weld_mean": "25 N"}, set=SHORT, out=out)
    lines = (out / "evaluations.csv").read_text().splitlines(keepends=True)
    out = _killed_record(tmp_path / "killed", "evaluations.csv", "".join(lines[:3]) + lines[3][:25])
    again = sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"},
                            target={"F2_weld_mean": "25 N"}, set=SHORT, out=out)
    assert again.best == first.best
    with open(out / "evaluations.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(first.evaluations) and all(r["status"] == "ok" for r in rows)
    assert [int(r["index"]) for r in rows] == list(range(len(rows)))
