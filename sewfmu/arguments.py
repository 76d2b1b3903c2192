"""The public API's arguments checked at its doors (sewfmu/api.py): a
folder, a flag, a progress callback, and what the file system answers. Whatever a caller passes
(another type, None, a number, a path into /proc, a file that does not exist, a name too long),
what comes out is a sewfmu.Error of one line, never Python's TypeError or FileNotFoundError."""
from __future__ import annotations

import contextlib
import functools
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Callable

from sewfmu.errors import Error
from sewfmu.scenarios.files.outputs import OutputError
from sewfmu.scenarios.format.values import ScenarioError, exact, plain, short


def folder(value: Any, name: str) -> Path | None:
    """A folder argument (out=, fmu_dir=, dest=): None, or a path that can be one."""
    if value is None:
        return None
    if not isinstance(value, (str, Path)):
        raise ScenarioError(f"{name}: expected a folder path, got {type(value).__name__} "
                            f"{short(value)}")
    if "\x00" in str(value) or not str(value):
        raise ScenarioError(f"{name}: {short(str(value))} is not a path")
    path = Path(value)
    try:
        if path.exists() and not path.is_dir():
            raise ScenarioError(f"{name}: {path} exists and is not a folder")
    except OSError as err:          # a name too long, a loop of links, no permission
        raise OutputError(f"{name}: {path_text(value)} cannot be a folder: "
                          f"{err.strerror or err}") from None
    return path


def path_text(path: Any) -> str:
    """A path for a message, quoted: whole, so that the user finds the file (short() cut
    every path over 40 characters); only one longer than any path can be is cut, its
    length said."""
    text = str(path)
    return repr(text) if len(text) <= 4096 else f"{text[:200]!r}...{text[-60:]!r} " \
        f"({len(text):,} characters)"


def flag(value: Any, name: str) -> bool:
    """True or False (numpy's bools too): plot=1 or plot="no" is refused, not read as truth."""
    value = plain(value)
    if not isinstance(value, bool):
        raise ScenarioError(f"{name}: expected True or False, got {short(value)}")
    return value


def progress_of(value: Any, name: str = "progress") -> bool | Callable:
    """progress=: True (a bar on the terminal), False, or a function progress(done, total)."""
    return value if callable(value) else flag(value, f"{name} (True, False or a function)")


def callback(value: Any, name: str) -> Callable | None:
    """A function the API calls back (on_point=), or None."""
    if value is not None and not callable(value):
        raise ScenarioError(f"{name}: expected a function or None, got {short(value)}")
    return value


def one_line(function: Callable) -> Callable:
    """A public function whose file system errors come out as one OutputError line naming the
    path and the cause (a folder in /proc, a file that does not exist, no permission, a name too
    long): every refusal of the API is a sewfmu.Error."""
    @functools.wraps(function)
    def guarded(*args, **kwargs):
        try:
            return function(*args, **kwargs)
        except OSError as err:
            where = f"{path_text(err.filename)}: " if err.filename is not None else ""
            raise OutputError(f"{function.__name__}: {where}"
                              f"{' '.join(str(err.strerror or err).split())}") from None
    return guarded


def whole(value: Any, name: str, low: int | None = None, high: int | None = None) -> int:
    """A whole number, from low to high where given (numpy's ints too; not True, not 1.5)."""
    value = plain(value)
    if isinstance(value, bool) or not isinstance(value, int) \
            or (low is not None and value < low) or (high is not None and value > high):
        span = (f" from {low} to {high}" if low is not None and high is not None
                else f" >= {low}" if low is not None else "")
        raise ScenarioError(f"{name}: expected a whole number{span}, got {short(value)}")
    return value


@contextlib.contextmanager
def reading(name: str):
    """The API reading a caller's object (set=, grid=): whatever that object raises while it is
    read (a generator that fails, a __len__ of 10**30, a key whose __str__ raises) comes out as
    one ScenarioError line naming the argument, not as the object's own exception."""
    try:
        yield
    except Error:
        raise
    except Exception as err:            # noqa: BLE001 - anything a user's object raises
        try:
            said = " ".join(str(err).split())
        except Exception:               # noqa: BLE001 - an exception whose text raises too
            said = ""
        said = f"{said[:200]}..." if len(said) > 200 else said
        raise ScenarioError(f"{name}: reading it raised {type(err).__name__}"
                            f"{': ' + said if said else ''}") from None


def mapping(value: Any, name: str, expected: str,
            scalars: bool = False) -> dict[str, Any] | None:
    """A dict argument (set=, grid=) read once, under `reading`: None, or a plain dict of text
    keys (a key's own __str__ asked once, here) and the values exact (format/values.exact: a
    subclass of str or float as the plain value it holds); with `scalars` (set=) each value a
    number, true or false, or a text."""
    if value is None:
        return None
    if not isinstance(value, Mapping):
        raise ScenarioError(f"{name}: expected a dict of {expected}, got {type(value).__name__}")
    with reading(name):
        out = {}
        for key, item in value.items():
            key = str.__str__(key) if isinstance(key, str) else str(key)
            if not isinstance(key, str):
                raise ScenarioError(f"{name}: a key is no text ({type(key).__name__})")
            out[key] = exact(item)
            if scalars and not isinstance(out[key], (bool, int, float, str)):
                raise ScenarioError(f"{name} {key}: a value is a number, true or false, or a "
                                    f"text with its unit (\"955 rpm\"), got {short(item)}")
        return out
