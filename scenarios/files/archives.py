"""Zip archives sewfmu unpacks (FMUs, .ssp systems), which may come from anyone: bounded and
confined before a byte is written, and checked again while writing.

- The directory is read first (`members`): more members than allowed, a member or the whole
  claiming more bytes than allowed, a name that is absolute, has a drive, a backslash or a '..',
  a link, a device, a name twice: refused, with one line naming the archive, the member and the
  size, and nothing written. A 5 MB zip can claim gigabytes; it is refused from its directory.
- `extract` writes only regular files, only inside the folder, and counts the bytes it writes:
  a directory that lies about its sizes is caught (zipfile's CRC check catches a changed byte).
- `differences` compares a folder with an archive's members (names, sizes, CRC32): what a cache
  checks before it runs code it extracted earlier.
- `remove_dead_scratch`: folders that processes killed mid-extraction left, recognised by a name
  of sewfmu's carrying the writer's pid; only those of dead writers go.
"""
from __future__ import annotations

import contextlib
import os
import re
import shutil
import stat
import time
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path

from sewfmu.errors import Error
from sewfmu.scenarios.files.outputs import alive

_CHUNK = 1 << 20
_MiB = 1 << 20


class ArchiveError(Error, ValueError):
    """An archive sewfmu will not unpack, named with the member and the reason (the callers
    re-raise it as their wing's error)."""


@dataclass(frozen=True)
class Limits:
    """What one archive may unpack to; `what` and `setting` only word the refusal."""
    total_bytes: int
    member_bytes: int
    members: int
    what: str = "archive"               # "FMU", "SSP archive"
    setting: str = ""                   # the environment variable that raises the limit, if any


@dataclass(frozen=True)
class Member:
    name: str                           # a relative path with '/' separators
    size: int
    crc: int


def _mib(n: int) -> str:
    return f"{n / _MiB:.0f} MiB" if n >= _MiB else f"{n} bytes"


def _clean_name(name: str) -> str | None:
    """The member's relative path, or None if it could land outside the folder (or is odd
    enough that no FMU or SSP tool writes it: a backslash, a control character)."""
    if (name.startswith("/") or "\\" in name or re.match(r"^[A-Za-z]:", name)
            or any(ord(c) < 32 for c in name)):
        return None
    parts = [p for p in name.split("/") if p not in ("", ".")]
    return None if ".." in parts else "/".join(parts)      # "" for the folder itself ("./")


def _refuse(path: Path, limits: Limits, text: str) -> ArchiveError:
    return ArchiveError(f"{limits.what} {path}: {text}")


def _too_big(path: Path, limits: Limits, whose: str, size: int, limit: int) -> ArchiveError:
    raise_it = f" ({limits.setting} raises it)" if limits.setting else ""
    said, allowed = _mib(size), _mib(limit)
    if said == allowed:                      # just over the limit: say it in bytes
        said, allowed = f"{size:,} bytes", f"{limit:,} bytes"
    return _refuse(path, limits, f"{whose} unpacks to {said}, more than the {allowed} "
                                 f"allowed{raise_it}; refused (a zip bomb?)")


def _checked(path: Path, archive: zipfile.ZipFile, limits: Limits) -> list[tuple]:
    """(info, name, is a folder) of every member; refused before anything is written."""
    infos = archive.infolist()
    if len(infos) > limits.members:
        raise _refuse(path, limits, f"{len(infos)} archive members, more than the "
                                    f"{limits.members} allowed; refused")
    out, seen, total = [], set(), 0
    for info in infos:
        name = _clean_name(info.filename)
        if name is None or (name == "" and not info.is_dir()):
            raise _refuse(path, limits, f"archive member {info.filename!r} points outside the "
                                        f"archive (an absolute path, a drive or '..'); refused")
        kind = stat.S_IFMT(info.external_attr >> 16)
        if info.is_dir():
            out.append((info, name, True))
            continue
        if kind not in (0, stat.S_IFREG):            # zip tools may give no type at all
            raise _refuse(path, limits, f"archive member {info.filename!r} is not a regular "
                                        f"file (a link or a device); refused")
        if info.flag_bits & 0x1:
            raise _refuse(path, limits, f"archive member {info.filename!r} is encrypted")
        if name in seen:
            raise _refuse(path, limits, f"archive member {name!r} appears twice")
        seen.add(name)
        if info.file_size > limits.member_bytes:
            raise _too_big(path, limits, f"member {name!r}", info.file_size, limits.member_bytes)
        total += info.file_size
        if total > limits.total_bytes:
            raise _too_big(path, limits, "the archive", sum(i.file_size for i in infos),
                           limits.total_bytes)
        out.append((info, name, False))
    return out


@contextlib.contextmanager
def _opened(path: Path, limits: Limits):
    # the directory is parsed whole into memory: an archive far larger than what it may unpack
    # to (plus its directory) is refused unread
    size = Path(path).stat().st_size
    if size > limits.total_bytes + limits.members * 1024:
        raise _refuse(path, limits, f"the file is {_mib(size)}, more than the "
                                    f"{_mib(limits.total_bytes)} it may unpack to; refused")
    try:
        with zipfile.ZipFile(path) as archive:
            yield archive
    except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, EOFError,
            RuntimeError) as err:
        raise _refuse(path, limits, f"not an {limits.what} sewfmu can read ({err})") from None


def members(path: Path, limits: Limits) -> list[Member]:
    """The regular files the archive holds, checked against the limits; nothing is written."""
    with _opened(path, limits) as archive:
        return [Member(name, info.file_size, info.CRC)
                for info, name, is_dir in _checked(path, archive, limits) if not is_dir]


def extract(path: Path, folder: Path, limits: Limits) -> list[Member]:
    """Unpack the archive into `folder` (made if needed, to be empty), checked before writing
    and counted while writing; return its members. On refusal the folder keeps what was written:
    the caller removes its scratch folder."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written, out = 0, []
    with _opened(path, limits) as archive:
        checked = _checked(path, archive, limits)
        try:
            for info, name, is_dir in checked:
                if is_dir:
                    (folder / name).mkdir(parents=True, exist_ok=True)
                    continue
                written += _write(archive, info, folder / name, path, limits, written)
                out.append(Member(name, info.file_size, info.CRC))
        except (zipfile.BadZipFile, NotImplementedError, EOFError, RuntimeError,
                zlib.error) as err:
            raise _refuse(path, limits, f"a damaged member ({err})") from None
        except OSError as err:
            raise _refuse(path, limits, f"cannot unpack into {folder}: {err.strerror or err}"
                          ) from None
    return out


def _write(archive, info, target: Path, path: Path, limits: Limits, before: int) -> int:
    """Write one member, counting: no more than its directory entry claims, nor the limits."""
    target.parent.mkdir(parents=True, exist_ok=True)
    bound = min(info.file_size, limits.member_bytes)
    count = 0
    # O_EXCL: a name twice (as a case-insensitive file system sees it) fails, never overwrites;
    # O_NOFOLLOW: never written through a link; 0o666: the user's umask decides, as for unzip
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0)
    with archive.open(info) as src, os.fdopen(os.open(target, flags, 0o666), "wb") as dst:
        while chunk := src.read(_CHUNK):
            count += len(chunk)
            if count > bound or before + count > limits.total_bytes:
                raise _refuse(path, limits, f"member {info.filename!r} unpacks to more than "
                                            f"the {_mib(bound)} its directory claims; refused")
            dst.write(chunk)
    return count


def _crc(file: Path) -> int:
    crc = 0
    with open(file, "rb") as f:
        while chunk := f.read(_CHUNK):
            crc = zlib.crc32(chunk, crc)
    return crc


def differences(folder: Path, expected: list[Member], ignore: str = "__pycache__") -> str | None:
    """The first way `folder` differs from the members (a file missing, of another size or CRC32,
    a file or link the archive does not hold), or None; folders named `ignore` are not looked
    into (the bytecode Python leaves beside the code)."""
    # plain strings and os calls, not Path objects: a run checks every member of every cached
    # FMU (45 files each), and pathlib's parsing was most of that check's time
    folder = os.fspath(folder)
    names = {m.name for m in expected}
    for m in expected:
        file = os.path.join(folder, m.name)
        try:
            st = os.lstat(file)
        except OSError:
            return f"{m.name} is missing"
        if not stat.S_ISREG(st.st_mode):
            return f"{m.name} is not a regular file"
        if st.st_size != m.size:
            return f"{m.name} is {st.st_size} bytes, not {m.size}"
        try:
            if _crc(file) != m.crc:
                return f"{m.name} has changed (CRC32)"
        except OSError as err:
            return f"{m.name} cannot be read ({err.strerror})"
    for base, dirs, files in os.walk(folder):
        rel = os.path.relpath(base, folder).replace(os.sep, "/")
        prefix = "" if rel == "." else rel + "/"     # the members' names: '/' separators
        for d in list(dirs):
            if os.path.islink(os.path.join(base, d)):
                return f"{prefix}{d} is a link"
            if d == ignore:
                dirs.remove(d)
        for f in files:
            name = prefix + f
            if name not in names:
                return f"{name} is not the archive's"
    return None


# --- scratch of dead processes ---------------------------------------------------------------
# Scratch names carry the writer's pid, and where a folder may be shared between machines (a
# cache in a home on NFS) its host: another host's pids say nothing here, so its scratch goes
# only when it is older than any extraction takes.
OTHER_HOSTS_SCRATCH_S = 86400


def host() -> str:
    """This machine's name as it may stand in a file name."""
    import socket  # only where there is scratch: a run from the cache names and finds none

    return re.sub(r"[^A-Za-z0-9_-]", "_", socket.gethostname())[:64] or "host"


def remove_dead_scratch(folder: Path, pattern: re.Pattern) -> list[Path]:
    """Remove the entries of `folder` whose whole name matches `pattern` (group `pid`, optional
    group `host`) and whose writer is dead; a user's files never match sewfmu's pattern. Only
    this user's entries, never through a link."""
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    now, here = time.time(), None
    for entry in entries:
        match = pattern.fullmatch(entry.name)
        if not match:
            continue
        try:
            st = entry.stat(follow_symlinks=False)
        except OSError:
            continue
        if hasattr(os, "getuid") and st.st_uid != os.getuid():
            continue
        pid = int(match.group("pid"))
        theirs = match.groupdict().get("host")
        if theirs is not None and here is None:
            here = host()
        if theirs is not None and theirs != here:
            dead = st.st_mtime < now - OTHER_HOSTS_SCRATCH_S
        else:
            dead = pid != os.getpid() and not alive(pid)
        if not dead:
            continue
        if stat.S_ISDIR(st.st_mode):
            shutil.rmtree(entry.path, ignore_errors=True)
        else:
            with contextlib.suppress(OSError):
                os.unlink(entry.path)
        removed.append(Path(entry.path))
    return removed
