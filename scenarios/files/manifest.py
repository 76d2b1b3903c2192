"""An output folder's manifest, `.sewfmu-outputs`: what sewfmu wrote there, and how it left it.

One JSON object a line, a later line of a name standing for it:
- a file: `{"file": NAME, "size", "sha256", "inode", "mtime_ns"}`, as sewfmu wrote it;
- a record appended run by run (points.jsonl, evaluations.csv): `{"record": NAME, "size",
  "sha256", "inode"}`, the part of it written when it was listed (the rest is appended after;
  listed before its first line, made empty, it is listed again with its first line); when
  its command ended, listed whole with `"closed": true`;
- a folder sewfmu made: `{"folder": NAME, "inode"}`.
A line that is a bare name is a manifest of before (names only): `LISTED`.

A file is sewfmu's only where the manifest lists it AND it still matches what was recorded
(`matches`): the same size and content (the same inode and mtime spare reading it again), a
record that still begins with what was recorded (a closed one: is all that was recorded,
a line the user appended makes it the user's), a folder that is the one sewfmu made. A file
the user replaced, edited or put at a listed name is the user's now. A bare name of an old
manifest counts where the file has not changed since that manifest was written (its mtime and
ctime not later), and only for one of sewfmu's own names or a name the command writes now
(files/outputs.py): a bare name alone never lets a command remove a user's notes.txt.
Every path is looked at without following links: a name whose way from the
folder passes through a symbolic link, or through anything but a folder, matches nothing.
"""
from __future__ import annotations

import hashlib
import json
import os
import stat
from dataclasses import dataclass
from pathlib import Path

MANIFEST = ".sewfmu-outputs"
FILE, RECORD, FOLDER, LISTED = "file", "record", "folder", "listed"
_CHUNK = 1 << 20


@dataclass(frozen=True)
class Entry:
    name: str                   # relative to the folder, '/' between its parts
    kind: str                   # FILE, RECORD, FOLDER, LISTED
    size: int = 0
    sha256: str = ""
    inode: int = 0
    mtime_ns: int = 0           # a LISTED name: the old manifest's own mtime
    closed: bool = False        # a RECORD as its command left it when it ended: whole

    def line(self) -> str:
        data = {self.kind: self.name}
        if self.kind in (FILE, RECORD):
            data.update(size=self.size, sha256=self.sha256)
        data["inode"] = self.inode
        if self.kind == FILE:
            data["mtime_ns"] = self.mtime_ns
        if self.kind == RECORD and self.closed:
            data["closed"] = True
        return json.dumps(data, ensure_ascii=False)


def valid_name(name) -> bool:
    """A relative path inside the folder: a damaged manifest must not reach outside it."""
    return isinstance(name, str) and bool(name) and "\\" not in name and "\x00" not in name \
        and not name.startswith("/") and all(p not in ("", ".", "..") for p in name.split("/"))


def read(folder: Path) -> dict[str, Entry]:
    """The manifest's entries by name (a later line of a name stands for it); none where there
    is no manifest, or it is not a plain file."""
    path = Path(folder) / MANIFEST
    try:
        st = os.lstat(path)
        if not stat.S_ISREG(st.st_mode):
            return {}
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
        with os.fdopen(fd, "rb") as f:
            lines = f.read().decode("utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return {}
    entries: dict[str, Entry] = {}
    for line in lines:
        entry = _parsed(line, st.st_mtime_ns)
        if entry is not None:
            entries.pop(entry.name, None)         # its place in the order: where last written
            entries[entry.name] = entry
    return entries


# what an old manifest's bare names end with: the kinds of file sewfmu writes
_OLD_KINDS = (".csv", ".json", ".jsonl", ".html", ".npy", ".png", ".gif")


def foreign(folder: Path) -> str | None:
    """What a `.sewfmu-outputs` in folder is where it is not sewfmu's manifest (a symbolic
    link, a folder, a file with a line that is neither an entry nor a bare name of a kind of
    file sewfmu writes), never overwritten; None where it is sewfmu's or not there."""
    path = Path(folder) / MANIFEST
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return None
    except OSError as err:
        return f"not readable ({err.strerror or err})"
    if stat.S_ISLNK(mode):
        return "a symbolic link"
    if stat.S_ISDIR(mode):
        return "a folder"
    if not stat.S_ISREG(mode):
        return "not a file"
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
        with os.fdopen(fd, "rb") as f:
            lines = f.read().decode("utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return "a file that is not sewfmu's manifest"
    for line in lines:
        entry = _parsed(line, 0)
        if entry is None or (entry.kind == LISTED and not entry.name.endswith(_OLD_KINDS)):
            return "a file that is not sewfmu's manifest"
    return None


def _parsed(line: str, written_ns: int) -> Entry | None:
    if not line.startswith("{"):
        return Entry(line, LISTED, mtime_ns=written_ns) if valid_name(line) else None
    try:
        data = json.loads(line)
    except ValueError:
        return None
    kind = next((k for k in (FILE, RECORD, FOLDER) if k in data), None) \
        if isinstance(data, dict) else None
    if kind is None or not valid_name(data[kind]):
        return None
    numbers = {k: data.get(k, 0) for k in ("size", "inode", "mtime_ns")}
    if not all(isinstance(v, int) and not isinstance(v, bool) and v >= 0
               for v in numbers.values()) or not isinstance(data.get("sha256", ""), str):
        return None
    return Entry(data[kind], kind, numbers["size"], data.get("sha256", ""), numbers["inode"],
                 numbers["mtime_ns"], kind == RECORD and data.get("closed") is True)


def text(entries) -> str:
    return "".join(e.line() + "\n" for e in entries)


def append(folder: Path, entries) -> None:
    """Entries added at the end of the manifest (a point's results placed as the sweep goes):
    one short write, never through a link."""
    data = text(entries).encode("utf-8")
    if not data:
        return
    path = Path(folder) / MANIFEST
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0),
                 0o666)
    try:
        os.write(fd, data)
    except OSError as err:
        raise OSError(err.errno, err.strerror, str(path)) from None
    finally:
        os.close(fd)


def blocked(folder: Path, name: str) -> tuple[str, str] | None:
    """Where the way to `name` inside folder is barred: (the first folder on it that is a
    symbolic link or is not a folder, what it is); None where every part before the last is a
    plain folder, or absent (made when written)."""
    parts = name.split("/")[:-1]
    here = Path(folder)
    for k, part in enumerate(parts):
        here = here / part
        try:
            mode = os.lstat(here).st_mode
        except FileNotFoundError:
            return None
        except OSError as err:
            return "/".join(parts[:k + 1]), f"not readable ({err.strerror or err})"
        if stat.S_ISLNK(mode):
            return "/".join(parts[:k + 1]), "a symbolic link"
        if not stat.S_ISDIR(mode):
            return "/".join(parts[:k + 1]), "a file where sewfmu would make a folder"
    return None


def _hash(path: Path, size: int) -> str:
    """sha256 of the first `size` bytes of the file (not through a link)."""
    digest, left = hashlib.sha256(), size
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
    with os.fdopen(fd, "rb") as f:
        while left > 0:
            chunk = f.read(min(_CHUNK, left))
            if not chunk:
                break
            digest.update(chunk)
            left -= len(chunk)
    return digest.hexdigest()


def state(folder: Path, name: str, kind: str = FILE) -> Entry:
    """The entry of `name` as it is now: a file's or a record's size and content hash (a
    record's whole present content: what the next run must find it beginning with), a
    folder's inode."""
    path = Path(folder) / name
    st = os.lstat(path)
    if kind == FOLDER:
        return Entry(name, FOLDER, inode=st.st_ino)
    return Entry(name, kind, st.st_size, _hash(path, st.st_size), st.st_ino,
                 st.st_mtime_ns if kind == FILE else 0)


def matches(folder: Path, entry: Entry) -> bool:
    """Whether the name is still what sewfmu left there (module docstring)."""
    if blocked(folder, entry.name) is not None:
        return False
    path = Path(folder) / entry.name
    try:
        st = os.lstat(path)
        if entry.kind == FOLDER:
            return stat.S_ISDIR(st.st_mode) and st.st_ino == entry.inode
        if not stat.S_ISREG(st.st_mode):
            return False
        if entry.kind == LISTED:
            return st.st_mtime_ns <= entry.mtime_ns and st.st_ctime_ns <= entry.mtime_ns
        if entry.kind == FILE:
            if st.st_size != entry.size:
                return False
            if (st.st_ino, st.st_mtime_ns) == (entry.inode, entry.mtime_ns):
                return True
            return _hash(path, entry.size) == entry.sha256
        if st.st_size < entry.size:                  # RECORD: it begins as recorded
            return False
        if entry.closed and st.st_size != entry.size:   # its command ended: lines after are
            return False                                # the user's, the record with them
        if entry.size == 0:          # made empty by sewfmu, listed again with its first line:
            return st.st_size == 0 and st.st_ino == entry.inode      # still that empty file
        return _hash(path, entry.size) == entry.sha256
    except OSError:
        return False


def ours(folder: Path, entries: dict[str, Entry], name: str) -> bool:
    """A file at `name` that the manifest lists and that still matches what was recorded."""
    entry = entries.get(name)
    return entry is not None and entry.kind != FOLDER and matches(folder, entry)
