"""fit_evaluations.jsonl: the runs of a fit, each as the model's values at the data's times, so
that a fit run again into the same folder (after a kill, or with a larger budget) reads the runs
it made instead of making them again. least_squares asks for the same points in the same order
when given the same numbers, so a resumed fit follows the first one's path exactly.

The first line says what the record is of (the free parameters, the data's columns and a hash
of the data); a record of another fit is set aside, not mixed. A point's key is the sweep's
identity of it (the scenario's content with its settings, the FMUs' versions, the values), so a
changed scenario or FMU runs again. Numbers are written by json as repr: read back bit for bit.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

from sewfmu.scenarios.files.outputs import Record, claim, drop_torn_line, held, set_aside
from sewfmu.scenarios.runs.sweep import Point, settings_of

RECORD_FILE = "fit_evaluations.jsonl"


class FitRecord:
    def __init__(self, folder: Path, scenario, fmu_paths: dict, names: list[str], data):
        self.path = Path(folder) / RECORD_FILE
        self.names = list(names)
        self.settings = settings_of(scenario, fmu_paths)
        digest = hashlib.sha256(np.ascontiguousarray(data.time, dtype="f8").tobytes())
        for column, values in data.columns.items():
            digest.update(column.encode() + b"\0")
            digest.update(np.ascontiguousarray(values, dtype="f8").tobytes())
        self.header = {"record": "sewfmu fit", "free": self.names,
                       "columns": list(data.columns), "data": digest.hexdigest()}
        self.known: dict[str, tuple[dict | None, str]] = {}     # key -> (values, error)
        self._folder = contextlib.ExitStack()      # the folder is this fit's while it runs
        self._folder.enter_context(held(self.path.parent))
        try:
            if self.path.exists():
                drop_torn_line(self.path)              # a line torn by a kill
            self._read()
            fresh = not self.path.exists() or self.path.stat().st_size == 0
            self.file = Record(self.path)
            if fresh:
                self._write(self.header)
        except BaseException:
            self._folder.close()
            raise

    def key(self, x) -> str:
        return Point(0, tuple(zip(self.names, x))).identity(self.settings)

    def _read(self) -> None:
        if not self.path.exists():
            return
        with open(self.path, encoding="utf-8", errors="replace") as f:
            lines = f.read().splitlines()
        if not lines or _json(lines[0]) != self.header:
            if lines:
                aside = set_aside(self.path)
                claim(self.path.parent, [self.path.name])    # the new record, listed
                print(f"sewfmu: warning: {self.path} records another fit (other parameters, "
                      f"columns or data); moved to {aside.name}, and this fit starts a new "
                      f"record", file=sys.stderr)
            return
        for line in lines[1:]:
            entry = _json(line)
            if not isinstance(entry, dict) or not isinstance(entry.get("key"), str):
                continue                            # a torn or foreign line: run again
            values, error = entry.get("values"), str(entry.get("error") or "failed")
            if values is None:
                self.known[entry["key"]] = (None, error)
            elif isinstance(values, dict) and set(values) == set(self.header["columns"]):
                self.known[entry["key"]] = ({c: np.asarray(v, dtype=float)
                                             for c, v in values.items()}, "")

    def add(self, x, values: dict | None, error: str = "") -> None:
        key = self.key(x)
        self.known[key] = (values, error)
        self._write({"key": key, "x": list(x), "error": error,
                     "values": None if values is None else
                     {c: v.tolist() for c, v in values.items()}})

    def _write(self, entry: dict) -> None:
        self.file.write(json.dumps(entry) + "\n")

    def close(self) -> None:
        self.file.close()
        self._folder.close()


def _json(line: str):
    try:
        return json.loads(line)
    except ValueError:
        return None
