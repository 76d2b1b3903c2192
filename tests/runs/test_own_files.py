"""An output folder holding the user's own files: sewfmu replaces only what its last run wrote
there (the folder's manifest), refuses in one line to replace a file of the same name it did not
write, lists as written only its own files, and a sweep neither appends to a points.jsonl nor
rewrites a sweep.csv that is not a sweep's."""
import pytest

import sewfmu
from sewfmu.cli import main

SHORT = {"experiment.revolutions": 1}


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


def test_a_users_file_of_the_same_name_is_not_replaced(tmp_path, capsys):
    (tmp_path / "results.csv").write_text("my own results\n")
    assert main(["run", "punch_drive", "--set", "experiment.revolutions=1", "--out",
                 str(tmp_path)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "results.csv there is not from sewfmu's last run" in err[0]
    assert (tmp_path / "results.csv").read_text() == "my own results\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.csv"]


def test_the_files_line_names_what_sewfmu_wrote_and_a_rerun_replaces_its_own(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("mine\n")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "a.png").write_bytes(b"mine")
    for _ in range(2):                         # the second run replaces the first's files
        assert main(["run", "punch_drive", "--set", "experiment.revolutions=1", "--out",
                     str(tmp_path)]) == 0
        files = [line for line in capsys.readouterr().out.splitlines() if "files:" in line]
        assert files == ["  files: results.csv, summary.json"]
    assert (tmp_path / "notes.txt").read_text() == "mine\n"
    assert (tmp_path / "sub" / "a.png").read_bytes() == b"mine"


@pytest.mark.parametrize("name, text", [("points.jsonl", "my own notes\n"),
                                        ("sweep.csv", "a,b\n1,2\n")])
def test_a_sweep_leaves_a_users_record_or_table_alone(tmp_path, name, text):
    (tmp_path / name).write_text(text)
    with pytest.raises(sewfmu.OutputError, match=f"{name} there is not from sewfmu's last run"):
        sewfmu.sweep("punch_drive", grid={"punch.F30": [1.0, 2.0]}, set=SHORT, out=tmp_path)
    assert (tmp_path / name).read_text() == text


@pytest.mark.slow
def test_a_sweep_lists_its_own_files(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("mine\n")
    assert main(["sweep", "punch_drive", "--grid", "punch.F30=1,2", "--set",
                 "experiment.revolutions=1", "--plot", "--out", str(tmp_path), "--quiet"]) == 0
    files = [line for line in capsys.readouterr().out.splitlines() if "files:" in line]
    assert files == ["  files: sweep.csv, points.jsonl, punch_drive_sweep.png"]


def test_plot_without_an_analysis_says_there_is_nothing_to_draw(tmp_path):
    sc = sewfmu.load("punch_drive", set=SHORT)
    sc.analysis, sc.roles = None, {}
    with pytest.warns(UserWarning, match="--plot: punch_drive has no analysis"):
        sewfmu.run(sc, out=tmp_path, plot=True)
    assert (tmp_path / "results.csv").exists() and not list(tmp_path.glob("*.png"))


@pytest.mark.slow
def test_ctrl_c_to_a_sweeps_process_group_prints_one_line_and_no_worker_traceback(tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    sewfmu_command = str(Path(sys.executable).with_name("sewfmu"))
    proc = subprocess.Popen([sewfmu_command, "sweep", "punch_drive", "--grid",
                             "punch.F30=1,2,3,4", "--set", "experiment.revolutions=3",
                             "--workers", "2", "--out", str(tmp_path), "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    deadline = time.monotonic() + 120          # until the workers run points
    while not (tmp_path / "points.jsonl").exists() and time.monotonic() < deadline \
            and proc.poll() is None:
        time.sleep(0.1)
    os.killpg(proc.pid, signal.SIGINT)         # as a terminal sends Ctrl-C: to every process
    _, err = proc.communicate(timeout=120)
    assert proc.returncode in (0, 130)
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err


def test_a_sweep_plot_without_an_analysis_says_there_is_nothing_to_draw(tmp_path, capsys):
    sc = sewfmu.load("punch_drive", set=SHORT)
    sc.analysis, sc.roles = None, {}
    sewfmu.sweep(sc, grid={"punch.F30": [1.0, 2.0]}, out=tmp_path, plot=True, workers=1)
    assert "the sweep's plot is left out: punch_drive has no analysis" in capsys.readouterr().err
    assert not list(tmp_path.glob("*.png"))
