"""Where a run's files go: written whole or not at all, with the user's umask, and no debris.

The one rule of an output folder: a file in it that sewfmu did not write there is never
replaced or removed, and nothing is written or removed through a symbolic link inside it.
sewfmu's own files are those its manifest lists and that still are as it left them
(files/manifest.py: size and content hash, a record's beginning, the folders it made); a file
the user replaced at such a name is the user's.

- `write_atomic` writes a file through a temporary beside it and renames it into place, so a
  reader never sees half a file; the file gets the permissions the user's umask gives (Python's
  temporary files would be 0600). What the file system refuses names the file (`writing`).
- `replacing(folder)` gives a run a staging folder inside its output folder; only when the whole
  run has succeeded do the staged files take their places, replacing what the previous command
  wrote there, and nothing else: a user's own files in the folder stay. A run that fails or is
  interrupted (in its third [compare] variant, say) leaves the previous results as they were.
- A command that writes as it goes (a sweep, a design study: records appended run by run, then
  its tables and pictures) follows the same rule: `refuse_theirs` before its first run, over
  every name it will write (the same check its files pass at the end), `claim` lists its records
  in the manifest before it appends to them, `Placing` puts a point's file in place and lists
  it, and `replacing(folder, kept=...)` puts its final files in place.
- Every command holds its output folder while it runs (`held`): a second one into it is refused.
- Temporaries carry the writing process's id in their names (".NAME.sewfmu-PID.tmp",
  ".outputs.sewfmu-PID.partial"). A killed process cannot clean up after itself; the next run
  into the same place removes what dead processes left (`remove_debris`, files/debris.py).
"""
from __future__ import annotations

import contextlib
import dataclasses
import os
import re
import shutil
import stat
import threading
from pathlib import Path

import filelock

try:
    import fcntl
except ImportError:         # Windows: the folder's lock is a file in it (held)
    fcntl = None

from sewfmu.errors import Error
from sewfmu.scenarios.files import manifest
from sewfmu.scenarios.files.debris import alive, remove_debris  # noqa: F401 (theirs from here)
from sewfmu.scenarios.files.manifest import MANIFEST

# the names sewfmu's commands write: where a manifest of before lists only names (no size,
# no hash), one of these, or one the command writes now, is all it may remove by that word
OLD_NAMES = frozenset({"results.csv", "results.npy", "summary.json", "report.html", "sweep.csv",
                       "points.jsonl", "study.json", "evaluations.csv", "fit.json",
                       "fit_evaluations.jsonl", "optimize.json", "sensitivity.json"})


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
    `write(f)` receives the open temporary (text in UTF-8, or binary). What the file system
    refuses names the file (`writing`)."""
    path = Path(path)
    tmp = _temporary(path, "tmp")
    try:
        with writing(path, tmp):
            path.parent.mkdir(parents=True, exist_ok=True)
            # os.open with 0o666 lets the umask decide the permissions, as a user's file gets
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


def cannot_write(err: OSError, folder) -> OutputError:
    """What the file system refused while a command wrote into `folder`, as one line naming
    the file (the folder where the error names none) and the system's reason."""
    where = err.filename if err.filename is not None else folder
    return OutputError(f"cannot write {where}: {' '.join(str(err.strerror or err).split())}")


@contextlib.contextmanager
def writing(path: Path, temporary: Path | None = None):
    """An OSError raised while writing `path` names it: a full disk's or a failed write's
    error names no file, a rename's names the temporary; a folder on the way names itself."""
    try:
        yield
    except OSError as err:
        if err.filename is not None and str(err.filename) != str(temporary):
            raise
        raise OSError(err.errno, err.strerror or str(err), str(path)) from err


def written_by_last_run(folder: Path) -> list[str]:
    """The files sewfmu's last command wrote into the folder and that are still as it left
    them (its manifest), as the user sees them."""
    folder = Path(folder)
    entries = manifest.read(folder)
    return [n for n in entries if manifest.ours(folder, entries, n)]


def _refusal(folder: Path, theirs: list[str], barred: list[tuple[str, str]]) -> OutputError:
    if barred:
        where, what = barred[0]
        return OutputError(f"output folder {folder}: {where} there is {what}, and sewfmu writes "
                           f"inside its output folder only into plain folders, never through a "
                           f"link nor over a file it did not write: give another output folder, "
                           f"or move {where} away")
    one = len(theirs) == 1
    shown = ", ".join(theirs[:3]) + (" ..." if len(theirs) > 3 else "")
    return OutputError(f"output folder {folder}: {shown} there {'is' if one else 'are'} "
                       f"not from sewfmu's last run into it ({MANIFEST} does not list "
                       f"{'it' if one else 'them'} as {'it is' if one else 'they are'} now), "
                       f"and sewfmu replaces only what it wrote: give another output folder, "
                       f"or move {'it' if one else 'them'} away")


def refuse_theirs(folder: Path, names, entries: dict | None = None) -> None:
    """The one check of an output folder, before a command writes anything and again as its
    files take their places: refuse, in one line, where a file of one of `names` (paths inside
    the folder) is there and is not sewfmu's (files/manifest.py: listed, and as recorded), or
    where the way to one passes through a symbolic link or a file."""
    folder = Path(folder)
    what = manifest.foreign(folder)          # the user's: never overwritten
    if what is not None:
        raise _refusal(folder, [], [(MANIFEST, what)])
    entries = manifest.read(folder) if entries is None else entries
    theirs, barred = [], []
    for name in dict.fromkeys(names):
        way = manifest.blocked(folder, name)
        if way is not None:
            barred.append(way)
        elif os.path.islink(folder / name):
            barred.append((name, "a symbolic link"))
        elif os.path.lexists(folder / name) and not manifest.ours(folder, entries, name):
            theirs.append(name)
    if theirs or barred:
        raise _refusal(folder, theirs, barred)


def claim(folder: Path, records) -> None:
    """List the records a command appends to run by run (points.jsonl, evaluations.csv) in the
    folder's manifest before their first line: each as it is now (a torn last line cut off
    first), or made empty, so that a command killed half-way leaves records the next one knows
    as sewfmu's. Checked by refuse_theirs before."""
    folder = Path(folder)
    entries = manifest.read(folder)
    for name in dict.fromkeys(records):
        path = folder / name
        entries.update((e.name, e) for e in make_parents(folder, name))
        if os.path.lexists(path):
            drop_torn_line(path)
        else:
            os.close(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        entries.pop(name, None)
        entries[name] = manifest.state(folder, name, manifest.RECORD)
    write_atomic(folder / MANIFEST, lambda f: f.write(manifest.text(entries.values())))


class Record:
    """A record a command appends to line by line (points.jsonl, evaluations.csv,
    fit_evaluations.jsonl), `claim`ed before: opened without following a link, each line
    flushed as it is written, what the file system refuses naming the file. A record claimed
    empty is listed again with its first line, so that from then on it is known by its
    beginning (files/manifest.py)."""

    def __init__(self, path: Path):
        self.path = Path(path)
        with writing(self.path):
            fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT
                         | getattr(os, "O_NOFOLLOW", 0), 0o666)
        self.file = os.fdopen(fd, "ab")
        self._listed = os.fstat(fd).st_size > 0

    def write(self, text) -> None:
        with writing(self.path):
            self.file.write(text.encode("utf-8") if isinstance(text, str) else text)
            self.file.flush()
            if not self._listed:
                folder = self.path.parent
                manifest.append(folder, [manifest.state(folder, self.path.name,
                                                        manifest.RECORD)])
                self._listed = True

    def close(self) -> None:
        self.file.close()

    def __enter__(self) -> "Record":
        return self

    def __exit__(self, *_) -> None:
        self.close()


def make_parents(folder: Path, name: str) -> list[manifest.Entry]:
    """The folders on the way to `name` that are not there, made (never through a link:
    refuse_theirs checked the way, and this looks again); their entries."""
    made, here = [], Path(folder)
    parts = name.split("/")[:-1]
    for k, part in enumerate(parts):
        here = here / part
        try:
            os.mkdir(here)                      # mode from the umask
        except FileExistsError:
            if not here.is_dir() or here.is_symlink():
                raise _refusal(Path(folder), [], [manifest.blocked(Path(folder), name)
                                                  or ("/".join(parts[:k + 1]), "not a folder")])
            continue
        made.append(manifest.state(folder, "/".join(parts[:k + 1]), manifest.FOLDER))
    return made


class Placing:
    """Files put in place one by one while a command runs (a sweep point's results.csv): each
    written beside under a temporary name, checked, moved to its name and listed at once."""

    def __init__(self, folder: Path):
        self.folder = Path(folder)
        self.entries = manifest.read(self.folder)

    def place(self, source: Path, name: str) -> None:
        try:
            refuse_theirs(self.folder, [name], self.entries)
            made = make_parents(self.folder, name)
            os.replace(source, self.folder / name)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(source)
            raise
        added = [*made, manifest.state(self.folder, name)]
        manifest.append(self.folder, added)
        self.entries.update((e.name, e) for e in added)


def _files_in(folder: Path) -> list[str]:
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*")
                  if not p.is_dir() or p.is_symlink())


@contextlib.contextmanager
def replacing(folder: Path, kept=()):
    """Yield a staging folder; when the block succeeds its files take their places in `folder`
    (the previous command's files go, the user's other files stay, in subfolders too), when it
    fails or is interrupted it is removed and `folder` stays as it was. `kept`: files this
    command wrote in place (its records, `claim`ed; a sweep's points' results, placed): listed
    in the manifest, neither staged nor removed. The folder is held (`held`) throughout."""
    folder = Path(folder)
    if os.path.lexists(folder) and not folder.is_dir():
        raise OutputError(f"output folder {folder}: exists and is not a folder")
    with held(folder):
        created = not folder.exists()
        folder.mkdir(parents=True, exist_ok=True)
        remove_debris(folder)
        staging = _temporary(folder / "outputs", "partial")
        shutil.rmtree(staging, ignore_errors=True)
        os.mkdir(staging)                        # mode from the umask
        try:
            try:
                yield staging
            except OSError as err:     # named as the user knows it: the file in the folder
                raise _named_in(err, staging, folder) from err
        except BaseException:
            shutil.rmtree(staging, ignore_errors=True)
            if created:
                with contextlib.suppress(OSError):
                    folder.rmdir()               # only if nothing else is in it
            raise
        try:
            _put_in_place(folder, staging, kept)
        finally:
            shutil.rmtree(staging, ignore_errors=True)


def _named_in(err: OSError, staging: Path, folder: Path) -> OSError:
    """An error of a file written in the staging folder, naming the file it was to become in
    the output folder (the folder itself where it named none)."""
    where = folder if err.filename is None else Path(err.filename)
    with contextlib.suppress(ValueError):
        where = folder / where.relative_to(staging)
    return OSError(err.errno, err.strerror or str(err), str(where))


def _put_in_place(folder: Path, staging: Path, kept) -> None:
    """The staged files to their names, in place of what the manifest lists as sewfmu's and
    still is (nothing else removed, nothing written through a link), and the new manifest."""
    entries = manifest.read(folder)
    new = _files_in(staging)
    kept = [n for n in dict.fromkeys(kept) if n not in new and os.path.lexists(folder / n)]
    refuse_theirs(folder, new, entries)       # the same check as before the first run
    for name, entry in entries.items():
        if entry.kind == manifest.LISTED and name not in new \
                and name.rsplit("/", 1)[-1] not in OLD_NAMES:
            continue        # an old manifest's bare name: enough only for sewfmu's own names
        if entry.kind != manifest.FOLDER and name not in kept and manifest.matches(folder, entry):
            with contextlib.suppress(FileNotFoundError):
                os.unlink(folder / name)         # never a link followed: matches() saw to it
    made = []
    for name in new:
        made += make_parents(folder, name)
        with writing(folder / name):
            os.replace(staging / name, folder / name)
    # the folders sewfmu made that nothing is in now, deepest first; a user's folder stays
    folders = [e for e in entries.values() if e.kind == manifest.FOLDER]
    for entry in sorted(folders, key=lambda e: -e.name.count("/")):
        if manifest.matches(folder, entry):
            with contextlib.suppress(OSError):
                os.rmdir(folder / entry.name)
    listed = [manifest.state(folder, n) for n in new]
    for name in kept:                        # as this command left them, and no other
        entry = entries.get(name)
        if entry is None or entry.kind == manifest.FOLDER or \
                not manifest.matches(folder, entry):
            continue
        if entry.kind == manifest.RECORD:     # whole, as it ended: the user's lines after
            listed.append(dataclasses.replace(manifest.state(folder, name, manifest.RECORD),
                                              closed=True))
        else:
            listed.append(entry if entry.kind == manifest.FILE else manifest.state(folder, name))
    listed += [e for e in folders + made if manifest.matches(folder, e)]
    write_atomic(folder / MANIFEST, lambda f: f.write(manifest.text(listed)))


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


LOCK = ".sewfmu-lock"     # where fcntl is missing (Windows): the lock file inside the folder


@contextlib.contextmanager
def held(folder: Path):
    """The folder for this command alone while the block runs (a run, a sweep, a study: every
    command that writes into an output folder): a second one into it is refused in one line,
    since it would replace or remove the files the first is writing (a sweep's live record).
    The lock is on the folder itself (flock), so that every process agrees on it whatever its
    environment (TMPDIR), and a killed process's lock goes with it; where there is no flock
    (Windows) it is the file LOCK inside the folder (filelock), sewfmu's own name. A folder
    that is not there is made, and removed again at the end where nothing was put in it. The
    thread that holds a folder may hold it again (a study holds its folder from its first
    check to its last file, its record and its sweep inside that)."""
    folder = Path(folder)
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
    made = _made_folders(folder)
    try:
        with _locked(folder):
            with _HELD_LOCK:
                _HELD[key] = (me, 1)
            try:
                yield
            finally:
                with _HELD_LOCK:
                    _HELD.pop(key, None)
    finally:
        for path in reversed(made):              # only where nothing was put in it
            with contextlib.suppress(OSError):
                os.rmdir(path)


def _made_folders(folder: Path) -> list[Path]:
    """The output folder and the folders on the way to it that are not there, made (in order)."""
    if os.path.lexists(folder) and not folder.is_dir():
        raise OutputError(f"output folder {folder}: exists and is not a folder")
    missing = [p for p in [folder, *folder.parents] if not os.path.lexists(p)][::-1]
    for path in missing:
        with contextlib.suppress(FileExistsError):
            os.mkdir(path)                       # mode from the umask
    return missing


def _busy(folder: Path) -> OutputError:
    return OutputError(f"{folder}: another sewfmu command (a run, sweep or study) is writing "
                       f"into this folder now; give another output folder, or run this one "
                       f"when it has ended")


@contextlib.contextmanager
def _locked(folder: Path):
    if fcntl is not None:
        fd = os.open(folder, os.O_RDONLY)
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                raise _busy(folder) from None
            yield
        finally:
            os.close(fd)                         # the lock goes with it
        return
    path = folder / LOCK
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        pass
    else:             # filelock truncates it: only an empty file a lock left is sewfmu's
        if not stat.S_ISREG(st.st_mode) or st.st_size:
            raise _refusal(folder, [LOCK], [])
    lock = filelock.FileLock(str(path), timeout=0)
    try:
        lock.acquire()
    except filelock.Timeout:
        raise _busy(folder) from None
    try:
        yield
    finally:
        lock.release()


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
