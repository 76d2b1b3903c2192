"""A design study's output folder follows the one rule of files/outputs.py, as a run's and a
sweep's do: a file of a name the study would write that sewfmu did not write there (the folder's
manifest does not list it) survives byte for byte, and the study is refused in one line before
its first run; a second study into its own folder replaces what the first wrote and nothing
else. The refused studies are checked to make no run: every way a study runs a point is made to
fail the test if it is reached."""
import json

import pytest

import sewfmu
from sewfmu.cli import main

SHORT = {"experiment.revolutions": 1}
MANIFEST = ".sewfmu-outputs"


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


@pytest.fixture
def no_runs(monkeypatch):
    """A study that reaches a run fails the test: the local optimizer's evaluations, a fit's
    runs, a sweep's points (sensitivity's samples run as one)."""
    def ran(*_, **__):
        raise AssertionError("a run was made before the refusal")

    # by module (sewfmu.scenarios, as a dotted name, is the function of the catalogue)
    from sewfmu.scenarios.design import evaluations, fit
    from sewfmu.scenarios.runs import sweep

    monkeypatch.setattr(evaluations, "evaluate_point", ran)
    monkeypatch.setattr(fit, "run", ran)
    monkeypatch.setattr(sweep, "_execute", ran)


def _data(folder) -> str:
    path = folder / "data.csv"
    path.write_text("time,punch.F2\n0.0,0.0\n0.01,1.0\n")
    return str(path)


def _argv(study: str, out, data: str) -> list[str]:
    return {
        "optimize": ["optimize", "punch_drive", "--vary", "punch.F10=15..40 N", "--minimize",
                     "F2_peak", "--plot"],
        "fit": ["fit", "punch_drive", "--data", data, "--free", "punch.c2=2e4..1.5e5"],
        "sensitivity": ["sensitivity", "punch_drive", "--vary", "punch.F10=15..40",
                        "--figure", "F2_peak", "--method", "morris", "--samples", "2"],
        "sweep": ["sweep", "punch_drive", "--grid", "punch.F30=1,2", "--plot", "--report"],
    }[study] + ["--set", "experiment.revolutions=1", "--out", str(out), "--quiet"]


# each file a study writes, the user's own of that name in the folder beforehand
THEIRS = [("optimize", "optimize.json"), ("optimize", "convergence.png"),
          ("optimize", "evaluations.csv"),
          ("fit", "fit.json"), ("fit", "fit.png"), ("fit", "fit_evaluations.jsonl"),
          ("sensitivity", "sensitivity.json"), ("sensitivity", "sensitivity_F2_peak.png"),
          ("sweep", "punch_drive_sweep.png"), ("sweep", "report.html")]


@pytest.mark.parametrize("study, name", THEIRS)
def test_a_users_file_survives_a_study_and_the_study_is_refused_in_one_line(
        study, name, tmp_path, capsys, no_runs):
    out = tmp_path / "D"
    out.mkdir()
    mine = f"the user's own {name}, not sewfmu's\n".encode() + bytes(range(256))
    (out / name).write_bytes(mine)
    assert main(_argv(study, out, _data(tmp_path))) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("sewfmu: error: output folder"), err
    assert f"{name} there is not from sewfmu's last run" in err[0], err
    assert (out / name).read_bytes() == mine
    assert sorted(p.name for p in out.iterdir()) == [name]     # nothing else written either


@pytest.mark.parametrize("call", ["optimize", "fit", "sensitivity", "sweep"])
def test_the_api_refuses_as_the_command_line_does(call, tmp_path, no_runs):
    out = tmp_path / "D"
    out.mkdir()
    name = {"optimize": "convergence.png", "fit": "fit.png",
            "sensitivity": "sensitivity.json", "sweep": "report.html"}[call]
    (out / name).write_bytes(b"mine")
    studies = {
        "optimize": lambda: sewfmu.optimize("punch_drive", vary={"punch.F10": (15.0, 40.0)},
                                            minimize="F2_peak", set=SHORT, out=out, plot=True),
        "fit": lambda: sewfmu.fit("punch_drive", data=_data(tmp_path),
                                  free={"punch.c2": (2e4, 1.5e5)}, out=out),
        "sensitivity": lambda: sewfmu.sensitivity("punch_drive", vary={"punch.F10": (15, 40)},
                                                  figures=["F2_peak"], method="morris",
                                                  samples=2, set=SHORT, out=out),
        "sweep": lambda: sewfmu.sweep("punch_drive", grid={"punch.F30": [1.0, 2.0]}, set=SHORT,
                                      out=out, report=True),
    }
    with pytest.raises(sewfmu.OutputError, match=f"{name} there is not from sewfmu's last run"):
        studies[call]()
    assert (out / name).read_bytes() == b"mine"


def _manifest(folder) -> set[str]:
    from sewfmu.scenarios.files.outputs import written_by_last_run  # the manifest, as read

    return set(written_by_last_run(folder))


def test_a_second_study_replaces_what_the_first_wrote_and_nothing_else(tmp_path):
    out = tmp_path / "D"
    out.mkdir()
    (out / "notes.txt").write_bytes(b"mine\n")
    vary, goal = {"punch.F10": "15..40 N"}, {"minimize": "F2_peak"}
    first = sewfmu.optimize("punch_drive", vary=vary, **goal, set=SHORT, max_evaluations=2,
                            out=out, plot=True)
    assert _manifest(out) == {"evaluations.csv", "optimize.json", "convergence.png"}
    assert json.loads((out / "optimize.json").read_text())["best"] == first.best
    # the same study again, without its picture: it finds its runs in its record (none made),
    # rewrites its summary and removes the picture the first wrote, not the user's file
    again = sewfmu.optimize("punch_drive", vary=vary, **goal, set=SHORT, max_evaluations=2,
                            out=out)
    assert again.computed == 0 and again.best == first.best
    assert _manifest(out) == {"evaluations.csv", "optimize.json"}
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "evaluations.csv", "notes.txt",
                                                     "optimize.json"]
    assert (out / "notes.txt").read_bytes() == b"mine\n"


@pytest.mark.slow
def test_a_killed_studys_record_is_its_own_to_the_next(tmp_path, monkeypatch):
    """The record is listed before the first run: a study stopped after it began leaves a record
    the next study resumes from, not one it refuses as the user's."""
    out = tmp_path / "D"
    calls = []

    def stopped(*args, **kwargs):
        if calls:
            raise KeyboardInterrupt
        calls.append(args)
        return original(*args, **kwargs)

    from sewfmu.scenarios.design import evaluations
    original = evaluations.evaluate_point
    monkeypatch.setattr(evaluations, "evaluate_point", stopped)
    with pytest.raises(KeyboardInterrupt):
        sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"}, minimize="F2_peak",
                        set=SHORT, max_evaluations=3, out=out)
    assert _manifest(out) == {"evaluations.csv"}
    assert len((out / "evaluations.csv").read_text().splitlines()) == 2     # header, one run
    monkeypatch.setattr(evaluations, "evaluate_point", original)
    resumed = sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"},
                              minimize="F2_peak", set=SHORT, max_evaluations=3, out=out)
    assert resumed.computed == len(resumed.evaluations) - 1
