"""A native model (native/models/) loaded on its own, without the FMI runtime: compiled with the
machine's C compiler into a small library and called through ctypes, so that a property test can
hold its numbers against the Python model's, call for call (docs/architecture.md: the twins)."""
from __future__ import annotations

import ctypes
import hashlib
import shutil
import subprocess
import tempfile
from pathlib import Path

from tests.paths import REPO

NATIVE = REPO / "native"
_DOUBLES = ctypes.POINTER(ctypes.c_double)
_BUILD = _DOUBLES, _DOUBLES, ctypes.c_char_p
_INIT = _DOUBLES, _DOUBLES, _DOUBLES, _DOUBLES
_ADVANCE = _DOUBLES, _DOUBLES, _DOUBLES, _DOUBLES, ctypes.c_double, ctypes.c_double, ctypes.c_char_p
_OUTPUTS = _DOUBLES, _DOUBLES, _DOUBLES, _DOUBLES, ctypes.c_double, _DOUBLES, ctypes.c_char_p
WHY = 1024


class SewModel(ctypes.Structure):
    """native/runtime/sew_model.h's SewModel."""
    _fields_ = [("name", ctypes.c_char_p), ("n_derived", ctypes.c_int), ("n_state", ctypes.c_int),
                ("build", ctypes.CFUNCTYPE(ctypes.c_int, *_BUILD)),
                ("initialize", ctypes.CFUNCTYPE(None, *_INIT)),
                ("advance", ctypes.CFUNCTYPE(ctypes.c_int, *_ADVANCE)),
                ("outputs", ctypes.CFUNCTYPE(ctypes.c_int, *_OUTPUTS))]


class ModelError(RuntimeError):
    """A call the native model refused (-1), with its reason."""


def _array(values, size=None):
    values = list(values)
    return (ctypes.c_double * max(1, size or len(values)))(*values)


class NativeModel:
    """One native model with its parameters built: initialize / advance / outputs as Python
    calls on lists of floats."""

    def __init__(self, library: ctypes.CDLL, name: str, params):
        self._lib = library          # kept alive while the model is
        self.model = SewModel.in_dll(library, f"SEW_MODEL_{name}")
        self.p = _array(params)
        self.derived = _array([], self.model.n_derived)
        why = ctypes.create_string_buffer(WHY)
        if self.model.build(self.p, self.derived, why) != 0:
            raise ModelError(why.value.decode())

    def initialize(self, u) -> list[float]:
        state = _array([], self.model.n_state)
        self.model.initialize(self.p, self.derived, _array(u), state)
        return list(state)[:self.model.n_state]

    def advance(self, state, u, t: float, h: float) -> list[float]:
        s = _array(state, self.model.n_state)
        why = ctypes.create_string_buffer(WHY)
        if self.model.advance(self.p, self.derived, s, _array(u), t, h, why) != 0:
            raise ModelError(why.value.decode())
        return list(s)[:self.model.n_state]

    def outputs(self, state, u, t: float, n_row: int) -> list[float]:
        row = _array([], n_row)
        why = ctypes.create_string_buffer(WHY)
        s = _array(state, self.model.n_state)
        if self.model.outputs(self.p, self.derived, s, _array(u), t, row, why) != 0:
            raise ModelError(why.value.decode())
        return list(row)[:n_row]


_LIBRARIES: dict[tuple[str, ...], ctypes.CDLL] = {}


def library(*sources: str) -> ctypes.CDLL:
    """The models in native/models/<source>.c (and what they include), compiled once per
    process into one library (cached by the sources' contents)."""
    if sources not in _LIBRARIES:
        files = [NATIVE / "models" / f"{s}.c" for s in sources]
        # the headers too: a change to one alone must not reuse a library built before it
        headers = sorted(NATIVE.glob("*/*.h"))
        digest = hashlib.sha256(b"".join(f.read_bytes() for f in [*files, *headers])
                                ).hexdigest()[:16]
        folder = Path(tempfile.gettempdir()) / f"sewfmu-twins-{digest}"
        lib = folder / "twins.so"
        if not lib.exists():
            folder.mkdir(exist_ok=True)
            compiler = shutil.which("gcc") or shutil.which("cc")
            staged = folder / f"twins.{id(files)}.so"
            subprocess.run([compiler, "-O2", "-shared", "-fPIC", "-std=c99", "-ffp-contract=off",
                            f"-I{NATIVE / 'runtime'}", f"-I{NATIVE / 'models'}",
                            *map(str, files), "-o", str(staged), "-lm"], check=True)
            staged.replace(lib)
        _LIBRARIES[sources] = ctypes.CDLL(str(lib))
    return _LIBRARIES[sources]


def native_model(name: str, params, *sources: str) -> NativeModel:
    """The native model SEW_MODEL_<name> from native/models/<sources>.c, built for params (the
    values in the order of the Python parameter dataclass's fields)."""
    return NativeModel(library(*sources), name, [float(v) for v in params])
