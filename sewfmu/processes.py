"""Every Python process sewfmu starts imports nothing from the current folder.

multiprocessing starts its fork server, its resource tracker and (spawn) each child as
`python -c CODE`, and such a Python puts the current folder first on sys.path: a numpy.py, or
a folder named sewfmu, where the user happened to `cd` was imported in every run's and every
sweep point's process (Python 3.11's forkserver is handed the parent's sys.path but ignores
it). `python -m` does the same. Python 3.11's safe path (-P, PYTHONSAFEPATH) puts nothing
there; a process started so passes -P on to its own (multiprocessing copies sys.flags), and a
forked child keeps its parent's sys.path.

Standard library only: the wings (runs/workers.py, interop/hosts.py) and the page
(sewfmu/app/jobs.py) use it alike. The parent's own sys.path is left as the user made it."""
from __future__ import annotations

import contextlib
import os
import sys
import threading

SAFE_PATH = "PYTHONSAFEPATH"
_lock = threading.RLock()      # one change of the environment at a time, within this process


@contextlib.contextmanager
def safe_path():
    """While it holds, a Python started by multiprocessing (its fork server, its resource
    tracker, a spawned child) puts nothing of the current folder on its sys.path: PYTHONSAFEPATH
    is set in this process's environment, which such a child inherits, and restored after."""
    with _lock:
        before = os.environ.get(SAFE_PATH)
        os.environ[SAFE_PATH] = "1"
        try:
            yield
        finally:
            if before is None:
                os.environ.pop(SAFE_PATH, None)
            else:
                os.environ[SAFE_PATH] = before


def python_command(*args: str) -> list[str]:
    """A command line that runs this Python with `args` (`-m module ...`) in safe-path mode."""
    return [sys.executable, "-P", *args]
