"""Accuracy as an output: each run's estimated coupling error on its key figures (runs/accuracy.py)
against the error it really has, measured against the independent solution of
tests/independent/ (which shares no code with sewfmu); a run beyond experiment.accuracy fails
in one line unless accepted."""
import json

import pytest

import sewfmu
from sewfmu.cli import main
from tests.paths import INDEPENDENT

STORED = json.loads((INDEPENDENT / "figures.json").read_text())
PUNCH = ("contact_onset_deg", "contact_loss_deg", "contact_duration_deg", "F2_peak",
         "F2_weld_mean")


# how far above the true error the ± may lie: at the catalogue's step within 5 times where the
# error follows the step (onset, duration: measured 2.0 and 2.9), further where the error of this
# one step happens to be small against its envelope (the loss's 0.005° where 0.0093° at twice the
# step; F2_peak's ± is F2_weld_mean's relative to the figure); at 1 ms the run is refused (its ±
# beyond 5 %), the bound still holds (docs/running.md, "How far above")
LOOSEST = {2.5e-4: {"contact_onset_deg": 5, "contact_loss_deg": 60, "contact_duration_deg": 5,
                    "F2_peak": 60, "F2_weld_mean": 15},
           1e-3: dict.fromkeys(PUNCH, 250)}


@pytest.mark.parametrize("step", [2.5e-4, 1e-3])
def test_the_estimate_covers_the_true_coupling_error_of_every_figure(step):
    run = sewfmu.run("punch_drive", set={"experiment.step": step, "experiment.accept_error": True})
    estimate = run.summary["coupling_error"]["figures"]
    exact = STORED["scenarios"]["punch_drive"]["figures"]
    for name in PUNCH:
        error = abs(run.summary[name] - exact[name]["value"])
        assert error <= estimate[name], (name, error, estimate[name])
        # and not so cautious that it says nothing
        assert estimate[name] <= LOOSEST[step][name] * error, (name, error, estimate[name])


def test_a_step_just_below_the_stability_limit_fails_in_one_line(tmp_path, capsys):
    """punch_split with Jacobi at 1.4 ms: F2_weld_mean 35.9 N against 22.8 N, stable but wrong.
    The run at twice the step diverges: no estimate, the run fails; accepted, it succeeds."""
    args = ["run", "punch_split", "--set", "experiment.master=jacobi", "--set",
            "experiment.step=1.4e-3", "--out", str(tmp_path / "a")]
    assert main(args) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "experiment.accuracy" in err[0] and "accept_error" in err[0]
    assert (tmp_path / "a" / "summary.json").exists()        # what it gave is kept, and said
    assert main(args + ["--set", "experiment.accept_error=true"]) == 0
    with pytest.raises(sewfmu.InaccurateRun) as caught:
        sewfmu.run("punch_split", set={"experiment.master": "jacobi", "experiment.step": 1.4e-3})
    assert caught.value.run.figures["F2_weld_mean"] > 30.0


def test_a_tighter_accuracy_is_a_setting_of_the_experiment():
    with pytest.raises(sewfmu.InaccurateRun, match="F2_weld_mean"):
        sewfmu.run("punch_drive", set={"experiment.step": 1e-3, "experiment.accuracy": 1e-5})
    with pytest.raises(sewfmu.ScenarioError, match="accept_error"):
        sewfmu.load("punch_drive", set={"experiment.accept_error": "yes"})


def test_the_estimate_switched_off_makes_no_coarser_run(tmp_path, capsys, monkeypatch):
    """experiment.accuracy = "off": the run alone, the same series as with the estimate; the
    summary says why there is none, and nothing but "off" or a positive number is taken."""
    from sewfmu.scenarios.runs import accuracy

    made = []
    monkeypatch.setattr(accuracy, "simulate", lambda *a, **k: made.append(a))
    off = sewfmu.run("punch_drive", set={"experiment.accuracy": "off",
                                         "experiment.revolutions": 1})
    assert made == []
    assert off.summary["coupling_error"] == {"method": None, "figures": {},
                                             "none": 'experiment.accuracy = "off"'}
    assert main(["run", "punch_drive", "--set", "experiment.accuracy=off", "--set",
                 "experiment.revolutions=1", "--out", str(tmp_path / "a")]) == 0
    assert 'experiment.accuracy = "off"' in capsys.readouterr().out
    monkeypatch.undo()
    on = sewfmu.run("punch_drive", set={"experiment.revolutions": 1})
    assert (off.series == on.series).all()
    for bad in (0, -1, "on", True):
        with pytest.raises(sewfmu.ScenarioError, match="experiment.accuracy"):
            sewfmu.load("punch_drive", set={"experiment.accuracy": bad})


def test_a_scenario_files_accuracy_and_accept_error_hold_as_with_set(tmp_path, capsys):
    """[experiment] accuracy and accept_error in a file were ignored (the check was skipped
    with exit 0): the file and --set give the same answer."""
    assert main(["show", "punch_drive"]) == 0
    toml = capsys.readouterr().out.replace("revolutions = 10", "revolutions = 2\naccuracy = 1e-4")
    strict = tmp_path / "strict.toml"
    strict.write_text(toml, encoding="utf-8")
    assert main(["run", str(strict), "--out", str(tmp_path / "a")]) == 1
    from_file = capsys.readouterr().err.strip().splitlines()
    assert main(["run", "punch_drive", "--set", "experiment.revolutions=2", "--set",
                 "experiment.accuracy=1e-4", "--out", str(tmp_path / "b")]) == 1
    from_set = capsys.readouterr().err.strip().splitlines()
    assert len(from_file) == 1 and "beyond experiment.accuracy = 0.0001" in from_file[0]
    assert from_file[0].split(":", 3)[3] == from_set[0].split(":", 3)[3]   # but the name
    accepted = tmp_path / "accepted.toml"
    accepted.write_text(toml.replace("accuracy = 1e-4", "accuracy = 1e-4\naccept_error = true"),
                        encoding="utf-8")
    assert main(["run", str(accepted), "--out", str(tmp_path / "c")]) == 0
    summary = json.loads((tmp_path / "c" / "summary.json").read_text())
    assert summary["provenance"]["experiment"]["accuracy"] == 1e-4
