"""A built FMU put in its folder (fmus/, fmus/native/, SEWFMU_FMU_DIR): staged beside it as
`.NAME.fmu.PID` and moved over it atomically (another process may be reading the old one), or
refused in one line naming that folder and what failed, the staged file removed. The staged files
and the builders' scratch folders ($TMPDIR/sewfmu_build_PID_*, sewfmu_native_PID_*) a killed
builder left are removed by the next build (files/archives.remove_dead_scratch)."""
from __future__ import annotations

import contextlib
import errno
import os
import re
import shutil
import tempfile
from pathlib import Path

from sewfmu.components.registry import FMUS
from sewfmu.errors import ScenarioError
from sewfmu.scenarios.files.archives import remove_dead_scratch

# only sewfmu's own FMU names: a user's `.Other.fmu.1234` is kept
_STAGED = re.compile(r"\.(" + "|".join(map(re.escape, FMUS)) + r")\.fmu\.(?P<pid>\d+)")
_READ_ONLY = (errno.EROFS, errno.EACCES, errno.EPERM)
_SWEPT: set[str] = set()            # the scratch folders' parents this process has swept


def scratch_folder(kind: str) -> tempfile.TemporaryDirectory:
    """A builder's temporary folder, `$TMPDIR/sewfmu_<kind>_<pid>_*`: named with its pid, so
    that the next build removes it where the builder was killed (kill -9 runs no cleanup)."""
    tmp = tempfile.gettempdir()
    if tmp not in _SWEPT:
        remove_dead_scratch(Path(tmp), re.compile(r"sewfmu_(build|native)_(?P<pid>\d+)_\w+"))
        _SWEPT.add(tmp)
    return tempfile.TemporaryDirectory(prefix=f"sewfmu_{kind}_{os.getpid()}_")


def refusal(dest: Path, err: OSError, rebuild: str) -> ScenarioError:
    """The one line of an FMU folder that cannot take a rebuilt FMU."""
    if err.errno in _READ_ONLY:
        return ScenarioError(f"{dest} is read-only: the FMUs there are out of date and cannot "
                             f"be rebuilt; set SEWFMU_FMU_DIR to a writable folder or rebuild "
                             f"them with {rebuild}")
    return ScenarioError(f"cannot write the rebuilt FMU into {dest}: {err.strerror or err}")


def writable(dest: Path, rebuild: str) -> None:
    """Make the folder, and refuse one that cannot be written before anything is built."""
    try:
        dest.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise refusal(dest, err, rebuild) from None
    if not os.access(dest, os.W_OK):
        raise refusal(dest, OSError(errno.EACCES, os.strerror(errno.EACCES)), rebuild)


def install(built: Path, dest: Path, name: str, rebuild: str) -> Path:
    """Put the FMU `built` into `dest` as NAME.fmu; return its path."""
    out = dest / f"{name}.fmu"
    staged = dest / f".{name}.fmu.{os.getpid()}"
    try:
        shutil.copy2(built, staged)
        os.replace(staged, out)
    except OSError as err:
        with contextlib.suppress(OSError):
            staged.unlink()
        raise refusal(dest, err, rebuild) from None
    remove_dead_scratch(dest, _STAGED)
    return out
