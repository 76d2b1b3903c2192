"""What a Python host must do around pythonfmu's and pythonfmu3's binaries, in one place (the FMU
side's counterpart is components/pythonfmu_quirks.py; docs/fmi.md says why, for other hosts).

- Exit: pythonfmu 0.7.0 keeps its interpreter state in a static shared_ptr, which the C++ exit
  handlers destroy, and which the library's unload function (finalizePythonInterpreter) releases
  once more when the process exits after them: a write into freed memory that aborts the process
  at exit ("corrupted double-linked list") or not, depending on the heap's layout (seen with four
  FMU types and scipy loaded). Called first, at Python's exit, that function releases the state
  while all is alive and leaves the static empty, so neither later step has anything to free;
  then the library is unloaded.
- sys.path: pythonfmu puts the FMU's resources folder first on sys.path at every instantiation
  and leaves it there: later imports of this process would find the FMU's copies (its pythonfmu
  lacks the binaries the builder needs) and sys.path would grow with every instance. The FMU has
  imported its code by then, so sys.path is put back.
"""
from __future__ import annotations

import atexit
import contextlib
import importlib
import sys

# Every FMU library this process loaded (one dlopen per instance), released at exit while the
# interpreter is still alive (see above).
_LIBRARIES: list = []


def release_at_exit(fmu) -> None:
    """Have the library of an fmpy FMU object released at Python's exit (see above)."""
    _LIBRARIES.append(fmu.dll)


@atexit.register
def _release_libraries() -> None:
    from fmpy import freeLibrary  # fmpy: only when an FMU file is read

    while _LIBRARIES:
        library = _LIBRARIES.pop()
        try:
            release_state = getattr(library, "finalizePythonInterpreter", None)
            if release_state is not None:
                release_state()
            freeLibrary(library._handle)
        except Exception:           # noqa: BLE001 - at exit, nothing to report to
            pass


@contextlib.contextmanager
def instantiating(keep_bytecode: bool = False, carried: str | None = None):
    """Around an instantiation: whatever it does to sys.path is undone (see above); with
    `keep_bytecode` (an FMU extracted into sewfmu's cache, scenarios/cosim/fmu_cache.py) the code it
    imports leaves its bytecode there even where PYTHONDONTWRITEBYTECODE is set, so that the next
    run, in any process, does not compile it again. `carried`: the package of pythonfmu the FMU
    carries a copy of ("pythonfmu", "pythonfmu3"); the installed one is imported first, so that
    the FMU's copy (without binaries) never takes its place in sys.modules, where a build made
    later in this process would find it (a run no longer imports the builder first)."""
    if carried and carried not in sys.modules:
        importlib.import_module(carried)
    saved, writes = list(sys.path), sys.dont_write_bytecode
    if keep_bytecode:
        sys.dont_write_bytecode = False
    try:
        yield
    finally:
        sys.path[:] = saved
        sys.dont_write_bytecode = writes
