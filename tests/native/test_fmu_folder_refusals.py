"""An FMU folder that cannot take a rebuilt FMU (full, read-only): one line naming that folder
and what failed, never the builder's temporary file, and no staged `.NAME.fmu.PID` left behind;
the staged files and the builders' scratch folders a killed builder left are removed by the next
build (attack46b, failure 3). Python and native builders alike (fmu_build/install.py)."""
from __future__ import annotations

import errno
import os
import subprocess
import sys

import pytest

from sewfmu.errors import Error
from sewfmu.scenarios.fmu_build import install

READ_ONLY = ("{dest} is read-only: the FMUs there are out of date and cannot be rebuilt; set "
             "SEWFMU_FMU_DIR to a writable folder or rebuild them with sewfmu build --native")


def _dead_pid() -> int:
    done = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    return int(done.stdout)


def _failing_copy(monkeypatch, code: int):
    """copy2 that writes part of the file, then fails as a full or read-only disk does."""
    def copy(src, dst):
        with open(dst, "wb") as out:
            out.write(b"PK partial")
        raise OSError(code, os.strerror(code), str(src))
    monkeypatch.setattr(install.shutil, "copy2", copy)


@pytest.mark.parametrize("code, line", [
    (errno.ENOSPC, "cannot write the rebuilt FMU into {dest}: No space left on device"),
    (errno.EROFS, READ_ONLY)])
def test_a_failed_write_is_one_line_naming_the_folder_and_leaves_nothing(tmp_path, monkeypatch,
                                                                         code, line):
    built = tmp_path / "scratch" / "MainShaft.fmu"
    built.parent.mkdir()
    built.write_bytes(b"PK whole fmu")
    dest = tmp_path / "fmus"
    dest.mkdir()
    _failing_copy(monkeypatch, code)
    with pytest.raises(Error) as err:
        install.install(built, dest, "MainShaft", "sewfmu build --native")
    assert str(err.value) == line.format(dest=dest)
    assert str(built) not in str(err.value)
    assert os.listdir(dest) == []


def test_a_folder_that_cannot_be_made_is_refused_before_a_build(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(Error, match="cannot write the rebuilt FMU into .*file/native"):
        install.writable(blocker / "native", "sewfmu build --native")


def test_a_dead_builders_staged_files_go_and_a_users_stay(tmp_path):
    dead, dest = _dead_pid(), tmp_path / "fmus"
    dest.mkdir()
    built = tmp_path / "MainShaft.fmu"
    built.write_bytes(b"PK whole fmu")
    theirs = [dest / f".PunchLinkage.fmu.{dead}", dest / f".MainShaft.fmu.{dead}"]
    mine = [dest / f".X.fmu.{dead}", dest / f".PunchLinkage.fmu.{os.getppid()}",
            dest / "notes.txt"]
    for path in theirs + mine:
        path.write_bytes(b"partial")
    install.install(built, dest, "MainShaft", "sewfmu build")
    assert sorted(os.listdir(dest)) == sorted(["MainShaft.fmu", *(p.name for p in mine)])
    assert (dest / "MainShaft.fmu").read_bytes() == b"PK whole fmu"


def test_a_killed_builders_scratch_folders_go(tmp_path, monkeypatch):
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    monkeypatch.setattr(install.tempfile, "tempdir", str(tmpdir))
    monkeypatch.setattr(install, "_SWEPT", set())
    dead = _dead_pid()
    gone = [tmpdir / f"sewfmu_native_{dead}_abc1", tmpdir / f"sewfmu_build_{dead}_x_y"]
    kept = [tmpdir / f"sewfmu_native_{os.getppid()}_abc1", tmpdir / "sewfmu_native_mine"]
    for folder in gone + kept:
        (folder / "sources").mkdir(parents=True)
    with install.scratch_folder("native") as tmp:
        assert os.path.basename(tmp).startswith(f"sewfmu_native_{os.getpid()}_")
    assert sorted(os.listdir(tmpdir)) == sorted(p.name for p in kept)


@pytest.mark.slow
def test_a_runs_native_rebuild_into_a_full_folder_is_that_one_line(native_fmu, tmp_path,
                                                                   monkeypatch):
    from sewfmu.scenarios.fmu_build.up_to_date import ensure_built  # the run's way to build

    python_dir = native_fmu("MainShaft", 2).parent.parent / "python2"
    dest = tmp_path / "native"
    _failing_copy(monkeypatch, errno.ENOSPC)
    with pytest.raises(Error) as err:
        ensure_built(["MainShaft"], dest, kind="native", python_dir=python_dir)
    assert str(err.value) == f"cannot write the rebuilt FMU into {dest}: No space left on device"
    assert os.listdir(dest) == []
