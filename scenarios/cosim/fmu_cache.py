"""Extracted FMUs kept between runs and processes, by the hash of the FMU file's content.

A run used to extract every FMU into a new temporary folder, so the FMU's Python code was
compiled again at every run (no bytecode survives a removed folder). Kept here, an FMU is
extracted once, and the bytecode its code leaves in resources/__pycache__ serves every later run,
in any process, until the file changes (another content, another entry).

- Where: $SEWFMU_CACHE_DIR (a relative path is taken from the folder the process started in),
  else $XDG_CACHE_HOME/sewfmu/fmus, else ~/.cache/sewfmu/fmus. SEWFMU_CACHE_DIR="" (or a folder
  that cannot be written) extracts into a temporary folder per process instead,
  $TMPDIR/sewfmu-fmu-PID-*, removed at exit, and by a later run if the process was killed.
- What it owns: that folder may be the user's (SEWFMU_CACHE_DIR=~/work), so the cache keeps to
  its subfolder SUBFOLDER, and there to entries named by a content hash that hold its MARKER
  (MAGIC on the first line) beside the extracted FMU (ENTRY/fmu/). Nothing else there is ever
  used, changed or removed (but the folder declared-units, scenarios/format/declared_units.py's);
  a folder in the way of an entry makes that FMU extract per process.
- Checked before use: an entry is compared with the FMU's own zip directory (every member's
  name, size and CRC32, and no file the FMU does not hold but bytecode); a damaged or changed
  entry is extracted again, so a deleted library or an edited module never runs.
- Bounded: an FMU unpacks to at most SEWFMU_FMU_MAX_BYTES (DEFAULT_MAX_BYTES; "2G", "800M"),
  checked in its directory before a byte is written and counted while writing
  (scenarios/files/archives.py).
- Concurrent runs: each extracts into its own scratch folder, named with its host and pid, and
  renames it into place under a lock (an atomic rename: a reader sees the old entry or the new);
  scratch whose writer is dead (killed mid-extraction) is removed by the next run.
- Stale entries: a use touches the entry; when a new one is made, entries unused for STALE_DAYS
  days go, and so do the least recently used beyond MAX_ENTRIES (every build makes a new FMU
  file: its GUID and time stamps differ).
"""
from __future__ import annotations

import atexit
import contextlib
import hashlib
import os
import re
import shutil
import tempfile
import time
from pathlib import Path

import filelock

from sewfmu.scenarios.cosim.fmi_calls import CosimError
from sewfmu.scenarios.files import archives
from sewfmu.scenarios.files import cache_root as cache_root_setting
from sewfmu.scenarios.files.outputs import write_atomic

STALE_DAYS = 30
# beyond this many entries the least recently used go, if unused for an hour (a running process
# may still be loading from a newer one); about 1 MiB each
MAX_ENTRIES = 64
SUBFOLDER = cache_root_setting.SUBFOLDER
MARKER = "SEWFMU-CACHE-ENTRY"
MAGIC = "sewfmu FMU cache entry, version 1: made and removed by sewfmu"
# the Cache Directory Tagging Specification's signature: backup tools skip the folder
CACHEDIR_TAG = "Signature: 8a477f597d28d172789f06886806bc55\n# sewfmu's extracted FMUs\n"
LIMIT_SETTING = "SEWFMU_FMU_MAX_BYTES"
DEFAULT_MAX_BYTES = 512 << 20       # sewfmu's FMUs unpack to 1-2 MiB; one bundling numpy ~100 MiB
MAX_MEMBERS = 20_000

_ENTRY = re.compile(r"[0-9a-f]{32}")
_SCRATCH = re.compile(r"\.[0-9a-f]{32}\.(?P<host>[A-Za-z0-9_-]+)\.sewfmu-(?P<pid>\d+)\."
                      r"(partial|trash)")
_TEMP_PREFIX = "sewfmu-fmu-"
_TEMP = re.compile(r"sewfmu-fmu-(?P<pid>\d+)-[A-Za-z0-9_]+")     # tempfile.mkdtemp's suffix

# the folder the process started in: a relative SEWFMU_CACHE_DIR means the same folder whatever
# the code's working folder later, and the FMU gets an absolute resources URI (a relative one
# failed as "instantiate returned FATAL")
_START_DIR = cache_root_setting.START_DIR

_CACHED: set[str] = set()           # the folders this process was given from the cache
_SWEPT: set[str] = set()            # the folders whose dead scratch this process has removed


def _configured_root() -> Path | None:
    """Where the cache is to be (not made here); None where it is turned off."""
    return cache_root_setting.configured_root(_START_DIR)


def cache_root() -> Path | None:
    """The folder the entries are in (sewfmu's subfolder of the configured one), made if needed;
    None where there is none to write."""
    root = _configured_root()
    if root is None:
        return None
    folder = root / SUBFOLDER
    try:
        folder.mkdir(parents=True, exist_ok=True)
        if not os.access(folder, os.W_OK | os.X_OK):
            return None
        if not (folder / "CACHEDIR.TAG").is_file():
            write_atomic(folder / "CACHEDIR.TAG", lambda f: f.write(CACHEDIR_TAG))
    except OSError:
        return None
    return folder


def fmu_limits() -> archives.Limits:
    """What one FMU may unpack to: SEWFMU_FMU_MAX_BYTES, else DEFAULT_MAX_BYTES."""
    text = os.environ.get(LIMIT_SETTING, "").strip()
    total = DEFAULT_MAX_BYTES
    if text:
        match = re.fullmatch(r"(\d+(?:\.\d+)?)\s*([KMG]?)(?:i?B)?", text, re.IGNORECASE)
        if not match or float(match.group(1)) <= 0:
            raise CosimError(f"{LIMIT_SETTING}={text!r} is not a size: bytes, or with K, M or G "
                             f"(800M, 2G)")
        total = int(float(match.group(1)) * 1024 ** " KMG".index(match.group(2).upper() or " "))
    return archives.Limits(total, total, MAX_MEMBERS, "FMU", LIMIT_SETTING)


def content_hash(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as file:
        for block in iter(lambda: file.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()[:32]


def _members(path: Path, limits: archives.Limits) -> list[archives.Member]:
    try:
        return archives.members(path, limits)
    except archives.ArchiveError as err:
        raise CosimError(str(err)) from None
    except OSError as err:
        raise CosimError(f"FMU {path}: cannot be read ({err.strerror or err})") from None


def extract_cached(path: Path) -> str:
    """The folder the FMU file is extracted in: from the cache, checked against the FMU, or
    extracted into it now."""
    path = Path(path)
    limits = fmu_limits()
    cache = cache_root()
    if cache is None:
        return _extract_for_process(path, limits)
    if str(cache) not in _SWEPT:
        archives.remove_dead_scratch(cache, _SCRATCH)
        _SWEPT.add(str(cache))
    expected = _members(path, limits)
    key = content_hash(path)
    entry = cache / key
    if not _usable(entry, key, expected):
        if os.path.lexists(entry) and not _marked(entry, key):
            return _extract_for_process(path, limits)      # not the cache's: left alone
        if not _install(path, entry, expected, limits):
            return _extract_for_process(path, limits)
        _remove_stale(cache, keep=entry)
        problem = archives.differences(entry / "fmu", expected)
        if problem is not None:
            raise CosimError(f"FMU {path}: its cache entry {entry} differs from the FMU right "
                             f"after extraction ({problem}); SEWFMU_CACHE_DIR='' extracts it "
                             f"per run")
    folder = str(entry / "fmu")
    _CACHED.add(folder)
    return folder


def is_cached(folder: str) -> bool:
    """Whether an unzip folder is one of the cache's (it keeps bytecode; a temporary one not)."""
    return str(folder) in _CACHED


def _marked(entry: Path, key: str) -> bool:
    """Whether `entry` is one of the cache's: a real folder with the marker, for this key."""
    try:
        if entry.is_symlink() or not entry.is_dir():
            return False
        with open(entry / MARKER, encoding="utf-8") as f:
            return f.readline().rstrip("\n") == MAGIC and f.readline().split() == ["key", key]
    except (OSError, UnicodeDecodeError):
        return False


def _usable(entry: Path, key: str, expected: list[archives.Member]) -> bool:
    # touched first: a run removing stale entries meanwhile sees it used
    if not _marked(entry, key):
        return False
    with contextlib.suppress(OSError):
        os.utime(entry)
    return archives.differences(entry / "fmu", expected) is None


@contextlib.contextmanager
def _locked(cache: Path):
    """One run at a time makes, mends or removes entries (readers take no lock)."""
    lock = filelock.FileLock(cache / ".sewfmu-lock", mode=0o666)
    try:
        lock.acquire()
    except OSError:                                 # no lock where the file system has none
        lock = None
    try:
        yield
    finally:
        if lock is not None:
            lock.release()


def _scratch(entry: Path, kind: str) -> Path:
    return entry.parent / f".{entry.name}.{archives.host()}.sewfmu-{os.getpid()}.{kind}"


def _install(path: Path, entry: Path, expected: list[archives.Member],
             limits: archives.Limits) -> bool:
    """Extract the FMU into a scratch folder and rename it into the entry's place, a damaged
    entry there moved aside first; False if a folder not the cache's took the place."""
    scratch, trash = _scratch(entry, "partial"), _scratch(entry, "trash")
    shutil.rmtree(scratch, ignore_errors=True)          # this pid's, from an earlier failure
    try:
        os.mkdir(scratch)
        write_atomic(scratch / MARKER, lambda f: f.write(f"{MAGIC}\nkey {entry.name}\n"
                                                         f"source {path}\n"))
        archives.extract(path, scratch / "fmu", limits)
        # the extraction runs unlocked (a stopped run must not hold up the others); the lock
        # makes the check and the renames one step
        with _locked(entry.parent):
            if _usable(entry, entry.name, expected):     # another run made or mended it
                return True
            if os.path.lexists(entry):
                if not _marked(entry, entry.name):
                    return False
                os.rename(entry, trash)
            os.rename(scratch, entry)
        return True
    except archives.ArchiveError as err:
        raise CosimError(str(err)) from None
    except OSError as err:
        raise CosimError(f"FMU {path}: cannot extract into the cache {entry.parent} "
                         f"({err.strerror or err}); SEWFMU_CACHE_DIR='' extracts it per "
                         f"run") from None
    finally:
        shutil.rmtree(scratch, ignore_errors=True)       # gone already if it was renamed
        shutil.rmtree(trash, ignore_errors=True)


def _remove_stale(cache: Path, keep: Path) -> None:
    """Remove the cache's own entries unused for STALE_DAYS, and beyond MAX_ENTRIES (moved aside
    first, so that a run finds an entry whole or not at all)."""
    with _locked(cache):
        _remove_stale_locked(cache, keep)


def _remove_stale_locked(cache: Path, keep: Path) -> None:
    now = time.time()
    entries = []
    for entry in cache.iterdir():
        if _ENTRY.fullmatch(entry.name) and entry != keep and _marked(entry, entry.name):
            with contextlib.suppress(OSError):
                entries.append((entry.stat().st_mtime, entry))
    entries.sort(reverse=True)                        # most recently used first
    for k, (used, entry) in enumerate(entries, start=1):
        if used < now - STALE_DAYS * 86400 or (k >= MAX_ENTRIES and used < now - 3600):
            trash = _scratch(entry, "trash")
            try:
                os.rename(entry, trash)
            except OSError:
                continue
            shutil.rmtree(trash, ignore_errors=True)


def _extract_for_process(path: Path, limits: archives.Limits) -> str:
    """Extract into a temporary folder of this process's, removed at its exit; the folders of
    killed processes (named with their pid) are removed here."""
    tmp = tempfile.gettempdir()
    if tmp not in _SWEPT:
        archives.remove_dead_scratch(Path(tmp), _TEMP)
        # and again at exit: a sweep's workers end without running atexit (multiprocessing
        # leaves by os._exit), so their folders are theirs to remove only once they are dead
        atexit.register(archives.remove_dead_scratch, Path(tmp), _TEMP)
        _SWEPT.add(tmp)
    folder = None
    try:
        folder = tempfile.mkdtemp(prefix=f"{_TEMP_PREFIX}{os.getpid()}-", dir=tmp)
        atexit.register(shutil.rmtree, folder, True)
        archives.extract(path, Path(folder), limits)
    except archives.ArchiveError as err:
        shutil.rmtree(folder, ignore_errors=True)
        raise CosimError(str(err)) from None
    except OSError as err:
        if folder is not None:
            shutil.rmtree(folder, ignore_errors=True)
        raise CosimError(f"FMU {path}: cannot be extracted into {tmp} "
                         f"({err.strerror or err})") from None
    return folder
