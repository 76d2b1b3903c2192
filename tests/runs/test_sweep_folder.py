"""What an attack on sweeps found (2026-11-29), each refused in one line before the first run,
or counted right: a user's file a sweep would write is refused by the same check its files pass
at the end (never after every point ran); the API's grid given as a generator without end is
refused without being listed; a run's length given twice (one set, one swept) is refused; a
`sewfmu run` into a folder a sweep is writing is refused; the time a sweep announces counts
each point's own steps, and a study scenario's sweep has one. Points are not run (the engine's
_execute is replaced), except where said."""
import math
import multiprocessing
import re
import time
import tracemalloc
from pathlib import Path

import pytest

import sewfmu
from sewfmu.cli import main
from sewfmu.scenarios.files.outputs import held

R = ["--set", "experiment.revolutions=2"]


@pytest.fixture(autouse=True)
def _fmus(fmus_of_this_session):
    pass


@pytest.fixture
def fake_runs(monkeypatch):
    """Every point 'ok' at once, with its values: the sweep's own bookkeeping, no FMU."""
    def rows(scenario, todo, keys, results_dir, workers, scheduler):
        for p in todo:
            yield {"index": p.index, "key": keys[p.index], **dict(p.values), "status": "ok"}

    from sewfmu.scenarios.runs import sweep  # by module: the engine's loop over points

    monkeypatch.setattr(sweep, "_execute", rows)


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


@pytest.mark.parametrize("command", [
    ["sweep", "punch_drive", "--grid", "shaft.omega0=90,100"],
    ["sensitivity", "punch_drive", "--vary", "punch.F10=15..40N", "--figure", "F2_peak",
     "--method", "morris", "--samples", "2"],
])
def test_a_users_table_is_refused_before_the_first_run_and_nothing_is_left(
        command, capsys, tmp_path, no_runs):
    """sweep.csv of the user's beginning "index,": refused at once (it ran every point, then
    refused, and left points.jsonl and .sewfmu-outputs beside the user's file)."""
    out = tmp_path / "u1"
    out.mkdir()
    (out / "sweep.csv").write_bytes(b"index,name\n0,alice\n")
    assert main(command + R + ["--out", str(out)]) == 1
    line = _one_line(capsys)
    assert "sweep.csv there is not from sewfmu's last run" in line and "error" in line
    assert sorted(p.name for p in out.iterdir()) == ["sweep.csv"]
    assert (out / "sweep.csv").read_bytes() == b"index,name\n0,alice\n"


def test_a_users_record_is_neither_appended_to_nor_deleted_by_the_next_study(
        capsys, tmp_path, fake_runs):
    """A points.jsonl whose first line is JSON with a "key": the sweep appended to it and listed
    it as its own, and the optimize after it deleted it."""
    out = tmp_path / "up"
    out.mkdir()
    mine = b'{"key":"k1","name":"alice"}\n'
    (out / "points.jsonl").write_bytes(mine)
    assert main(["sweep", "punch_drive", "--grid", "shaft.omega0=90,100", *R, "--out", str(out),
                 "--quiet"]) == 1
    assert "points.jsonl there is not from sewfmu's last run" in _one_line(capsys)
    assert sorted(p.name for p in out.iterdir()) == ["points.jsonl"]
    # a study into the folder after a sweep that did write there: the user's record stays
    other = tmp_path / "other"
    sewfmu.sweep("punch_drive", grid={"shaft.omega0": [90.0, 100.0]}, set={
        "experiment.revolutions": 2}, out=other)
    (other / "points.jsonl").write_bytes(mine)        # the user's now, at a listed name
    from sewfmu.scenarios.files.outputs import replacing  # what the next study's end does

    with replacing(other):
        pass
    assert (other / "points.jsonl").read_bytes() == mine


def test_a_users_results_under_points_and_a_link_for_points_are_refused(
        capsys, tmp_path, fake_runs):
    out = tmp_path / "ur"
    sewfmu.sweep("punch_drive", grid={"shaft.omega0": [90.0, 100.0]},
                 set={"experiment.revolutions": 2}, out=out)
    mine = out / "points" / "shaft.omega0=90" / "results.csv"
    mine.parent.mkdir(parents=True)
    mine.write_bytes(b"my own results\n")
    assert main(["sweep", "punch_drive", "--grid", "shaft.omega0=90,100", "--set",
                 "experiment.revolutions=3", "--out", str(out), "--results", "--quiet"]) == 1
    assert "points/shaft.omega0=90/results.csv there is not from sewfmu" in _one_line(capsys)
    assert mine.read_bytes() == b"my own results\n"
    # points/ a link out of the folder: refused, nothing made where it points
    linked, elsewhere = tmp_path / "u3", tmp_path / "elsewhere"
    linked.mkdir(), elsewhere.mkdir()
    (linked / "points").symlink_to(elsewhere)
    assert main(["sweep", "punch_drive", "--grid", "shaft.omega0=90,100", *R, "--out",
                 str(linked), "--results", "--quiet"]) == 1
    assert "points there is a symbolic link" in _one_line(capsys)
    assert not list(elsewhere.iterdir())


def test_a_generator_without_end_is_refused_without_being_listed(no_runs):
    import itertools

    tracemalloc.start()
    started = time.perf_counter()
    with pytest.raises(sewfmu.ScenarioError, match=r"grid shaft.omega0 gives more than 10,000 "
                                                   r"values .*--max-runs N"):
        sewfmu.sweep("punch_drive", {"shaft.omega0": (float(i) for i in itertools.count(1))})
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert time.perf_counter() - started < 10 and peak < 50e6, peak
    with pytest.raises(sewfmu.ScenarioError, match="gives more than 2 values"):   # 3 of them
        sewfmu.sweep("punch_drive", {"shaft.omega0": (float(w) for w in (90, 100, 110))},
                     max_runs=2)


def test_a_generator_within_the_bound_gives_its_values(fake_runs):
    s = sewfmu.sweep("punch_drive", {"shaft.omega0": (float(w) for w in (90, 100, 110))},
                     set={"experiment.revolutions": 2})
    assert [r["shaft.omega0"] for r in s.rows] == [90.0, 100.0, 110.0]


@pytest.mark.parametrize("argv, said", [
    (["--grid", "experiment.revolutions=2,3", "--set", "experiment.stop_time=0.3"],
     "experiment.revolutions (--grid, grid=) and experiment.stop_time (--set, set=)"),
    (["--grid", "experiment.stop_time=0.2,0.3", "--set", "experiment.revolutions=2"],
     "experiment.revolutions (--set, set=) and experiment.stop_time (--grid, grid=)"),
    (["--grid", "experiment.stop_time=0.2,0.3", "--grid", "experiment.revolutions=2,3"],
     "experiment.revolutions (--grid, grid=) and experiment.stop_time (--grid, grid="),
])
def test_a_runs_length_given_twice_is_refused(argv, said, capsys, tmp_path, no_runs):
    """It ran, exit 0, stop_time ignored without a word."""
    assert main(["sweep", "punch_drive", *argv, "--out", str(tmp_path / "d")]) == 1
    line = _one_line(capsys)
    assert said in line and "exactly one of revolutions and stop_time" in line, line
    assert not (tmp_path / "d").exists()


def test_a_runs_length_given_twice_in_a_sweep_table_the_api_and_a_run(capsys, tmp_path,
                                                                     no_runs):
    text = sewfmu.show("punch_drive")
    for table in ('\n[sweep.grid]\n"experiment.stop_time" = [0.2, 0.3]\n',
                  '\n[[sweep.points]]\n"experiment.stop_time" = 0.2\n'):
        path = tmp_path / "s.toml"
        path.write_text(text + table)
        assert main(["sweep", str(path), *R, "--out", str(tmp_path / "o")]) == 1
        assert "experiment.stop_time (the [sweep] table of" in _one_line(capsys)
    with pytest.raises(sewfmu.ScenarioError, match="exactly one of revolutions and stop_time"):
        sewfmu.sweep("punch_drive", {"experiment.revolutions": [2, 3]},
                      set={"experiment.stop_time": 0.3})
    with pytest.raises(sewfmu.ScenarioError, match="exactly one of revolutions and stop_time"):
        sewfmu.run("punch_drive", set={"experiment.revolutions": 2,
                                       "experiment.stop_time": 0.3})
    assert main(["run", "punch_drive", *R, "--set", "experiment.stop_time=0.3", "--out",
                 str(tmp_path / "r")]) == 1
    assert "exactly one of revolutions and stop_time" in _one_line(capsys)
    assert not (tmp_path / "r").exists() and not (tmp_path / "o").exists()


def _hold(folder: str, ready, release) -> None:
    """A sweep's process: it holds its folder and appends to its record."""
    with held(Path(folder)):
        (Path(folder) / "points.jsonl").write_text('{"key": "a", "status": "ok"}\n')
        ready.set()
        release.wait(60)


def test_a_run_into_a_folder_a_sweep_is_writing_is_refused_at_once(capsys, tmp_path):
    ctx = multiprocessing.get_context("spawn")
    ready, release = ctx.Event(), ctx.Event()
    other = ctx.Process(target=_hold, args=(str(tmp_path), ready, release))
    other.start()
    try:
        assert ready.wait(60)
        started = time.perf_counter()
        assert main(["run", "punch_drive", "--set", "experiment.revolutions=400", "--out",
                     str(tmp_path)]) == 1
        assert time.perf_counter() - started < 5                 # before its first step
        assert "another sewfmu command (a run, sweep or study) is writing" in _one_line(capsys)
        assert (tmp_path / "points.jsonl").read_text() == '{"key": "a", "status": "ok"}\n'
    finally:
        release.set()
        other.join(60)


def _estimated(capsys) -> float:
    line = capsys.readouterr().err.strip().splitlines()[0]
    found = re.search(r"about (\d+) (s|min)", line)
    assert found, line
    return float(found.group(1)) * (60 if found.group(2) == "min" else 1)


def test_the_estimate_counts_each_points_own_steps(capsys, tmp_path, fake_runs):
    """ω = 1 and 1.1 rad/s at 0.05 ms: it said about 1 s (the scenario's 100 rad/s at
    0.25 ms) and took 43 s."""
    from sewfmu.scenarios.runs import budget

    assert main(["sweep", "punch_drive", "--grid", "shaft.omega0=1,1.1", "--grid",
                 "experiment.step=0.05 ms", *R, "--workers", "1", "--out",
                 str(tmp_path / "f")]) == 0
    instances = len(sewfmu.load("punch_drive").instances)
    # two revolutions at ω, no ramp: 4π/ω seconds, in whole steps of at most 0.05 ms
    expected = sum(budget.START_COST + math.ceil(4 * math.pi / w / 5e-5) * instances
                   * budget.STEP_COST for w in (1.0, 1.1))
    assert _estimated(capsys) == pytest.approx(expected, abs=1)
    assert expected > 30


def test_a_study_scenarios_sweep_has_an_estimate(capsys, tmp_path, fake_runs):
    from sewfmu.scenarios.runs.budget import STUDY_SECONDS

    assert main(["sweep", "takeup_tolerance", "--grid", "takeup.L_CD=0.024,0.025", "--workers",
                 "1", "--out", str(tmp_path / "t")]) == 0
    assert _estimated(capsys) == pytest.approx(2 * STUDY_SECONDS["takeup_tolerance"], abs=1)
