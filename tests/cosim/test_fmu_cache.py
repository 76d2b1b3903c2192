"""The FMU cache (scenarios/cosim/fmu_cache.py, scenarios/files/archives.py): one folder per FMU
content, shared by concurrent runs, its bytecode kept, stale entries removed, and a plain
temporary extraction where there is no cache to write; it owns only what it made, and what it
unpacks is bounded: a user's folder given as SEWFMU_CACHE_DIR keeps every file as it was; zip
bombs in an FMU or an .ssp are refused before a byte is written; runs killed mid-extraction leave
scratch that the next run removes (and a live run's stays); a damaged or changed entry is
extracted again; a relative SEWFMU_CACHE_DIR is the folder the user stood in."""
import hashlib
import os
import re
import signal
import stat
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest

from sewfmu.scenarios.cosim import fmu_cache
from sewfmu.scenarios.cosim.fmi_calls import CosimError
from sewfmu.scenarios.files import archives
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.format.values import ScenarioError
from tests.paths import REPO

OLD = time.time() - 400 * 86400                 # older than any clean-up rule

_RUN = """
import sys
from pathlib import Path
from sewfmu.scenarios.cosim.fmi_calls import LogCollector
from sewfmu.scenarios.cosim.instances import open_instance
inst = open_instance("shaft", Path(sys.argv[1]), LogCollector())
inst.real_out = ["phi"]
inst.prepare(); inst.instantiate(); inst.enter_initialization(1.0); inst.exit_initialization()
inst.do_step(0.0, 0.5); inst.read_outputs(); inst.release()
print(inst.unzip_dir, inst.out_buf[0])
"""

# extracts an FMU and stops for good after its first member, to be killed there
_STOP_MID_EXTRACTION = """
import sys, time
from pathlib import Path
from sewfmu.scenarios.cosim import fmu_cache
from sewfmu.scenarios.files import archives
write = archives._write
def write_then_stop(*args):
    n = write(*args)
    print("mid", flush=True)
    time.sleep(600)
    return n
archives._write = write_then_stop
fmu_cache.extract_cached(Path(sys.argv[1]))
"""


def _started(fmu: Path, cache: Path, **env) -> subprocess.Popen:
    """The FMU run in a process of its own, started and not waited for."""
    return subprocess.Popen([sys.executable, "-c", _RUN, str(fmu)],
                            env=_env(SEWFMU_CACHE_DIR=str(cache), **env),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO)


def _env(**env):
    return {**os.environ, "PYTHONDONTWRITEBYTECODE": "1", **env}


def _run(fmu: Path, cwd: Path = REPO, **env) -> tuple[str, float]:
    """Run the FMU in a process of its own: (its unzip folder, an output after half a second)."""
    done = subprocess.run([sys.executable, "-c", _RUN, str(fmu)], env=_env(**env), cwd=cwd,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-1500:]
    folder, value = done.stdout.split()
    return folder, float(value)


def _stopped_mid_extraction(fmu: Path, **env) -> subprocess.Popen:
    proc = subprocess.Popen([sys.executable, "-c", _STOP_MID_EXTRACTION, str(fmu)],
                            env=_env(**env), cwd=REPO, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    if proc.stdout.readline().strip() != "mid":
        proc.kill()
        pytest.fail(f"the extraction did not start: {proc.communicate(timeout=30)[1][-1500:]}")
    return proc


def _kill(proc: subprocess.Popen) -> None:
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(timeout=30)
    proc.stdout.close()
    proc.stderr.close()


def _snapshot(folder: Path, skip: str | None = None) -> dict:
    """Everything in a folder, byte for byte, with its mode and times, links as links."""
    out = {}
    for path in sorted(folder.rglob("*")):
        rel = path.relative_to(folder)
        if skip and rel.parts[0] == skip:
            continue
        st = path.lstat()
        if stat.S_ISLNK(st.st_mode):
            what = ("link", os.readlink(path))
        elif stat.S_ISDIR(st.st_mode):
            what = ("folder",)
        else:
            what = ("file", hashlib.sha256(path.read_bytes()).hexdigest())
        out[str(rel)] = (*what, st.st_mode, st.st_mtime_ns)
    return out


def _users_folder(base: Path) -> Path:
    """A folder as a user's ~/work looks, with names the old clean-up took for its own, old."""
    home = base / "work"
    (home / "thesis").mkdir(parents=True)
    (home / "thesis" / "chapter1.tex").write_text("\\chapter{Stitches}\n")
    (home / "notes.txt").write_text("do not lose\n")
    (home / "data.bin").write_bytes(os.urandom(4096))
    for k in range(70):                             # beyond the old 64 entries, named as hashes
        folder = home / f"{k:032x}"
        folder.mkdir()
        (folder / "modelDescription.xml").write_text(f"<mine n='{k}'/>")
    (home / ".0123abcd-xyz").mkdir()                # the old scratch folders' look
    (home / ".0123abcd-xyz" / "kept").write_text("mine")
    (home / f".{'a' * 32}.{archives.host()}.sewfmu-999999.partial").mkdir()
    (home / "link").symlink_to(home / "notes.txt")
    for path in [*home.rglob("*"), home]:
        os.utime(path, (OLD, OLD), follow_symlinks=False)
    return home


def _entries(cache: Path) -> list[str]:
    return sorted(p.name for p in (cache / fmu_cache.SUBFOLDER).iterdir())


# --- the cache owns what it made, and nothing else ---------------------------------------------
@pytest.mark.slow
def test_a_users_folder_as_the_cache_keeps_every_file(fmu_dir, tmp_path):
    home = _users_folder(tmp_path)
    before = _snapshot(home)
    for _ in range(2):
        done = subprocess.run([sys.executable, "-m", "sewfmu", "run", "punch_drive", "--out",
                               str(tmp_path / "out")], cwd=tmp_path, capture_output=True,
                              text=True, timeout=300,
                              env=_env(SEWFMU_CACHE_DIR=str(home), SEWFMU_FMU_DIR=str(fmu_dir)))
        assert done.returncode == 0, done.stderr[-1500:]
    assert _snapshot(home, skip=fmu_cache.SUBFOLDER) == before
    assert sorted(p.name for p in home.iterdir()) == sorted([*{k.split("/")[0] for k in before},
                                                             fmu_cache.SUBFOLDER])
    entries = [e for e in _entries(home) if re.fullmatch("[0-9a-f]{32}", e)]
    assert len(entries) == 3 and _entries(home) == sorted([*entries, "CACHEDIR.TAG",
                                                           ".sewfmu-lock", "declared-units"])
    for entry in entries:
        marker = home / fmu_cache.SUBFOLDER / entry / fmu_cache.MARKER
        assert marker.read_text().splitlines()[:2] == [fmu_cache.MAGIC, f"key {entry}"]


def test_only_marked_entries_are_used_or_removed(fmu_paths, tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    monkeypatch.setenv("SEWFMU_CACHE_DIR", str(cache))
    monkeypatch.setattr(fmu_cache, "MAX_ENTRIES", 1)
    ours = cache / fmu_cache.SUBFOLDER
    ours.mkdir(parents=True)
    # where the MainShaft's entry goes: a folder of the user's, without the marker
    squatter = ours / fmu_cache.content_hash(fmu_paths["MainShaft"])
    (squatter / "fmu").mkdir(parents=True)
    (squatter / "fmu" / "modelDescription.xml").write_text("<mine/>")
    # where the PunchLinkage's goes: a link to the user's folder, with a marker that claims it
    target = tmp_path / "elsewhere"
    target.mkdir()
    key = fmu_cache.content_hash(fmu_paths["PunchLinkage"])
    (target / fmu_cache.MARKER).write_text(f"{fmu_cache.MAGIC}\nkey {key}\n")
    (ours / key).symlink_to(target, target_is_directory=True)
    # old folders named as entries: one without a marker, one with another program's
    for name, marker in (("b" * 32, None), ("c" * 32, "someone else's cache\n")):
        (ours / name).mkdir()
        if marker:
            (ours / name / fmu_cache.MARKER).write_text(marker)
        os.utime(ours / name, (OLD, OLD))
    before = _snapshot(cache) | _snapshot(target)
    shaft = fmu_cache.extract_cached(fmu_paths["MainShaft"])
    linkage = fmu_cache.extract_cached(fmu_paths["PunchLinkage"])
    fmu_cache.extract_cached(fmu_paths["PunchContact"])        # a new entry: stale ones go
    for folder in (shaft, linkage):                  # extracted for the process instead
        assert ours not in Path(folder).parents and not fmu_cache.is_cached(folder)
        assert (Path(folder) / "modelDescription.xml").read_text().startswith("<?xml")
    after = _snapshot(cache) | _snapshot(target)
    assert {k: v for k, v in after.items() if k in before and k != fmu_cache.SUBFOLDER} == {
        k: v for k, v in before.items() if k != fmu_cache.SUBFOLDER}


def test_a_relative_cache_folder_is_where_the_user_stood(fmu_paths, tmp_path, monkeypatch):
    here = tmp_path / "here"
    here.mkdir()
    folder, phi = _run(fmu_paths["MainShaft"], cwd=here, SEWFMU_CACHE_DIR="rel/cache")
    assert phi == 50.0 and Path(folder).is_absolute()
    assert Path(folder).parents[2] == here / "rel" / "cache"
    monkeypatch.setattr(fmu_cache, "_START_DIR", str(here))
    monkeypatch.chdir(tmp_path)                       # where the code stands later is no matter
    monkeypatch.setenv("SEWFMU_CACHE_DIR", "rel/cache")
    assert fmu_cache.cache_root() == here / "rel" / "cache" / fmu_cache.SUBFOLDER
    monkeypatch.setenv("HOME", str(tmp_path))
    monkeypatch.setenv("SEWFMU_CACHE_DIR", "~/c")
    assert fmu_cache._configured_root() == tmp_path / "c"


# --- damaged and changed entries are extracted again --------------------------------------------
def _delete_library(fmu: Path):
    fmu.joinpath("binaries", "linux64", "MainShaft.so").unlink()


def _truncate_code(fmu: Path):
    code = next(fmu.glob("resources/sewfmu_*/shaft_fmu.py"))
    code.write_bytes(code.read_bytes()[:100])


def _change_code_keeping_its_size(fmu: Path):
    code = next(fmu.glob("resources/sewfmu_*/shaft.py"))
    text = code.read_bytes()
    code.write_bytes(text.replace(b"return", b"raise ", 1))
    assert len(code.read_bytes()) == len(text)


def _shadow_a_module(fmu: Path):
    (fmu / "resources" / "json.py").write_text("raise SystemExit('not the FMU')\n")


def _code_as_a_link(fmu: Path):
    code = next(fmu.glob("resources/sewfmu_*/shaft.py"))
    copy = fmu.parents[3] / "elsewhere.py"           # beside the cache, in the test's folder
    copy.write_bytes(code.read_bytes())
    code.unlink()
    code.symlink_to(copy)


@pytest.mark.slow
@pytest.mark.parametrize("damage", [_delete_library, _truncate_code, _change_code_keeping_its_size,
                                    _shadow_a_module, _code_as_a_link])
def test_a_damaged_or_changed_entry_is_extracted_again(fmu_paths, tmp_path, damage):
    cache = tmp_path / "cache"
    folder, _ = _run(fmu_paths["MainShaft"], SEWFMU_CACHE_DIR=str(cache))
    damage(Path(folder))
    expected = archives.members(fmu_paths["MainShaft"], fmu_cache.fmu_limits())
    assert archives.differences(Path(folder), expected) is not None
    again, phi = _run(fmu_paths["MainShaft"], SEWFMU_CACHE_DIR=str(cache))
    assert (again, phi) == (folder, 50.0)
    assert archives.differences(Path(folder), expected) is None
    assert len(_entries(cache)) == 3                 # the entry, the tag, the lock: no trash


# --- bounded extraction -------------------------------------------------------------------------
def _with_member(fmu: Path, out: Path, name: str, data: bytes, claim: int | None = None) -> Path:
    """A copy of an FMU with one more member; `claim`: the size its directory says instead."""
    with zipfile.ZipFile(fmu) as src, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for item in src.infolist():
            dst.writestr(item, src.read(item))
        dst.writestr(name, data)
        if claim is not None:
            dst.getinfo(name).file_size = claim      # written into the central directory
    return out


def _nothing_may_be_written(monkeypatch):
    def refuse(*args):
        raise AssertionError("a member was written")
    monkeypatch.setattr(archives, "_write", refuse)


@pytest.mark.parametrize("cached", [True, False], ids=["cache", "no cache"])
def test_a_zip_bomb_fmu_is_refused_from_its_directory(fmu_paths, tmp_path, monkeypatch, cached):
    bomb = _with_member(fmu_paths["MainShaft"], tmp_path / "Bomb.fmu", "resources/zeros", b"\0",
                        claim=1 << 30)
    cache, tmp = tmp_path / "cache", tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setenv("SEWFMU_CACHE_DIR", str(cache) if cached else "")
    monkeypatch.setattr("tempfile.tempdir", str(tmp))
    _nothing_may_be_written(monkeypatch)
    with pytest.raises(CosimError) as refused:
        fmu_cache.extract_cached(bomb)
    said = str(refused.value)
    assert "\n" not in said and str(bomb) in said and "'resources/zeros'" in said
    assert "1024 MiB" in said and "512 MiB" in said and fmu_cache.LIMIT_SETTING in said
    assert list(tmp.iterdir()) == []
    assert not cached or _entries(cache) == ["CACHEDIR.TAG"]


def test_a_bomb_is_counted_while_written_and_the_limit_is_a_setting(fmu_paths, tmp_path,
                                                                     monkeypatch):
    monkeypatch.setenv("SEWFMU_CACHE_DIR", str(tmp_path / "cache"))
    zeros = _with_member(fmu_paths["MainShaft"], tmp_path / "Zeros.fmu", "resources/zeros",
                         bytes(16 << 20))
    monkeypatch.setenv(fmu_cache.LIMIT_SETTING, "4M")
    with pytest.raises(CosimError, match=r"'resources/zeros' unpacks to 16 MiB, more than the "
                                         r"4 MiB allowed"):
        fmu_cache.extract_cached(zeros)
    monkeypatch.setenv(fmu_cache.LIMIT_SETTING, "64MiB")
    assert (Path(fmu_cache.extract_cached(zeros)) / "resources" / "zeros").stat().st_size == 16 << 20
    # a directory that says less than the member holds: counted, and refused as it is written
    liar = _with_member(fmu_paths["MainShaft"], tmp_path / "Liar.fmu", "resources/zeros",
                        bytes(16 << 20), claim=1000)
    with pytest.raises(CosimError, match="Liar.fmu"):
        fmu_cache.extract_cached(liar)
    assert _entries(tmp_path / "cache") == sorted(
        ["CACHEDIR.TAG", ".sewfmu-lock", fmu_cache.content_hash(zeros)])
    monkeypatch.setenv(fmu_cache.LIMIT_SETTING, "lots")
    with pytest.raises(CosimError, match=f"{fmu_cache.LIMIT_SETTING}='lots' is not a size"):
        fmu_cache.extract_cached(zeros)


def test_a_zip_bomb_ssp_is_refused_before_a_byte_is_written(tmp_path, monkeypatch):
    ssp = tmp_path / "bomb.ssp"
    with zipfile.ZipFile(ssp, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd", "<x/>")
        z.writestr("resources/zeros", b"\0")
        z.getinfo("resources/zeros").file_size = 3 << 30      # 1.9 GiB got written before
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setattr("tempfile.tempdir", str(tmp))
    _nothing_may_be_written(monkeypatch)
    with pytest.raises(ScenarioError, match=r"bomb.ssp: member 'resources/zeros' unpacks to "
                                            r"3072 MiB, more than the 2048 MiB allowed"):
        load(str(ssp))
    assert list(tmp.iterdir()) == []


def _zip(path: Path, members: dict, modes: dict | None = None) -> Path:
    with zipfile.ZipFile(path, "w") as z:
        for name, data in members.items():
            info = zipfile.ZipInfo(name)
            if modes and name in modes:
                info.external_attr = modes[name] << 16
            z.writestr(info, data)
    return path


@pytest.mark.parametrize("members, modes, said", [
    ({"/etc/cron.d/x": "x"}, None, "points outside"),
    ({"resources/../../x": "x"}, None, "points outside"),
    ({"C:/x": "x"}, None, "points outside"),
    ({"resources\\..\\..\\x": "x"}, None, "points outside"),
    ({"link": "/etc/passwd"}, {"link": stat.S_IFLNK | 0o777}, "not a regular file"),
    ({"a": "1", "./a": "2"}, None, "appears twice"),
    ({f"m{k}": "" for k in range(30)}, None, "30 archive members, more than the 20"),
    ({"big": "x" * 2000}, None, "'big' unpacks to 2000 bytes, more than the 1000 bytes"),
    ({f"m{k}": "x" * 400 for k in range(3)}, None, "the archive unpacks to 1200 bytes"),
])
def test_what_an_archive_may_not_hold(tmp_path, members, modes, said):
    archive = _zip(tmp_path / "a.zip", members, modes)
    limits = archives.Limits(1000, 1000, 20, "FMU")
    for read in (lambda: archives.members(archive, limits),
                 lambda: archives.extract(archive, tmp_path / "out", limits)):
        with pytest.raises(archives.ArchiveError, match=re.escape(said)):
            read()
        assert not any((tmp_path / "out").rglob("*")) and not (tmp_path / "x").exists()


# --- killed extractions --------------------------------------------------------------------------
@pytest.mark.slow
def test_a_run_killed_mid_extraction_leaves_scratch_the_next_run_removes(fmu_paths, tmp_path,
                                                                          monkeypatch):
    cache = tmp_path / "cache"
    killed = _stopped_mid_extraction(fmu_paths["MainShaft"], SEWFMU_CACHE_DIR=str(cache))
    _kill(killed)
    scratch = cache / fmu_cache.SUBFOLDER / (f".{fmu_cache.content_hash(fmu_paths['MainShaft'])}"
                                             f".{archives.host()}.sewfmu-{killed.pid}.partial")
    assert any(scratch.rglob("*.py"))                                 # half-written
    assert _entries(cache) == sorted(["CACHEDIR.TAG", scratch.name])    # and no entry
    live = _stopped_mid_extraction(fmu_paths["PunchLinkage"], SEWFMU_CACHE_DIR=str(cache))
    try:
        folder, phi = _run(fmu_paths["MainShaft"], SEWFMU_CACHE_DIR=str(cache))
        assert phi == 50.0 and not scratch.exists()
        left = [e for e in _entries(cache) if e.startswith(".") and e != ".sewfmu-lock"]
        assert left == [f".{fmu_cache.content_hash(fmu_paths['PunchLinkage'])}.{archives.host()}"
                        f".sewfmu-{live.pid}.partial"]                  # a live writer's stays
    finally:
        _kill(live)
    _run(fmu_paths["PunchLinkage"], SEWFMU_CACHE_DIR=str(cache))
    assert [e for e in _entries(cache) if e.startswith(".")] == [".sewfmu-lock"]


@pytest.mark.slow
def test_a_run_without_a_cache_killed_mid_extraction_is_cleaned_up_by_the_next(fmu_paths,
                                                                              tmp_path):
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    mine = {"sewfmu-fmu-notes.txt": "x", "sewfmu-fmu-12-abc.txt": "y"}     # a user's look-alikes
    for name, text in mine.items():
        (tmp / name).write_text(text)
    (tmp / f"sewfmu-fmu-{os.getpid()}-alive").mkdir()                     # a live process's
    killed = _stopped_mid_extraction(fmu_paths["MainShaft"], SEWFMU_CACHE_DIR="", TMPDIR=str(tmp))
    _kill(killed)
    (left,) = tmp.glob(f"sewfmu-fmu-{killed.pid}-*")
    assert any(left.rglob("*.py"))
    folder, phi = _run(fmu_paths["MainShaft"], SEWFMU_CACHE_DIR="", TMPDIR=str(tmp))
    assert phi == 50.0 and Path(folder).parent == tmp
    assert sorted(p.name for p in tmp.iterdir()) == sorted([*mine, f"sewfmu-fmu-{os.getpid()}-alive"])


def test_scratch_of_another_host_goes_only_when_old(tmp_path):
    pattern = re.compile(r"\.x\.(?P<host>[A-Za-z0-9_-]+)\.sewfmu-(?P<pid>\d+)\.partial")
    for name in (".x.otherhost.sewfmu-1.partial", ".x.oldhost.sewfmu-1.partial",
                 f".x.{archives.host()}.sewfmu-{os.getpid()}.partial"):
        (tmp_path / name).mkdir()
    os.utime(tmp_path / ".x.oldhost.sewfmu-1.partial", (OLD, OLD))
    removed = archives.remove_dead_scratch(tmp_path, pattern)
    assert [p.name for p in removed] == [".x.oldhost.sewfmu-1.partial"]


@pytest.mark.slow
def test_concurrent_runs_share_one_extraction_with_its_bytecode(fmu_paths, tmp_path):
    cache = tmp_path / "cache"
    runs = [_started(fmu_paths["MainShaft"], cache) for _ in range(4)]     # all at once
    outputs = [p.communicate(timeout=120) for p in runs]
    assert all(p.returncode == 0 for p in runs), [err[-500:] for _, err in outputs]
    folders = {out.split()[0] for out, _ in outputs}
    assert len(folders) == 1 and {out.split()[1] for out, _ in outputs} == {"50.0"}
    folder = Path(folders.pop())
    assert folder.parent.parent == cache / fmu_cache.SUBFOLDER and folder.name == "fmu"
    # one entry, no scratch folder left (the lock and the backup tools' tag are the cache's own)
    assert sorted(p.name for p in folder.parent.parent.iterdir()) == sorted(
        [folder.parent.name, "CACHEDIR.TAG", ".sewfmu-lock"])
    # the FMU's code left its bytecode, PYTHONDONTWRITEBYTECODE notwithstanding
    assert list(folder.glob("resources/*/__pycache__/*.pyc"))
    # and the bytecode is no damage: a later run uses the entry as it is
    marker = (folder.parent / fmu_cache.MARKER).stat()
    again = _started(fmu_paths["MainShaft"], cache)
    assert again.communicate(timeout=120)[0].split()[0] == str(folder)
    assert (folder.parent / fmu_cache.MARKER).stat().st_ino == marker.st_ino


def test_another_content_is_another_entry_and_stale_ones_go(fmu_paths, tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    monkeypatch.setenv("SEWFMU_CACHE_DIR", str(cache))
    first = fmu_cache.extract_cached(fmu_paths["MainShaft"])
    assert fmu_cache.extract_cached(fmu_paths["MainShaft"]) == first       # reused
    assert fmu_cache.is_cached(first)
    old = time.time() - (fmu_cache.STALE_DAYS + 1) * 86400
    os.utime(Path(first).parent, (old, old))          # the entry, which a use touches
    second = fmu_cache.extract_cached(fmu_paths["PunchLinkage"])
    assert second != first and Path(second).is_dir()
    assert not Path(first).parent.exists()          # unused for longer than STALE_DAYS
    # beyond MAX_ENTRIES the least recently used go (if unused for an hour)
    monkeypatch.setattr(fmu_cache, "MAX_ENTRIES", 1)
    os.utime(Path(second).parent, (time.time() - 7200,) * 2)
    third = fmu_cache.extract_cached(fmu_paths["PunchContact"])
    assert Path(third).is_dir() and not Path(second).parent.exists()


def test_without_a_cache_to_write_the_fmu_is_extracted_for_the_process(fmu_paths, tmp_path,
                                                                        monkeypatch):
    monkeypatch.setenv("SEWFMU_CACHE_DIR", "")
    folder = fmu_cache.extract_cached(fmu_paths["MainShaft"])
    assert (Path(folder) / "modelDescription.xml").is_file()
    assert not fmu_cache.is_cached(folder)
    assert Path(folder).name.startswith(f"sewfmu-fmu-{os.getpid()}-")   # a killed run's: found
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setenv("SEWFMU_CACHE_DIR", str(blocked / "cache"))
    assert fmu_cache.cache_root() is None
