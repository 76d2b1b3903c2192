"""The output folder's one rule (scenarios/files/outputs.py, files/manifest.py), on the functions
every command writes through, no FMU run: a file is sewfmu's only where the manifest lists it and
it still is as sewfmu left it; a file the user replaced, edited or put at such a name, a folder
the user made, anything through a symbolic link inside the folder, is never replaced or removed;
what the file system refuses while writing names the file. In milliseconds."""
import errno
import json
import os
import shutil
from pathlib import Path

import pytest

from sewfmu.scenarios.files import manifest
from sewfmu.scenarios.files.outputs import (
    MANIFEST,
    OutputError,
    Placing,
    Record,
    claim,
    refuse_theirs,
    replacing,
    write_atomic,
    written_by_last_run,
)


def _write(folder: Path, files: dict[str, bytes], kept=()) -> None:
    """One command's files, as a run writes them (staged, then in place)."""
    with replacing(folder, kept=kept) as staging:
        for name, data in files.items():
            (staging / name).parent.mkdir(parents=True, exist_ok=True)
            (staging / name).write_bytes(data)


def _tree(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and not p.is_symlink()}


def test_a_listed_file_the_user_replaced_is_theirs_even_of_the_same_size(tmp_path):
    _write(tmp_path, {"sweep.csv": b"index,F2\n0,24.5\n"})
    assert written_by_last_run(tmp_path) == ["sweep.csv"]
    (tmp_path / "sweep.csv").write_bytes(b"index,my\n0,notes\n")     # 17 bytes, as before
    assert written_by_last_run(tmp_path) == []
    with pytest.raises(OutputError, match="sweep.csv there is not from sewfmu's last run"):
        _write(tmp_path, {"sweep.csv": b"index,F2\n0,25.0\n"})
    _write(tmp_path, {"other.csv": b"x"})            # nor removed as the last command's file
    assert (tmp_path / "sweep.csv").read_bytes() == b"index,my\n0,notes\n"


def test_a_listed_file_copied_back_unchanged_is_still_sewfmus(tmp_path):
    """Its content decides, not its inode: a copy of what sewfmu wrote (a backup restored)."""
    _write(tmp_path, {"summary.json": b'{"F2": 24.5}\n'})
    shutil.copy(tmp_path / "summary.json", tmp_path / "copy")
    os.replace(tmp_path / "copy", tmp_path / "summary.json")
    assert written_by_last_run(tmp_path) == ["summary.json"]
    _write(tmp_path, {"summary.json": b'{"F2": 25.0}\n'})
    assert (tmp_path / "summary.json").read_bytes() == b'{"F2": 25.0}\n'


def test_a_users_empty_folder_stays_and_the_folders_sewfmu_made_go(tmp_path):
    (tmp_path / "points").mkdir()                                    # the user's
    _write(tmp_path, {"points/a/results.csv": b"1", "sweep.csv": b"2"})
    _write(tmp_path, {"sweep.csv": b"3"})          # without the points' results
    assert (tmp_path / "points").is_dir() and not (tmp_path / "points" / "a").exists()
    # a folder sewfmu made and the user put a file in stays, with the file
    _write(tmp_path, {"points/b/results.csv": b"1"})
    (tmp_path / "points" / "b" / "mine.txt").write_bytes(b"mine")
    _write(tmp_path, {})
    assert _tree(tmp_path / "points") == {"b/mine.txt": b"mine"}


def test_nothing_is_written_through_a_link_inside_the_folder(tmp_path):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    out.mkdir(), elsewhere.mkdir()
    (out / "points").symlink_to(elsewhere)
    with pytest.raises(OutputError, match="points there is a symbolic link"):
        refuse_theirs(out, ["points/a/results.csv"])
    with pytest.raises(OutputError, match="points there is a symbolic link"):
        _write(out, {"points/a/results.csv": b"1"})
    pending = out / ".pending"
    pending.write_bytes(b"1")
    with pytest.raises(OutputError, match="points there is a symbolic link"):
        Placing(out).place(pending, "points/a/results.csv")
    assert not list(elsewhere.iterdir()) and not pending.exists()
    # a file where a folder would go: refused as well, the file left alone
    (out / "sub").write_bytes(b"mine")
    with pytest.raises(OutputError, match="sub there is a file where sewfmu would make a folder"):
        _write(out, {"sub/results.csv": b"1"})
    # a link at a listed name is not followed either: its target stays
    _write(out, {"summary.json": b"{}"})
    (elsewhere / "target").write_bytes(b"mine")
    os.unlink(out / "summary.json")
    (out / "summary.json").symlink_to(elsewhere / "target")
    with pytest.raises(OutputError, match="summary.json there is a symbolic link"):
        _write(out, {"summary.json": b"{}"})
    assert (elsewhere / "target").read_bytes() == b"mine"


def test_nothing_is_removed_through_a_link_swapped_in_for_a_folder_sewfmu_made(tmp_path):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    _write(out, {"points/a/results.csv": b"sewfmu's"})
    (elsewhere / "a").mkdir(parents=True)
    (elsewhere / "a" / "results.csv").write_bytes(b"mine")
    shutil.rmtree(out / "points")
    (out / "points").symlink_to(elsewhere)
    _write(out, {"sweep.csv": b"1"})               # the listed results.csv would go
    assert (elsewhere / "a" / "results.csv").read_bytes() == b"mine"
    assert (out / "points").is_symlink()


def test_a_record_is_sewfmus_while_it_begins_as_recorded(tmp_path):
    """A record is appended run by run: listed before its first line, it stays sewfmu's as it
    grows (a study killed half-way is resumed), not once its beginning changed or the file
    was replaced by another."""
    claim(tmp_path, ["points.jsonl"])
    with Record(tmp_path / "points.jsonl") as record:          # as a sweep appends its rows
        record.write('{"key": "a", "status": "ok"}\n')
        record.write('{"key": "b", "sta')                      # killed mid-line
    refuse_theirs(tmp_path, ["points.jsonl"])
    claim(tmp_path, ["points.jsonl"])             # the next command: the torn line cut off
    assert (tmp_path / "points.jsonl").read_bytes() == b'{"key": "a", "status": "ok"}\n'
    with open(tmp_path / "points.jsonl", "a") as f:
        f.write('{"key": "b", "status": "ok"}\n')
    refuse_theirs(tmp_path, ["points.jsonl"])
    (tmp_path / "points.jsonl").write_bytes(b'{"key": "a", "name": "alice"}\n' * 3)
    with pytest.raises(OutputError, match="points.jsonl there is not from sewfmu"):
        refuse_theirs(tmp_path, ["points.jsonl"])
    # made empty by sewfmu: listed again with its first line, as a command writes it; then
    # replaced by a file of the user's (which may get the same inode): not sewfmu's
    other = tmp_path / "other"
    other.mkdir()
    claim(other, ["evaluations.csv"])
    with Record(other / "evaluations.csv") as record:
        record.write("index,punch.F10,status,error,key\r\n")
    refuse_theirs(other, ["evaluations.csv"])
    os.unlink(other / "evaluations.csv")
    (other / "evaluations.csv").write_bytes(b"index,mine\r\n0,my own notes\r\n")
    with pytest.raises(OutputError, match="evaluations.csv there is not from sewfmu"):
        refuse_theirs(other, ["evaluations.csv"])
    # claimed, and the command killed before its first line: the user's lines written into
    # that empty file are the user's
    third = tmp_path / "third"
    third.mkdir()
    claim(third, ["points.jsonl"])
    (third / "points.jsonl").write_bytes(b'{"key": "k1", "name": "alice"}\n')
    with pytest.raises(OutputError, match="points.jsonl there is not from sewfmu"):
        refuse_theirs(third, ["points.jsonl"])


def test_no_file_is_sewfmus_for_what_it_holds(tmp_path):
    """A points.jsonl whose first line is a JSON object with "key", a sweep.csv that begins
    "index,": not listed, so the user's."""
    (tmp_path / "points.jsonl").write_text('{"key": "k1", "name": "alice"}\n')
    (tmp_path / "sweep.csv").write_text("index,name\n0,alice\n")
    with pytest.raises(OutputError, match="points.jsonl, sweep.csv there are not from"):
        refuse_theirs(tmp_path, ["points.jsonl", "sweep.csv"])


def test_an_old_manifest_of_names_counts_until_the_file_changes(tmp_path):
    """Folders written before the manifest recorded sizes and hashes: a listed name is
    sewfmu's while the file is not newer than the manifest."""
    (tmp_path / "results.csv").write_bytes(b"old run")
    (tmp_path / "notes.csv").write_bytes(b"old run")
    (tmp_path / MANIFEST).write_text("results.csv\nnotes.csv\n")
    later = os.stat(tmp_path / MANIFEST).st_mtime_ns + 10**9
    (tmp_path / "notes.csv").write_bytes(b"the user's now")
    os.utime(tmp_path / "notes.csv", ns=(later, later))
    assert written_by_last_run(tmp_path) == ["results.csv"]
    _write(tmp_path, {"summary.json": b"{}"})
    assert sorted(_tree(tmp_path)) == [MANIFEST, "notes.csv", "summary.json"]


def test_the_manifest_records_size_and_content(tmp_path):
    import hashlib

    _write(tmp_path, {"a/results.csv": b"1,2\n"})
    lines = [json.loads(line) for line in (tmp_path / MANIFEST).read_text().splitlines()]
    assert {"file": "a/results.csv", "size": 4, "sha256": hashlib.sha256(b"1,2\n").hexdigest(),
            "inode": os.stat(tmp_path / "a/results.csv").st_ino,
            "mtime_ns": os.stat(tmp_path / "a/results.csv").st_mtime_ns} in lines
    assert {"folder": "a", "inode": os.stat(tmp_path / "a").st_ino} in lines
    # a damaged manifest reaches nothing outside the folder
    (tmp_path / MANIFEST).write_text('{"file": "../x"}\n../y\n/etc/passwd\n{"file": 3}\n')
    assert manifest.read(tmp_path) == {}


def test_what_the_file_system_refuses_names_the_file(tmp_path):
    def full(f):
        raise OSError(errno.ENOSPC, "No space left on device")      # names no file

    with pytest.raises(OSError) as err:
        write_atomic(tmp_path / "convergence.png", full, binary=True)
    assert err.value.filename == str(tmp_path / "convergence.png") and \
        err.value.errno == errno.ENOSPC
    assert not list(tmp_path.iterdir())                  # no temporary left
    # a writer inside a command's staging that names no file: the output folder is named
    with pytest.raises(OSError) as err:
        with replacing(tmp_path / "out") as staging:
            (staging / "x").write_bytes(b"1")
            raise OSError(errno.ENOSPC, "No space left on device")
    assert err.value.filename == str(tmp_path / "out")
    assert not (tmp_path / "out").exists()               # made by it, and left empty: gone
