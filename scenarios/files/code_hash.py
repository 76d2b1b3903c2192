"""The content hash of folders of Python code (the name and bytes of each .py file), read and
hashed once per process while no file's stat changes: what names an FMU's code and version
(fmu_build/sources.py) and keys the FMUs' declared units (format/declared_units.py). Below both
wings, so that either reads it without the other."""
from __future__ import annotations

import hashlib
from pathlib import Path

# the files' (path, inode, size, mtime) -> their hash, for this process's lifetime: a run (and
# every sweep point in a worker) checks the FMUs by a stat of each file, and reads and hashes
# only what changed since
_SEEN: dict[tuple, str] = {}


def _signature(path: Path) -> tuple:
    st = path.stat()
    return str(path), st.st_ino, st.st_size, st.st_mtime_ns


def hash_of(*folders: Path) -> str:
    files = [path for folder in folders for path in sorted(Path(folder).glob("*.py"))]
    key = tuple(_signature(path) for path in files)
    if key not in _SEEN:
        digest = hashlib.sha256()
        for path in files:
            digest.update(path.name.encode())
            digest.update(path.read_bytes())
        _SEEN[key] = digest.hexdigest()[:12]
    return _SEEN[key]
