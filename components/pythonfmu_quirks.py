"""What an FMU on pythonfmu 0.7.0 or pythonfmu3 0.3.4 must do that the standard does not ask,
in one place (the host side's counterpart is scenarios/cosim/pythonfmu_host.py; docs/fmi.md says why).

- No exception may reach pythonfmu: it turns every one into Fatal and keeps the interpreter lock,
  after which a host may call nothing, not even FreeInstance. The getters and setters below
  answer every call, a wrong value reference with a log line; do_step returns False (Discard).
- pythonfmu's own getters and setters check every variable's type on every call: these look the
  getter up directly (the hot path of a co-simulation step).
- sys.path: pythonfmu puts the instance's resources folder first at every instantiation and never
  takes it out (forget_resources_path).
- Exit: pythonfmu 0.7.0 releases its interpreter state twice when a Python host exits with the
  library still loaded (scenarios/cosim/pythonfmu_host.py says how); in a Python host the FMU has its
  own library release that state at Python's exit, first (release_state_at_exit), so that a
  host that does not do it itself is safe too.
"""
from __future__ import annotations

import atexit
import ctypes
import glob
import math
import os
import sys
from typing import Any, Callable


class ExceptionFreeAccess:
    """The get and set calls of an FMU's layer, answered without an exception (SewSlave's)."""

    def get_reals(self, vrs) -> list[float]:
        # outputs (every step's call): read from the row of outputs through the table of their
        # places, the row made once per instant (SewSlave._fill_cache); a host asks for the
        # same references at every step, so their places are kept from the last call
        if type(vrs) is list and vrs == self._read_vrs:   # (pythonfmu passes lists)
            places = self._read_places
        else:
            try:
                slots = self._real_slots
                places = [slots[vr] for vr in vrs]
            except Exception:             # noqa: BLE001 - not outputs: answered below
                return self._get_real_values(vrs)
            self._read_vrs, self._read_places = list(vrs), places
        row = self._cache
        if row is None:
            row = self._fill_cache()
        return [row[i] for i in places]

    def _get_real_values(self, vrs) -> list[float]:
        try:
            return [float(self._real_getters[vr]()) for vr in vrs]
        except Exception:                 # noqa: BLE001 - an unknown reference: answered below
            return self.get_values(vrs, "Real")

    def get_values(self, vrs, kind: str) -> list:
        if kind == "Boolean":             # Boolean outputs: as get_reals
            try:
                slots = self._bool_slots
                places = [slots[vr] for vr in vrs]
            except Exception:             # noqa: BLE001 - not outputs: answered below
                pass
            else:
                row = self._cache
                if row is None:
                    row = self._fill_cache()
                return [bool(row[i]) for i in places]
        convert, missing = _CONVERT[kind]
        return [self._get(vr, kind, convert, missing) for vr in vrs]

    def _get(self, vr, kind, convert, missing):
        if self._kinds.get(vr) != kind:
            self._error_once(f"{self._call(kind, 0)}: no such variable (value reference {vr})")
            return missing
        try:
            return convert(self._getters[vr]())
        except Exception as err:          # noqa: BLE001
            self._error_once(f"value reference {vr}: {describe(err)}")
            return missing

    def set_reals(self, vrs, values) -> None:
        # inputs (every step's call): what each input's setter does, once for all of them
        try:
            names = [self._input_names[vr] for vr in vrs]
        except (KeyError, TypeError):     # not all inputs: each by its setter
            self._set_real_values(vrs, values)
            return
        inputs, fresh = self._inputs, self._set_since_step
        value = _NOTHING
        for name, value in zip(names, values):
            inputs[name] = value
            fresh.add(name)
        if value is not _NOTHING:     # what each setter does besides, once for the call
            self._held_stale = True
            self._elapsed = 0.0
            self._cache = None

    def _set_real_values(self, vrs, values) -> None:
        try:
            setters = [self._real_setters[vr] for vr in vrs]
        except (KeyError, TypeError):     # not a settable Real: answered below
            self.set_values(vrs, values, "Real")
            return
        for set_value, value in zip(setters, values):
            set_value(value)

    def set_values(self, vrs, values, kind: str) -> None:
        for vr, value in zip(vrs, values):
            setter = self._setters.get(vr)
            if setter is None or self._kinds.get(vr) != kind:
                name = self._names.get(vr, f"value reference {vr}")
                self._error(f"{self._call(kind, 1)}: {name} cannot be set this way "
                            f"(value {value!r} ignored)")
                continue
            setter(value)

    def _call(self, kind: str, which: int) -> str:
        return type(self).call_names.get(kind, ("Get", "Set"))[which]


_NOTHING = object()                  # set_reals: no value was set

# kind -> (conversion of a got value, the answer for a reference of another kind)
_CONVERT: dict[str, tuple[Callable[[Any], Any], Any]] = {
    "Real": (float, math.nan), "Integer": (int, 0), "Boolean": (bool, False), "String": (str, ""),
    "Int64": (int, 0), "UInt64": (int, 0),             # FMI 3.0 kinds no sewfmu variable has
}


def describe(err: Exception) -> str:
    """An exception as the one line a log needs: the model's own message, or what kind of
    failure it was."""
    text = str(err)
    # the models' own exceptions (parameters, assembly, step too long, chatter) say it for users
    if type(err).__module__.rpartition(".")[0] == __name__.rpartition(".")[0] and text:
        return text
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def forget_resources_path(resources: str | None) -> None:
    """pythonfmu puts the instance's resources folder first on sys.path at every instantiation
    (to import the FMU's script) and never takes it out: sys.path would grow with every instance,
    and the host's later imports would find the FMU's copies first. The FMU's modules are
    imported by now, so the entry is removed again."""
    if resources and resources in sys.path:
        sys.path.remove(resources)


# libraries whose release at exit is registered: process-level bookkeeping of pythonfmu's
# binary, not model state (an instance's model state lives on the instance)
_RELEASED_AT_EXIT: set[str] = set()


def release_state_at_exit(resources: str | None) -> None:
    """In a Python host, have this FMU's own library release pythonfmu's interpreter state at
    Python's exit, while everything is alive (what sewfmu's master does for the libraries it
    loads; the second release then finds nothing). Not in a host whose interpreter pythonfmu
    started itself (a C host): there the exit is pythonfmu's own, and clean."""
    if not resources or not _in_python_process():
        return
    for library in glob.glob(os.path.join(resources, os.pardir, "binaries", "*", "*.so")):
        path = os.path.realpath(library)
        if path in _RELEASED_AT_EXIT:
            continue
        try:        # the library this process has loaded, never a second copy of it
            handle = ctypes.CDLL(path, mode=os.RTLD_NOLOAD | os.RTLD_LAZY)
        except OSError:
            continue
        release = getattr(handle, "finalizePythonInterpreter", None)
        if release is not None:
            _RELEASED_AT_EXIT.add(path)
            atexit.register(release)


def _in_python_process() -> bool:
    try:
        return os.path.basename(os.readlink("/proc/self/exe")).startswith("python")
    except OSError:
        return False

