"""What an FMI call answers, on the host side, in one place: the statuses, the error a failed call
raises (sewfmu's own, whatever FMI version or library made the call), the log callback that keeps
the FMUs' messages for error reports, and the variable types in FMI 2.0's words.

The run loop (scenarios/cosim/master.py) turns a FmiCallError into the CosimError a user reads: the
instance, the phase, the time and the FMU's own last error message.
"""
from __future__ import annotations

import ctypes
from enum import IntEnum

from fmpy import calloc, free
from fmpy.fmi2 import (
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)

from sewfmu.errors import Error


class Status(IntEnum):
    """fmi2Status and fmi3Status: the same numbers (FMI 3.0 has no Pending)."""
    OK = 0
    WARNING = 1
    DISCARD = 2
    ERROR = 3
    FATAL = 4
    PENDING = 5


# Warning, the worst status a run goes on after, as a plain int for the per-step comparisons (an
# IntEnum member is looked up through the enum's metaclass at every use: 75 ns a comparison)
WARNING_LEVEL = int(Status.WARNING)


class FmiCallError(RuntimeError):
    """An FMI call that returned worse than Warning (or an instance that could not be made).

    After Discard or Error the instance may still be terminated and freed; after Fatal the
    standard allows no call at all (`fatal`)."""

    def __init__(self, call: str, status: int, instance=None, when: str | None = None):
        self.call = call
        self.status = Status(status) if 0 <= status <= 5 else status
        self.instance = instance          # the Instance (cosim/instances.py) it failed on
        self.when = when                  # "from t = … to … s", where the caller knows better
        name = self.status.name if isinstance(self.status, Status) else str(status)
        super().__init__(f"{call} returned {name}")

    @property
    def fatal(self) -> bool:
        return self.status >= Status.FATAL


class CosimError(Error, RuntimeError):
    """An FMU failed during the run; the message names the instance, the time and its log."""


class StepTimeout(CosimError):
    """A communication step ran longer than experiment.step_timeout (cosim/watchdog.py): the
    message names the instance, the FMI call, the time and the limit."""


def failed(status: int) -> bool:
    """Whether a status stops the run: worse than Warning."""
    return status > WARNING_LEVEL


def reason(lines: list[str], err: Exception | None) -> str:
    """The FMU's own error message if it logged one, else the failed call; on one line."""
    errors = [line.split(": ", 1)[-1] for line in lines if line.startswith("[ERROR]")]
    text = errors[-1] if errors else (lines[-1] if lines else str(err))
    return " ".join(text.split())


class LogCollector:
    """FMU log callback that keeps the messages (for error reports) instead of printing them."""

    def __init__(self):
        self.lines: list[str] = []
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        try:
            from fmpy.logging import addLoggerProxy  # fmpy: only when an FMU file is read
            addLoggerProxy(ctypes.byref(self.callbacks))
        except Exception:        # without the proxy, messages arrive unformatted: still useful
            pass

    def _log(self, component, instance_name, status, category, message):
        self.add(instance_name.decode("utf-8", "replace") if instance_name else "?", status,
                 message)

    def add(self, name: str, status: int, message: bytes | str | None) -> None:
        if isinstance(message, bytes):
            message = message.decode("utf-8", "replace")
        label = Status(status).name if 0 <= status <= 5 else status
        self.lines.append(f"[{label}] {name}: {message or ''}")

    def for_fmi3(self, name: str):
        """An FMI 3.0 log callback for the instance `name` (FMI 3.0 passes no instance name)."""
        return lambda environment, status, category, message: self.add(name, status, message)

    def for_instance(self, name: str) -> list[str]:
        return [line for line in self.lines if f"] {name}: " in line]

    def errors_of(self, name: str) -> list[str]:
        return [line for line in self.for_instance(name) if line.startswith("[ERROR]")]


def kind_of(variable) -> str:
    """A variable's type in FMI 2.0's words: Real, Integer, Boolean or String (FMI 3.0 names
    Float64, Int32 and their kin)."""
    return _KINDS.get(variable.type, variable.type)


_KINDS = {"Float64": "Real", "Float32": "Real",
          **{f"{sign}Int{bits}": "Integer" for sign in ("", "U") for bits in (8, 16, 32, 64)}}
