"""The content hash of folders of Python code (the name and bytes of each .py file), read and
hashed once per process while no file's stat changes: what names an FMU's code and version
(fmu_build/sources.py) and keys the FMUs' declared units (format/declared_units.py). Below both
wings, so that either reads it without the other."""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

# the files' (path, inode, size, mtime) -> their hash, for this process's lifetime: a run (and
# every sweep point in a worker) checks the FMUs by a stat of each file, and reads and hashes
# only what changed since
_SEEN: dict[tuple, str] = {}


def _python_files(folder: Path) -> list[tuple[str, str]]:
    """(name, path) of each .py file in the folder, by name (os.scandir and strings: a run lists
    its code folders twice, and pathlib's glob and sorting cost 0.5 ms each time)."""
    try:
        with os.scandir(folder) as entries:
            return sorted((e.name, e.path) for e in entries if e.name.endswith(".py"))
    except FileNotFoundError:
        return []


def hash_of(*folders: Path) -> str:
    return hash_of_files([file for folder in folders for file in _python_files(folder)])


def hash_of_files(files: list[tuple[str, str]], separator: bytes = b"") -> str:
    """12 hex digits of the hash of the (name, path) files' names and bytes (each name followed
    by `separator`), read again only when a file's stat changed."""
    key = tuple((path, st.st_ino, st.st_size, st.st_mtime_ns)
                for path, st in ((path, os.stat(path)) for _, path in files))
    if (key, separator) not in _SEEN:
        digest = hashlib.sha256()
        for name, path in files:
            digest.update(name.encode() + separator)
            digest.update(Path(path).read_bytes())
        _SEEN[key, separator] = digest.hexdigest()[:12]
    return _SEEN[key, separator]
