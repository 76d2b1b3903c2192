"""A native FMU in fmpy, for the tests of tests/native: an instance whose log lines are kept
(the reason of a refusal comes through the logger), the reference its Python FMU carries, and
the rows of a DefaultExperiment."""
from __future__ import annotations

import csv
import io
import zipfile
from pathlib import Path

import numpy as np
from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.fmi3 import FMU3Slave, fmi3LogMessageCallback

LS_REF = "extra/org.fmi-standard.fmi-ls-ref"
ERROR = 3          # fmi2Error, fmi3Error


class Instance:
    """One instance of an FMU in fmpy, instantiated, with `lines`: what it logged (status,
    line) and `vr`: value reference by name."""

    def __init__(self, fmu: Path, fmi: int, unzipped: Path | None = None, name: str = "inst"):
        self.md = read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.lines: list[tuple[int, str]] = []
        where = str(unzipped) if unzipped else extract(str(fmu))
        kwargs = dict(guid=self.md.guid, unzipDirectory=where, instanceName=name,
                      modelIdentifier=self.md.coSimulation.modelIdentifier)
        if fmi == 2:
            self.fmu = FMU2Slave(**kwargs)
            self._callbacks = fmi2CallbackFunctions()
            self._callbacks.logger = fmi2CallbackLoggerTYPE(self._log2)
            self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
            # no fmpy.logging.addLoggerProxy: it keeps one logger for the whole process, so
            # the lines of two instances would meet in the last one's list; a sewfmu line is
            # the format itself (no '%'), so the fixed arguments are all there is to read
            self.fmu.instantiate(callbacks=self._callbacks, loggingOn=True)
        else:
            self.fmu = FMU3Slave(**kwargs)
            self._log = fmi3LogMessageCallback(self._log3)
            self.fmu.instantiate(loggingOn=True, logMessage=self._log)
        self.fmi = fmi

    @staticmethod
    def describe(fmu: Path):
        return read_model_description(str(fmu))

    def _log2(self, env, name, status, category, message):
        self.lines.append((status, message.decode()))

    def _log3(self, env, status, category, message):
        self.lines.append((status, message.decode()))

    def start(self, t0: float = 0.0) -> None:
        if self.fmi == 2:
            self.fmu.setupExperiment(startTime=t0)
            self.fmu.enterInitializationMode()
        else:
            self.fmu.enterInitializationMode(startTime=t0)
        self.fmu.exitInitializationMode()

    def outputs(self, names) -> list[float]:
        return list(self.fmu.getReal([self.vr[n] for n in names]) if self.fmi == 2
                    else self.fmu.getFloat64([self.vr[n] for n in names]))

    def set_real(self, name: str, value: float) -> None:
        if self.fmi == 2:
            self.fmu.setReal([self.vr[name]], [value])
        else:
            self.fmu.setFloat64([self.vr[name]], [value])

    def free(self) -> None:
        self.fmu.freeInstance()


def reference_of(python_fmu: Path, name: str) -> tuple[list[str], np.ndarray]:
    """(column names, rows) of the DefaultExperiment's output a Python FMU carries (fmi-ls-ref);
    Booleans as 0/1."""
    with zipfile.ZipFile(python_fmu) as archive:
        text = archive.read(f"{LS_REF}/{name}_out.csv").decode()
    rows = list(csv.reader(io.StringIO(text)))
    values = [[1.0 if x == "true" else 0.0 if x == "false" else float(x) for x in row]
              for row in rows[1:]]
    return rows[0], np.array(values)


def worst_relative(a: np.ndarray, b: np.ndarray) -> float:
    """The largest |a - b| of two columns relative to |b|, or to a millionth of the column's
    largest magnitude where b is smaller (a value that crosses zero); 0 where they are equal."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.shape != b.shape:
        return np.inf
    diff = np.abs(a - b)
    scale = np.maximum(np.abs(b), 1e-6 * np.max(np.abs(b), initial=0.0))
    return float(np.max(np.where(diff == 0, 0.0, diff / np.maximum(scale, 1e-300)),
                        initial=0.0))
