"""Where a run's files go: written whole or not at all, with the user's umask, and no debris.

- `write_atomic` writes a file through a temporary beside it and renames it into place, so a
  reader never sees half a file; the file gets the permissions the user's umask gives (Python's
  temporary files would be 0600).
- `replacing(folder)` gives a run a staging folder inside its output folder; only when the whole
  run has succeeded do the staged files take their places, replacing what the previous run wrote
  there (listed in the folder's MANIFEST), and nothing else: a user's own files in the folder stay.
  A run that fails or is interrupted (in its third [compare] variant, say) leaves the previous
  results as they were, never a mix of old and new.
- A command that writes as it goes (a sweep, a design study: records appended run by run, then
  its tables and pictures) follows the same rule: `refuse_theirs` before its first run (a file of
  a name it will write that the manifest does not list is refused in one line), `claim` lists its
  records in the manifest before it appends to them, and `replacing(folder, kept=records)` puts
  its final files in place.
- Temporaries carry the writing process's id in their names (".NAME.PID.tmp",
  ".sewfmu.PID.partial"). A killed process cannot clean up after itself; the next run into the
  same place removes what dead processes left (`remove_debris`).
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import re
import shutil
import tempfile
import threading
from pathlib import Path

import filelock

from sewfmu.errors import Error

# sewfmu's own temporaries, `.NAME.sewfmu-PID.tmp|partial`: only these are ever cleaned up
_DEBRIS = re.compile(r"^\..+\.sewfmu-(\d+)\.(tmp|partial)$")


class OutputError(Error, ValueError):
    """An output folder sewfmu will not write into, named with the reason."""


def umask() -> int:
    """The process's umask (read without changing it where Linux allows)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)          # elsewhere: the classic read-by-setting, restored at once
    os.umask(mask)
    return mask


def _temporary(path: Path, kind: str) -> Path:
    return path.parent / f".{path.name}.sewfmu-{os.getpid()}.{kind}"


def write_atomic(path: Path, write, binary: bool = False) -> None:
    """Write a file via a temporary in the same folder, then rename: never a half-written file.
    `write(f)` receives the open temporary (text in UTF-8, or binary)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _temporary(path, "tmp")
    try:
        # os.open with 0o666 lets the umask decide the permissions, as for any file a user writes
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o666)
        mode = "wb" if binary else "w"
        with (os.fdopen(fd, mode) if binary
              else os.fdopen(fd, mode, newline="", encoding="utf-8")) as f:
            write(f)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:         # someone else's process: alive
        return True
    return True


def remove_debris(folder: Path, recursive: bool = False) -> list[Path]:
    """Remove the temporaries that dead processes left in folder (and below it); return them."""
    folder = Path(folder)
    if not folder.is_dir():
        return []
    removed = []
    entries = folder.rglob(".*") if recursive else folder.glob(".*")
    for entry in list(entries):
        match = _DEBRIS.match(entry.name)
        if not match or int(match.group(1)) == os.getpid() or alive(int(match.group(1))):
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry, ignore_errors=True)
        else:
            with contextlib.suppress(OSError):
                entry.unlink()
        removed.append(entry)
    return removed


MANIFEST = ".sewfmu-outputs"      # the files the last run wrote into an output folder, one per line


def written_by_last_run(folder: Path) -> list[str]:
    """The files sewfmu's last run wrote into the folder (its manifest), as the user sees them."""
    return [n for n in _entries_of_last_run(folder) if (Path(folder) / n).is_file()]


def _entries_of_last_run(folder: Path) -> list[str]:
    try:
        lines = (folder / MANIFEST).read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return []
    # only relative paths inside the folder: a damaged manifest must not reach outside it
    return [n for n in lines if n and "\\" not in n and "\x00" not in n and not n.startswith("/")
            and all(part not in ("", ".", "..") for part in n.split("/"))]


def _not_ours_error(folder: Path, theirs: list[str]) -> OutputError:
    one = len(theirs) == 1
    shown = ", ".join(theirs[:3]) + (" ..." if len(theirs) > 3 else "")
    return OutputError(f"output folder {folder}: {shown} there {'is' if one else 'are'} "
                       f"not from sewfmu's last run into it ({MANIFEST} does not list "
                       f"{'it' if one else 'them'}), and sewfmu replaces only "
                       f"what it wrote: give another output folder, or move "
                       f"{'it' if one else 'them'} away")


def refuse_theirs(folder: Path, names, ours=None) -> None:
    """Before a command writes anything: refuse, in one line, where a file of one of `names`
    (paths inside the folder) is there and sewfmu's last command into the folder did not write
    it (its manifest does not list it). `ours(name)`, where given, recognizes a record of
    sewfmu's by its content (one written before folders kept a manifest)."""
    folder = Path(folder)
    listed = set(_entries_of_last_run(folder))
    theirs = [n for n in dict.fromkeys(names) if n not in listed
              and os.path.lexists(folder / n) and not (ours is not None and ours(n))]
    if theirs:
        raise _not_ours_error(folder, theirs)


def claim(folder: Path, names) -> None:
    """List `names` in the folder's manifest, beside what it lists, before they are written in
    place (a record appended run by run): killed half-way, the command leaves files the next one
    knows as sewfmu's."""
    folder = Path(folder)
    listed = _entries_of_last_run(folder)
    new = [n for n in dict.fromkeys(names) if n not in listed]
    if new:
        write_atomic(folder / MANIFEST, lambda f: f.write("".join(f"{n}\n"
                                                                  for n in listed + new)))


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:                       # gone, or a user's file stands where its folder was
        with contextlib.suppress(FileNotFoundError, NotADirectoryError):
            path.unlink()


def _files_in(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*")
                  if not p.is_dir() or p.is_symlink())


@contextlib.contextmanager
def replacing(folder: Path, kept=()):
    """Yield a staging folder; when the block succeeds its files take their places in `folder`
    (the previous run's files go, the user's other files stay, in subfolders too), when it fails
    or is interrupted it is removed and `folder` stays as it was. `kept`: files this command
    wrote in place (its records, `claim`ed): listed in the manifest, neither staged nor
    removed."""
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise OutputError(f"output folder {folder}: exists and is not a folder")
    created = not folder.exists()
    folder.mkdir(parents=True, exist_ok=True)
    remove_debris(folder)
    staging = _temporary(folder / "outputs", "partial")
    shutil.rmtree(staging, ignore_errors=True)
    os.mkdir(staging)                        # mode from the umask
    try:
        yield staging
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        if created:
            with contextlib.suppress(OSError):
                folder.rmdir()               # only if nothing else is in it
        raise
    new = _files_in(staging)
    kept = [n for n in dict.fromkeys(kept) if n not in new and os.path.lexists(folder / n)]
    old = _entries_of_last_run(folder)
    theirs = [n for n in new if n not in old and os.path.lexists(folder / n)]
    if theirs:                               # a file sewfmu did not write is never replaced
        shutil.rmtree(staging, ignore_errors=True)
        raise _not_ours_error(folder, theirs)
    for name in (set(old) | set(new)) - set(kept):
        _remove(folder / name)
    for name in old:                         # the folders the last run made, if now empty
        for parent in (folder / name).parents:
            if parent == folder:
                break
            with contextlib.suppress(OSError):
                parent.rmdir()
    for name in new:
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        os.rename(staging / name, folder / name)
    write_atomic(folder / MANIFEST, lambda f: f.write("".join(f"{n}\n" for n in new + kept)))
    shutil.rmtree(staging, ignore_errors=True)


def folder_for(base: Path, label: str) -> Path:
    """The folder of one variant or sweep point (`instance.parameter=value`) inside base: path
    separators and a leading dot are replaced, and the result is checked to lie inside base."""
    name = re.sub(r"[/\\\x00]", "_", label).lstrip(".") or "_"
    folder = Path(base) / name
    if Path(base).resolve() not in folder.resolve().parents:
        raise OutputError(f"{label!r} cannot be a folder inside {base}")
    return folder


# the folders this process holds (held): real path -> (the holding thread, how deep)
_HELD: dict[str, tuple[int, int]] = {}
_HELD_LOCK = threading.Lock()


@contextlib.contextmanager
def held(folder: Path):
    """The folder for this study or sweep alone while the block runs: a second one into it is
    refused in one line, since both would append to the same resume record and mix their lines.
    The lock (filelock: flock, or Windows' own) is a file of this user's temporary folder named
    by the folder's real path: nothing is left in the folder, and a killed process's lock goes
    with it. The thread that holds a folder may hold it again (a study holds its
    folder from its first check to its last file, its record and its sweep inside that)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    key, me = os.path.realpath(folder), threading.get_ident()
    with _HELD_LOCK:
        holder, depth = _HELD.get(key, (None, 0))
        if holder == me:
            _HELD[key] = (me, depth + 1)
    if holder == me:
        try:
            yield
        finally:
            with _HELD_LOCK:
                _HELD[key] = (me, _HELD[key][1] - 1)
        return
    lock = filelock.FileLock(_lock_file(key), timeout=0)
    try:
        lock.acquire()
    except filelock.Timeout:
        raise OutputError(f"{folder}: another sewfmu sweep or study is writing into this folder "
                          f"now; give another output folder, or run this one when it has "
                          f"ended") from None
    try:
        with _HELD_LOCK:
            _HELD[key] = (me, 1)
        try:
            yield
        finally:
            with _HELD_LOCK:
                _HELD.pop(key, None)
    finally:
        lock.release()


def _lock_file(real_path: str) -> str:
    """The lock of an output folder: in this user's temporary folder, never in the folder."""
    user = os.getuid() if hasattr(os, "getuid") else os.environ.get("USERNAME", "user")
    locks = Path(tempfile.gettempdir()) / f"sewfmu-locks-{user}"
    locks.mkdir(mode=0o700, exist_ok=True)
    return str(locks / f"{hashlib.sha256(real_path.encode()).hexdigest()[:32]}.lock")


def set_aside(path: Path) -> Path:
    """Move a file out of the way under the first free name NAME.previous[-N].EXT beside it,
    never over a file that is there (an earlier one set aside, or the user's own)."""
    path = Path(path)
    for n in range(1, 10000):
        aside = path.with_name(f"{path.stem}.previous{'' if n == 1 else f'-{n}'}{path.suffix}")
        try:
            os.link(path, aside)        # fails where the name is taken: nothing is overwritten
        except FileExistsError:
            continue
        except OSError:                 # a file system without hard links
            if aside.exists():
                continue
            os.rename(path, aside)
            return aside
        os.unlink(path)
        return aside
    raise OutputError(f"{path}: 9999 earlier records are set aside beside it already; move "
                      f"them away")


def drop_torn_line(path: Path) -> None:
    """A record appended line by line and killed in the middle of a line: that part-line is cut
    off (the record is sewfmu's own), so that the next line starts clean and a reader of the
    file sees whole lines only."""
    with open(path, "r+b") as f:
        f.seek(0, os.SEEK_END)
        size = f.tell()
        if not size:
            return
        f.seek(max(0, size - 65536))
        tail = f.read()
        if tail.endswith(b"\n"):
            return
        cut = tail.rfind(b"\n")
        f.truncate(size - len(tail) + cut + 1 if cut >= 0 else (0 if size <= 65536 else size))
