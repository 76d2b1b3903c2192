"""What a killed sewfmu process left in an output folder (files/outputs.py): its temporaries,
`.NAME.sewfmu-PID.tmp` and the staging folder `.outputs.sewfmu-PID.partial`, removed by the next
command into the folder, only where sewfmu writes and only of its own kinds."""
from __future__ import annotations

import contextlib
import os
import re
import shutil
import stat
from pathlib import Path

from sewfmu.scenarios.files import manifest
from sewfmu.scenarios.files.manifest import MANIFEST

# sewfmu's own temporaries, `.NAME.sewfmu-PID.tmp|partial`: only these are ever cleaned up
_DEBRIS = re.compile(r"^\..+\.sewfmu-(\d+)\.(tmp|partial)$")


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:         # someone else's process: alive
        return True
    return True


def remove_debris(folder: Path, recursive: bool = False) -> list[Path]:
    """Remove the temporaries that dead processes of this host left where sewfmu writes: at the
    folder's top level and (`recursive`) in the folders its manifest lists as made by sewfmu,
    never in a user's own folder. Only sewfmu's own kinds go: a staging folder
    `.outputs.sewfmu-PID.partial`, a file `.NAME.sewfmu-PID.tmp` of a name sewfmu writes there
    (its manifest, a name the manifest lists, a sweep point's pending `.point-...`); return
    them."""
    folder = Path(folder)
    if not folder.is_dir():
        return []
    entries = manifest.read(folder)
    places = [folder] + [folder / e.name for e in entries.values() if recursive
                         and e.kind == manifest.FOLDER and manifest.matches(folder, e)]
    removed = []
    for place in places:
        for entry in list(place.glob(".*")):
            if _debris(folder, entry, entries):
                if entry.is_dir():
                    shutil.rmtree(entry, ignore_errors=True)
                else:
                    with contextlib.suppress(OSError):
                        entry.unlink()
                removed.append(entry)
    return removed


def _debris(folder: Path, entry: Path, entries: dict) -> bool:
    match = _DEBRIS.match(entry.name)
    if not match or int(match.group(1)) == os.getpid() or alive(int(match.group(1))):
        return False
    try:
        mode = os.lstat(entry).st_mode
    except OSError:
        return False
    written = entry.name[1:entry.name.rindex(".sewfmu-")]
    if match.group(2) == "partial":
        return written == "outputs" and stat.S_ISDIR(mode)
    inside = entry.parent.relative_to(folder).as_posix()
    name = written if inside == "." else f"{inside}/{written}"
    return stat.S_ISREG(mode) and (written == MANIFEST or name in entries
                                   or (inside == "." and entry.name.startswith((".point-", "..point-"))))
