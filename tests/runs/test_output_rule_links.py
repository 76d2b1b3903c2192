"""The output folder's rule after the second attack (files/outputs.py, files/manifest.py,
runs/results.py): OUT/interrupted is a folder inside OUT (never followed as a link), the lock of
a folder does not depend on TMPDIR, debris is removed only where sewfmu writes, a record the
user appended to is the user's, an old manifest of names counts only for a command's own
names, and a manifest that is not sewfmu's is refused."""
import os
import subprocess
import sys

import numpy as np
import pytest

from sewfmu.errors import Error
from sewfmu.scenarios.cosim.master import RunResult
from sewfmu.scenarios.files.manifest import MANIFEST
from sewfmu.scenarios.files.outputs import (
    OutputError,
    Record,
    claim,
    held,
    refuse_theirs,
    remove_debris,
    replacing,
)
from sewfmu.scenarios.runs import results
from tests.fake_fmu import fake_scenario


def _other_run(folder):
    """A finished run's files in a folder outside OUT, with their manifest."""
    record = RunResult(fake_scenario({}, [], 1.0, 0.1), np.linspace(0, 1, 5),
                       {"a.x": np.arange(5.0)}, 0.0, units={"a.x": "m"})
    results.keep_unfinished(record, "interrupted", folder)
    return sorted(p.name for p in (folder / "interrupted").iterdir())


def test_a_link_named_interrupted_is_never_followed(tmp_path):
    other = tmp_path / "other"
    other.mkdir()
    files = _other_run(other)                  # sewfmu's own files, manifest and all
    assert MANIFEST in files and "results.csv" in files
    out = tmp_path / "i1"
    out.mkdir()
    os.symlink(other / "interrupted", out / "interrupted")
    results.forget_unfinished(out)             # a finished run into i1: nothing removed
    assert sorted(p.name for p in (other / "interrupted").iterdir()) == files
    record = RunResult(fake_scenario({}, [], 1.0, 0.1), np.linspace(0, 2, 5),
                       {"a.x": np.arange(5.0) + 7}, 0.0, units={"a.x": "m"})
    before = (other / "interrupted" / "results.csv").read_bytes()
    with pytest.raises(Error, match="interrupted: is a symbolic link"):
        results.keep_unfinished(record, "interrupted", out)    # a Ctrl-C run into i1
    assert (other / "interrupted" / "results.csv").read_bytes() == before
    assert os.path.islink(out / "interrupted")


def test_the_folders_lock_holds_whatever_tmpdir_says(tmp_path):
    """A second command with another TMPDIR is refused while the first holds the folder, and
    the folder it made is not left behind empty."""
    out = tmp_path / "new" / "k1"
    child = ("import sys; from pathlib import Path; from sewfmu.errors import Error\n"
             "from sewfmu.scenarios.files.outputs import held\n"
             "try:\n    with held(Path(sys.argv[1])): print('held')\n"
             "except Error as err: print(err)\n")
    other_tmp = tmp_path / "other_tmp"
    other_tmp.mkdir()
    with held(out):
        assert out.is_dir()
        said = subprocess.run([sys.executable, "-c", child, str(out)], capture_output=True,
                              text=True, env={**os.environ, "TMPDIR": str(other_tmp)},
                              timeout=60).stdout
        assert "another sewfmu command" in said, said
    assert not (tmp_path / "new").exists()
    said = subprocess.run([sys.executable, "-c", child, str(out)], capture_output=True,
                          text=True, timeout=60).stdout
    assert said.strip() == "held"


def test_debris_is_removed_only_where_sewfmu_writes_and_of_its_own_kind(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    pid = int(dead.stdout)
    out = tmp_path / "d1"
    drafts = out / "mywork" / f".drafts.sewfmu-{pid}.partial"    # the user's, in the user's
    drafts.mkdir(parents=True)
    (drafts / "chapter.txt").write_text("mine")
    theirs = out / f".x.sewfmu-{pid}.tmp"                         # not a name sewfmu writes
    theirs.write_text("mine")
    staging = out / f".outputs.sewfmu-{pid}.partial"              # sewfmu's staging
    (staging / "deep").mkdir(parents=True)
    pending = out / f".point-k.results.csv.sewfmu-{pid}.tmp"      # a sweep point's
    pending.write_text("1,2\n")
    torn = out / f".{MANIFEST}.sewfmu-{pid}.tmp"
    torn.write_text("{}")
    removed = remove_debris(out, recursive=True)
    assert sorted(removed) == sorted([staging, pending, torn])
    assert (drafts / "chapter.txt").read_text() == "mine" and theirs.read_text() == "mine"


def test_debris_in_a_folder_sewfmu_made_is_removed(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    pid = int(dead.stdout)
    with replacing(tmp_path) as staging:
        (staging / "v1").mkdir()
        (staging / "v1" / "results.csv").write_text("1\n")
    left = tmp_path / "v1" / f".results.csv.sewfmu-{pid}.tmp"
    left.write_text("1")
    assert remove_debris(tmp_path, recursive=True) == [left]
    assert remove_debris(tmp_path) == []


def test_a_finished_record_the_user_appended_to_is_the_users(tmp_path):
    claim(tmp_path, ["points.jsonl"])
    with Record(tmp_path / "points.jsonl") as record:
        record.write('{"key": "a", "status": "ok"}\n')
        record.write('{"key": "b", "status": "ok"}\n')
    with replacing(tmp_path, kept=["points.jsonl"]) as staging:     # the sweep's end
        (staging / "sweep.csv").write_text("index\n0\n1\n")
    refuse_theirs(tmp_path, ["points.jsonl"])          # as the sweep left it: sewfmu's
    with open(tmp_path / "points.jsonl", "a") as f:
        f.write("# my note\n")
    with pytest.raises(OutputError, match="points.jsonl there is not from sewfmu"):
        refuse_theirs(tmp_path, ["points.jsonl"])
    with replacing(tmp_path) as staging:                # a run into the folder after it
        (staging / "results.csv").write_text("1\n")
    assert (tmp_path / "points.jsonl").read_text().endswith("# my note\n")
    assert not (tmp_path / "sweep.csv").exists()


def test_an_old_manifests_bare_name_removes_only_a_file_the_command_writes(tmp_path):
    (tmp_path / "notes.csv").write_text("thesis")
    (tmp_path / "results.csv").write_text("old run")
    (tmp_path / MANIFEST).write_text("notes.csv\nresults.csv\n")
    past = os.stat(tmp_path / MANIFEST).st_mtime_ns - 10**9
    for name in ("notes.csv", "results.csv"):
        os.utime(tmp_path / name, ns=(past, past))
    with replacing(tmp_path) as staging:
        (staging / "results.csv").write_text("new run")
        (staging / "summary.json").write_text("{}")
    assert (tmp_path / "notes.csv").read_text() == "thesis"
    assert (tmp_path / "results.csv").read_text() == "new run"
    assert "notes.csv" not in (tmp_path / MANIFEST).read_text()


@pytest.mark.parametrize("make, what", [
    (lambda p: os.symlink("../x", p), "is a symbolic link"),
    (lambda p: p.write_text("thesis\nchapter one\n"), "is a file that is not sewfmu's"),
    (lambda p: p.mkdir(), "is a folder"),
])
def test_a_manifest_that_is_not_sewfmus_is_refused_before_anything_is_written(tmp_path, make,
                                                                              what):
    make(tmp_path / MANIFEST)
    before = sorted(os.listdir(tmp_path))
    with pytest.raises(OutputError, match=f"{MANIFEST} there {what}"):
        refuse_theirs(tmp_path, ["results.csv"])
    with pytest.raises(OutputError, match=f"{MANIFEST} there {what}"):
        with replacing(tmp_path) as staging:
            (staging / "results.csv").write_text("1\n")
    assert sorted(os.listdir(tmp_path)) == before
    if what == "is a file that is not sewfmu's":
        assert (tmp_path / MANIFEST).read_text() == "thesis\nchapter one\n"


def test_a_run_into_a_folder_with_a_foreign_manifest_is_refused_before_it_starts(tmp_path):
    (tmp_path / MANIFEST).write_text("my notes\n")
    proc = subprocess.run([sys.executable, "-m", "sewfmu", "run", "punch_drive", "--set",
                           "experiment.revolutions=1", "--out", str(tmp_path)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0 and "Traceback" not in proc.stderr
    assert f"{MANIFEST} there is a file that is not sewfmu's" in proc.stderr, proc.stderr
    assert sorted(os.listdir(tmp_path)) == [MANIFEST]
