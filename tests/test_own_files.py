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
    with pytest.raises(sewfmu.OutputError, match=f"{name} there is not a sewfmu sweep's"):
        sewfmu.sweep("punch_drive", grid={"punch.F30": [1.0, 2.0]}, set=SHORT, out=tmp_path)
    assert (tmp_path / name).read_text() == text
