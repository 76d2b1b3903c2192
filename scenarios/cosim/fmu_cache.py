"""Extracted FMUs kept between runs and processes, by the hash of the FMU file's content.

A run used to extract every FMU into a new temporary folder, so the FMU's Python code was
compiled again at every run (no bytecode survives a removed folder). Kept here, an FMU is
extracted once, and the bytecode its code leaves in resources/__pycache__ serves every later run,
in any process, until the file changes (another content, another folder).

- Where: $SEWFMU_CACHE_DIR, else $XDG_CACHE_HOME/sewfmu/fmus, else ~/.cache/sewfmu/fmus;
  SEWFMU_CACHE_DIR="" (or a folder that cannot be written) extracts into a temporary folder per
  process instead, removed at exit, as before.
- Concurrent runs: each extracts into its own hidden folder and renames it into place; the rename
  is atomic, and a run that finds the place taken uses the folder already there.
- Stale entries: a use touches the entry; when a new one is made, entries unused for STALE_DAYS
  days go, and so do the least recently used beyond MAX_ENTRIES (every build makes a new FMU
  file: its GUID and time stamps differ).
"""
from __future__ import annotations

import atexit
import hashlib
import os
import shutil
import tempfile
import time
from pathlib import Path

STALE_DAYS = 30
# beyond this many entries the least recently used go, if unused for an hour (a running process
# may still be loading from a newer one); about 1 MiB each
MAX_ENTRIES = 64


def _configured_root() -> Path | None:
    """Where the cache is to be (not made here); None where it is turned off."""
    setting = os.environ.get("SEWFMU_CACHE_DIR")
    if setting == "":
        return None
    if setting:
        return Path(setting)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "sewfmu" / "fmus"


def cache_root() -> Path | None:
    """The cache folder, made if needed; None where there is none to write."""
    root = _configured_root()
    if root is None:
        return None
    try:
        root.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    return root if os.access(root, os.W_OK | os.X_OK) else None


def content_hash(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as file:
        for block in iter(lambda: file.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()[:32]


def extract_cached(path: Path) -> str:
    """The folder the FMU file is extracted in: from the cache, or extracted into it now."""
    from fmpy import extract  # fmpy: only when an FMU file is read

    root = cache_root()
    if root is None:
        folder = extract(str(path))
        atexit.register(shutil.rmtree, folder, True)
        return folder
    target = root / content_hash(path)
    if (target / "modelDescription.xml").is_file():
        _touch(target)
        return str(target)
    scratch = tempfile.mkdtemp(prefix=f".{target.name}-", dir=root)
    try:
        extract(str(path), unzipdir=scratch)
        os.rename(scratch, target)
    except OSError:                       # another run put it there first: theirs is the same
        shutil.rmtree(scratch, ignore_errors=True)
        if not (target / "modelDescription.xml").is_file():
            raise
    _remove_stale(root)
    return str(target)


def is_cached(folder: str) -> bool:
    """Whether an unzip folder is one of the cache's (it keeps bytecode; a temporary one not)."""
    root = _configured_root()
    return root is not None and Path(folder).parent == root


def _touch(folder: Path) -> None:
    try:
        os.utime(folder)
    except OSError:
        pass


def _remove_stale(root: Path) -> None:
    now = time.time()
    entries = []
    for entry in root.iterdir():
        try:
            if entry.is_dir() and not entry.name.startswith("."):
                entries.append((entry.stat().st_mtime, entry))
        except OSError:
            pass
    entries.sort(reverse=True)                        # most recently used first
    for k, (used, entry) in enumerate(entries):
        if used < now - STALE_DAYS * 86400 or (k >= MAX_ENTRIES and used < now - 3600):
            shutil.rmtree(entry, ignore_errors=True)
