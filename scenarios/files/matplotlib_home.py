"""matplotlib for sewfmu's pictures, its own files kept out of the user's home.

matplotlib makes its configuration folder and writes its font cache, the first time it draws,
under the home folder (~/.config/matplotlib, ~/.cache/matplotlib): files outside the folders a
user named. Every picture sewfmu draws gets matplotlib through `pyplot()`, which first points
MPLCONFIGDIR (matplotlib's one setting for both) at sewfmu's cache (files/cache_root.py: the
folder MATPLOTLIB in its SUBFOLDER), or, where the cache is turned off or cannot be written, at a
temporary folder removed when the process ends. A user's own MPLCONFIGDIR is kept, and so is a
matplotlib that was loaded before sewfmu drew (the user's, configured as they chose); a
matplotlibrc of the user's in their configuration folder is still read (MATPLOTLIBRC names it).
"""
from __future__ import annotations

import atexit
import os
import shutil
import sys
import tempfile
from pathlib import Path

from sewfmu.scenarios.files.cache_root import SUBFOLDER, configured_root

SETTING = "MPLCONFIGDIR"
MATPLOTLIB = "matplotlib"           # the folder in the cache's SUBFOLDER


def keep_out_of_home() -> Path | None:
    """Point matplotlib's files at sewfmu's folder, before matplotlib is loaded; the folder, or
    None where the user chose one or matplotlib is loaded already."""
    if os.environ.get(SETTING) or "matplotlib" in sys.modules:
        return None
    folder = _cache_folder() or _temporary_folder()
    rc = _users_rc()
    if rc is not None and not os.environ.get("MATPLOTLIBRC"):
        os.environ["MATPLOTLIBRC"] = str(rc)
    os.environ[SETTING] = str(folder)
    return folder


def pyplot():
    """matplotlib.pyplot on the Agg backend (files, no window), its own files where
    keep_out_of_home puts them."""
    keep_out_of_home()
    import matplotlib  # matplotlib: only when drawing

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib: only when drawing

    return plt


def _cache_folder() -> Path | None:
    root = configured_root()
    if root is None:
        return None
    folder = root / SUBFOLDER / MATPLOTLIB
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    return folder if os.access(folder, os.W_OK | os.X_OK) else None


def _temporary_folder() -> Path:
    folder = Path(tempfile.mkdtemp(prefix=f"sewfmu-matplotlib-{os.getpid()}-"))
    atexit.register(shutil.rmtree, folder, True)
    return folder


def _users_rc() -> Path | None:
    """The matplotlibrc matplotlib would have read from the user's configuration folder."""
    xdg = os.environ.get("XDG_CONFIG_HOME")
    base = Path(xdg) if xdg and os.path.isabs(xdg) else Path.home() / ".config"
    rc = base / "matplotlib" / "matplotlibrc"
    return rc if rc.is_file() else None
