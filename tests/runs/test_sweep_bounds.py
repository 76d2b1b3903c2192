"""A sweep's grid from the API and the command line: counted from its axes' lengths before a
point or a list of values is made, refused in one line over the bound on runs (max_runs=,
--max-runs, SEWFMU_MAX_RUNS) without taking memory, said with a time estimate before its first
point; a parameter both fixed (set=, --set) and swept (grid=, --grid, the file's [sweep]) is
refused, not silently overridden; the sweep's own files follow the output folder's one rule."""
import tracemalloc

import numpy as np
import pytest

import sewfmu
from sewfmu.cli import main

SHORT = {"experiment.revolutions": 1}


@pytest.fixture(autouse=True)
def _fmus(fmus_of_this_session):
    pass


def test_a_million_point_grid_is_refused_at_once_without_memory(no_runs):
    axes = {"shaft.omega0": np.linspace(50.0, 300.0, 1000), "punch.F30": range(1000)}
    tracemalloc.start()
    try:
        with pytest.raises(sewfmu.ScenarioError) as refused:
            sewfmu.sweep("punch_drive", grid=axes, workers=1)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    message = str(refused.value)
    assert "sweep punch_drive: 1,000,000 runs (a grid of 1,000 × 1,000)" in message
    assert "more than the 10,000" in message and "max_runs=N" in message and "\n" not in message
    # a million points would be hundreds of MB of Points and scenario copies: none was made
    assert peak < 5 * 2 ** 20, peak


def test_one_long_axis_is_counted_without_a_list_of_it(no_runs):
    values = np.linspace(1.0, 10.0, 10 ** 7)          # 80 MB as an array; ~400 MB as a list
    tracemalloc.start()
    try:
        with pytest.raises(sewfmu.ScenarioError, match=r"10,000,000 runs \(a grid of "
                                                       r"10,000,000\)"):
            sewfmu.sweep("punch_drive", grid={"punch.F30": values})
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 5 * 2 ** 20, peak


def test_the_command_line_refuses_it_in_one_line_naming_the_option(capsys, tmp_path, no_runs):
    many = ",".join(str(v) for v in range(1, 102))
    assert main(["sweep", "punch_drive", "--grid", f"punch.F30={many}", "--grid",
                 f"punch.F10={many}", "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "10,201 runs (a grid of 101 × 101)" in err[0], err
    assert "--max-runs N" in err[0] and not (tmp_path / "out").exists()
    # the option sets the bound: 2 points over a bound of 1, under a bound of 2 (which goes on
    # to its points: the test's stand-in fails there)
    for bound, said in (("1", "2 runs (a grid of 2), about"), ("2", "was made before the refusal")):
        assert main(["sweep", "punch_drive", "--grid", "punch.F30=1,2", "--out",
                     str(tmp_path / "out"), "--max-runs", bound, "--quiet"]) == 1
        assert said in capsys.readouterr().err


def test_the_bound_from_the_argument_and_the_environment(monkeypatch, no_runs):
    with pytest.raises(sewfmu.ScenarioError, match=r"3 runs .* more than the 2 "):
        sewfmu.sweep("punch_drive", grid={"punch.F30": [1.0, 2.0, 3.0]}, max_runs=2)
    monkeypatch.setenv("SEWFMU_MAX_RUNS", "2")
    with pytest.raises(sewfmu.ScenarioError, match=r"3 runs .* more than the 2 "):
        sewfmu.sweep("punch_drive", grid={"punch.F30": [1.0, 2.0, 3.0]})
    with pytest.raises(AssertionError, match="was made before the refusal"):   # the argument wins
        sewfmu.sweep("punch_drive", grid={"punch.F30": [1.0, 2.0, 3.0]}, max_runs=3)


def test_the_count_and_an_estimate_come_before_the_first_point(capsys, monkeypatch):
    said = []

    def first(*_, **__):
        said.append(capsys.readouterr().err)
        raise KeyboardInterrupt

    from sewfmu.scenarios.runs import sweep

    monkeypatch.setattr(sweep, "_execute", first)
    with pytest.raises(KeyboardInterrupt):
        sewfmu.sweep("punch_drive", grid={"punch.F30": [1.0, 2.0]}, set=SHORT, workers=1,
                     progress=True)
    assert len(said) == 1 and said[0].startswith("sewfmu: sweep punch_drive: 2 runs, about "), \
        said


@pytest.mark.parametrize("call, where", [
    (lambda: sewfmu.sweep("punch_drive", grid={"punch.F30": [1.0, 2.0]},
                          set={"punch.F30": 3.0}), "(--grid, grid=)"),
    (lambda: sewfmu.sweep("punch_grid", set={"punch.F30": 3.0}), "the [sweep] table of"),
])
def test_a_parameter_both_fixed_and_swept_is_refused(call, where, no_runs):
    with pytest.raises(sewfmu.ScenarioError, match="punch.F30 is both fixed") as refused:
        call()
    assert where in str(refused.value)


def test_the_command_line_refuses_set_and_grid_of_one_parameter(capsys, tmp_path, no_runs):
    assert main(["sweep", "punch_drive", "--grid", "punch.F30=1,2", "--set", "punch.F30=3",
                 "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "punch.F30 is both fixed (--set, set=) and swept (--grid" in err[0]


def test_a_users_file_where_a_point_keeps_its_results_survives(tmp_path, capsys, no_runs):
    from sewfmu.scenarios.files.outputs import folder_for  # the point's folder, as named
    from sewfmu.scenarios.format.values import label_of

    mine = folder_for(tmp_path / "points", label_of("punch.F30", 1.0)) / "results.csv"
    mine.parent.mkdir(parents=True)
    mine.write_bytes(b"my own results\n")
    assert main(["sweep", "punch_drive", "--grid", "punch.F30=1,2", "--results", "--out",
                 str(tmp_path), "--quiet"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "results.csv there is not from sewfmu's last run" in err[0], err
    assert mine.read_bytes() == b"my own results\n"


@pytest.mark.slow
def test_a_second_sweep_replaces_what_the_first_wrote_and_nothing_else(tmp_path):
    (tmp_path / "notes.txt").write_bytes(b"mine\n")
    grid = {"punch.F30": [1.0, 2.0]}
    sewfmu.sweep("punch_drive", grid=grid, set=SHORT, workers=1, out=tmp_path, plot=True)
    from sewfmu.scenarios.files.outputs import written_by_last_run  # the manifest, as read

    listed = set(written_by_last_run(tmp_path))
    assert listed == {"points.jsonl", "sweep.csv", "punch_drive_sweep.png"}
    sewfmu.sweep("punch_drive", grid=grid, set=SHORT, workers=1, out=tmp_path)   # resumed
    assert sorted(p.name for p in tmp_path.iterdir()) == [".sewfmu-outputs", "notes.txt",
                                                          "points.jsonl", "sweep.csv"]
    assert (tmp_path / "notes.txt").read_bytes() == b"mine\n"
