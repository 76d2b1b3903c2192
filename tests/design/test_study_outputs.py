"""What an attack on the design studies found (2026-11-29): a file the study cannot write (a full
disk) is named in its one line; a bound just past a range's end is shown with the digits that
tell it from the end, and the range with the brackets its FMU declares, in every message; a
study's record set aside and started again is its own to the next run. No FMU runs: a run's
figures are stood in for where the study needs some."""
import errno
import math

import matplotlib.figure
import pytest

import sewfmu
from sewfmu.cli import main

SHORT = ["--set", "experiment.revolutions=2"]


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


@pytest.fixture
def stand_in(monkeypatch):
    """Each evaluation 'ok' at once, its figures a function of the point."""
    from sewfmu.scenarios.design import evaluations

    def evaluate(scenario, fmu_paths, names, values, figures):
        return "ok", {f: 20.0 + sum(values) / 10 for f in figures}, ""

    monkeypatch.setattr(evaluations, "evaluate_point", evaluate)


def _one_line(capsys) -> str:
    err = [line for line in capsys.readouterr().err.strip().splitlines()
           if not line.startswith("sewfmu: warning")]
    assert len(err) == 1, err
    return err[0]


def test_a_full_disk_names_the_file(capsys, tmp_path, monkeypatch, stand_in):
    """It said "sewfmu: error: No space left on device", naming no file."""
    def full(self, *_, **__):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", full)
    out = tmp_path / "o"
    assert main(["optimize", "punch_drive", "--vary", "punch.F10=15..40N", "--target",
                 "F2_weld_mean=25N", *SHORT, "--max-evaluations", "2", "--out", str(out),
                 "--plot", "--quiet"]) == 1
    line = _one_line(capsys)
    assert line == f"sewfmu: error: optimize: {str(out / 'convergence.png')!r}: No space left " \
                   f"on device", line
    # the record written so far stays, the study's other files were not put in place
    assert sorted(p.name for p in out.iterdir()) == [".sewfmu-outputs", "evaluations.csv"]
    with pytest.raises(sewfmu.OutputError, match=r"convergence.png': No space left on device"):
        sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"}, minimize="F2_peak",
                        set={"experiment.revolutions": 2}, max_evaluations=2, out=out,
                        plot=True)


def test_a_record_that_cannot_be_appended_to_names_itself(tmp_path):
    from sewfmu.scenarios.files.outputs import Record

    class Full:
        def write(self, data):
            raise OSError(errno.ENOSPC, "No space left on device")

    record = Record(tmp_path / "evaluations.csv")
    record.file.close()
    record.file = Full()
    with pytest.raises(OSError) as err:
        record.write("index,status\r\n")
    assert err.value.filename == str(tmp_path / "evaluations.csv")


def test_a_bound_past_the_ranges_end_shows_its_digits_and_the_declared_brackets(capsys,
                                                                                 monkeypatch,
                                                                                 tmp_path):
    """19098.6 rpm is 2000.000715 rad/s: it was refused as "the upper bound 2000 rad/s lies
    outside the range [0, 2000] rad/s" (omega0's range is (0, 2000]). A bound within a rounding
    of the end (19098.593171027446 rpm, 2000.0000000000005 rad/s) is the end since the value
    grammar's attack (docs/scenarios.md: a value at a declared bound)."""
    monkeypatch.chdir(tmp_path)                # the default output folder lies in the cwd
    given = 19098.6
    assert given * 2 * math.pi / 60 > 2000.0                 # just past the end, in rad/s
    said = repr(given * 2 * math.pi / 60)
    assert main(["optimize", "punch_drive", "--vary", f"shaft.omega0=1000..{given} rpm",
                 "--minimize", "F2_peak"]) == 1
    assert f"the upper bound {said} rad/s lies outside the range (0, 2000] rad/s" in \
        _one_line(capsys)
    # the lower end, which the model refuses and the modelDescription's minimum allows: the
    # same brackets
    assert main(["optimize", "punch_drive", "--vary", "shaft.omega0=0..1000 rpm",
                 "--minimize", "F2_peak"]) == 1
    assert "the lower bound 0 rad/s lies outside the range (0, 2000] rad/s" in _one_line(capsys)
    # a bound plainly outside keeps its short form; a closed range its brackets
    assert main(["optimize", "punch_drive", "--vary", "punch.F10=0..20000 N",
                 "--minimize", "F2_peak"]) == 1
    assert "the upper bound 20000 N lies outside the range [0, 10000] N" in _one_line(capsys)


def test_a_record_set_aside_and_started_again_is_the_studys_own(tmp_path, stand_in):
    """Another study's evaluations.csv moved aside: the new record is listed as the study
    starts it, so that the same study killed then is resumed, not refused as the user's."""
    from sewfmu.scenarios.design import evaluations
    from sewfmu.scenarios.files.outputs import refuse_theirs, written_by_last_run

    out = tmp_path / "s"
    sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"}, minimize="F2_peak",
                    set={"experiment.revolutions": 2}, max_evaluations=2, out=out)
    with evaluations.study_folder(out, ["evaluations.csv"], []):
        log = evaluations.EvaluationLog(out / "evaluations.csv", ["punch.F30"], ["F2_peak"])
        log.close()                                # the new record: its header, no run yet
    assert (out / "evaluations.previous.csv").exists()
    refuse_theirs(out, ["evaluations.csv"])
    assert "evaluations.csv" in written_by_last_run(out)
    assert "evaluations.previous.csv" not in written_by_last_run(out)  # kept, not replaced
