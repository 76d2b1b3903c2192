"""A run's files are checked before its first step, by the check they pass as they take their
places (runs/results.outputs_of with files/outputs.refuse_theirs): a user's file of a name the
run would write refuses the run at once (it ran to the end, then refused); and what
outputs_of says a run may write is what it writes, for a [compare] run with every picture and a
study scenario (slow: they draw)."""
import pytest

import sewfmu
from sewfmu.cli import main
from sewfmu.scenarios.files.outputs import written_by_last_run
from sewfmu.scenarios.runs.results import outputs_of


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


def test_a_users_file_refuses_the_run_before_its_first_step(capsys, tmp_path, monkeypatch):
    def ran(*_, **__):
        raise AssertionError("the run was made before the refusal")

    from sewfmu.scenarios.runs import variants  # by module: where a run's variants run

    monkeypatch.setattr(variants, "run", ran)
    for name, argv in (("summary.json", []), ("punch_drive.gif", ["--animate"]),
                       ("report.html", ["--report"])):
        out = tmp_path / name
        out.mkdir()
        (out / name).write_bytes(b"mine")
        assert main(["run", "punch_drive", *argv, "--out", str(out)]) == 1
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"{name} there is not from sewfmu's last run" in err[0], err
        assert (out / name).read_bytes() == b"mine" and len(list(out.iterdir())) == 1
    # a name it would not write (no --report) is no obstacle: the run goes on to its step
    (tmp_path / "free").mkdir()
    (tmp_path / "free" / "report.html").write_bytes(b"mine")
    assert main(["run", "punch_drive", "--out", str(tmp_path / "free")]) == 1
    assert "the run was made" in capsys.readouterr().err


@pytest.mark.slow
def test_what_a_run_may_write_is_what_it_writes(tmp_path):
    sc = sewfmu.load("punch_speed", set={"experiment.revolutions": 1,
                                         "experiment.accept_error": True})
    sewfmu.run(sc, out=tmp_path / "c", plot=True, animate=True, report=True)
    assert sorted(written_by_last_run(tmp_path / "c")) == \
        sorted(outputs_of(sc, plot=True, animate=True, report=True))
    study = sewfmu.load("takeup_tolerance")
    sewfmu.run(study, out=tmp_path / "s", plot=True, report=True)
    assert sorted(written_by_last_run(tmp_path / "s")) == \
        sorted(outputs_of(study, plot=True, report=True))
