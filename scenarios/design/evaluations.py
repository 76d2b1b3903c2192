"""Runs at points of a design space, and their record.

An evaluation is one co-simulation of the scenario with the varied parameters set: its key
figures, or the reason it could not give them. Sequential methods run them in this process,
straight through the run loop and the analysis (cosim.master.run, runs.runner.summarize): the
FMUs stay extracted and loaded between runs, nothing is written but one line of the record, so
a point costs its co-simulation. A batch (a population of the global method) runs in the sweep
engine's worker processes (runs/workers.py), one point at a time each, kept for the whole study.

The record, evaluations.csv, gets every evaluation as it finishes: the parameters, the status,
every key figure, the reason where it failed, and the point's identity (the sweep's: the
scenario's content with its settings, the FMUs' versions, the point's values). A study run again
into the same folder finds its points there and does not run them again.

Statuses: "ok"; "infeasible" (the run refused or failed: a sewfmu Error, e.g. a value an FMU
refuses, a linkage that cannot be assembled, a diverging coupling: the same every time, so kept
for a rerun); "failed" (a worker process died or a task broke: tried again by a rerun).
"""
from __future__ import annotations

import contextlib
import csv
import io
import math
import re
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np

from sewfmu.errors import Error
from sewfmu.scenarios.cosim.master import run
from sewfmu.scenarios.files.outputs import (
    Record,
    claim,
    drop_torn_line,
    held,
    refuse_theirs,
    remove_debris,
    set_aside,
)
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.runs import progress
from sewfmu.scenarios.runs.runner import summarize
from sewfmu.scenarios.runs.sweep import WORKER_PRELOAD, Point, settings_of
from sewfmu.scenarios.runs.workers import WorkerPool

OK, INFEASIBLE, FAILED = "ok", "infeasible", "failed"
LOG_FILE = "evaluations.csv"
_KEY = re.compile(r"^[0-9a-f]{32}$")


@dataclass
class Evaluation:
    values: tuple[float, ...]              # the varied parameters, in their declared units
    status: str
    figures: dict = field(default_factory=dict)
    error: str = ""
    key: str = ""
    index: int = -1                        # its line in evaluations.csv
    reused: bool = False                   # found in the record, not run now


@contextlib.contextmanager
def study_folder(folder: Path | None, records: Sequence[str], outputs: Sequence[str]):
    """A study's output folder, the one rule of files/outputs.py: held from the first check to
    the last file; every name the study will write (`records`, appended run by run, and
    `outputs`, written at its end through outputs.replacing(folder, kept=records)) checked
    before the first run, a file sewfmu did not write refused in one line (the manifest's
    word, never a file's content); the records listed in the folder's manifest before they
    are written. No folder (out=None): nothing to hold."""
    if folder is None:
        yield
        return
    folder = Path(folder)
    with held(folder):
        refuse_theirs(folder, [*records, *outputs])
        folder.mkdir(parents=True, exist_ok=True)
        remove_debris(folder)
        claim(folder, records)
        yield


def progress_bar(enabled: bool, what: str, total: int | None):
    """A study's runs on one line of stderr, on a terminal only (runs/progress.py), or None."""
    return progress.bar(total, what, "run") if enabled else None


def one_line(err: BaseException) -> str:
    return " ".join(str(err).split()) or type(err).__name__


def evaluate_point(scenario: Scenario, fmu_paths: dict, names: Sequence[str],
                   values: Sequence[float], figures: Sequence[str]) -> tuple[str, dict, str]:
    """One co-simulation at a point: (status, key figures, reason). A sewfmu Error (a value
    refused, a run that fails or diverges) makes the point infeasible; anything else is a bug
    and goes up."""
    sc = scenario.copy()
    try:
        for name, value in zip(names, values):
            sc.set_value(name, float(value), origin="design point")
        summary = summarize(run(sc, fmu_paths))
    except Error as err:
        return INFEASIBLE, {}, one_line(err)
    return OK, {f: summary.get(f) for f in figures}, ""


class Evaluator:
    """The scenario at points of the space (values in the variables' declared units), each run
    once: from the record of an earlier run into the same folder, or now."""

    def __init__(self, scenario: Scenario, fmu_paths: dict, names: Sequence[str],
                 figures: Sequence[str], folder: Path | None = None, workers: int = 1,
                 bar=None):
        self.scenario, self.fmu_paths = scenario, dict(fmu_paths)
        self.names, self.figures = list(names), list(figures)
        self.workers = workers
        self.settings = settings_of(scenario, self.fmu_paths)
        self.log = EvaluationLog(Path(folder) / LOG_FILE, self.names, self.figures) \
            if folder is not None else None
        self.known: dict[str, Evaluation] = dict(self.log.rows) if self.log else {}
        self.history: list[Evaluation] = []        # this study's points, in the order asked
        self._asked: set[str] = set()
        self.computed = 0
        self.run_seconds = 0.0
        self.pool: WorkerPool | None = None
        self.bar = bar                             # a progress bar: update(1) a point asked

    def key(self, values: Sequence[float]) -> str:
        return Point(0, tuple(zip(self.names, values))).identity(self.settings)

    def __call__(self, values: Sequence[float]) -> Evaluation:
        values = tuple(float(v) for v in values)
        key = self.key(values)
        if key not in self.known:
            started = time.perf_counter()
            status, figures, error = evaluate_point(self.scenario, self.fmu_paths, self.names,
                                                    values, self.figures)
            self.run_seconds += time.perf_counter() - started
            self._record(Evaluation(values, status, figures, error, key))
        return self._asked_for(key)

    def batch(self, points: Sequence[Sequence[float]]) -> list[Evaluation]:
        """Several points, those not yet known run in the worker processes (in this process
        with one worker)."""
        points = [tuple(float(v) for v in p) for p in points]
        keys = [self.key(p) for p in points]
        todo = {k: p for k, p in zip(keys, points) if k not in self.known}
        if self.workers > 1 and len(todo) > 1:
            if self.pool is None:
                self.pool = WorkerPool(self.workers, WORKER_PRELOAD + [__name__])
            tasks = [(k, evaluate_point, (self.scenario, self.fmu_paths, self.names, p,
                                          self.figures)) for k, p in todo.items()]
            started = time.perf_counter()
            for k, answer in self.pool.run(tasks):
                if isinstance(answer, Exception):     # the worker died, or the task broke
                    evaluation = Evaluation(todo[k], FAILED, {}, one_line(answer), k)
                else:
                    evaluation = Evaluation(todo[k], *answer, key=k)
                self._record(evaluation)
            self.run_seconds += time.perf_counter() - started
        failed = {e.key: e for e in self.history if e.status == FAILED}
        return [self._asked_for(k) if k in self.known else failed.get(k) or self(p)
                for k, p in zip(keys, points)]

    def _record(self, evaluation: Evaluation) -> None:
        self.computed += 1
        if self.log is not None:
            evaluation.index = self.log.append(evaluation)
        if evaluation.status != FAILED:
            self.known[evaluation.key] = evaluation
        else:                                    # not known: a failed point is tried again
            self.history.append(evaluation)
            self._counted()

    def _asked_for(self, key: str) -> Evaluation:
        evaluation = self.known[key]
        if key not in self._asked:
            self._asked.add(key)
            self.history.append(evaluation)
            self._counted()
        return evaluation

    def _counted(self) -> None:
        if self.bar is not None:
            self.bar.update(1)

    def table(self, extra: dict[str, list] | None = None):
        """This study's evaluations as a numpy structured array: the parameters and figures
        (NaN where there is none), the status and the reason."""
        columns = self.names + self.figures + list(extra or {})
        width = max([len(e.error) for e in self.history] + [1])
        data = np.zeros(len(self.history), dtype=[(c, "f8") for c in columns]
                        + [("status", "U10"), ("error", f"U{width}")])
        for i, e in enumerate(self.history):
            for name, value in zip(self.names, e.values):
                data[name][i] = value
            for f in self.figures:
                v = e.figures.get(f)
                data[f][i] = v if isinstance(v, (int, float)) and v is not None else math.nan
            for c, values in (extra or {}).items():
                data[c][i] = values[i]
            data["status"][i], data["error"][i] = e.status, e.error
        return data

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
        if self.pool is not None:
            self.pool.close()
        if self.log is not None:
            self.log.close()


class EvaluationLog:
    """evaluations.csv: one line per evaluation, appended and flushed as each finishes."""

    def __init__(self, path: Path, names: list[str], figures: list[str]):
        self.path = path
        self.columns = ["index", *names, "status", *figures, "error", "key"]
        self.names, self.figures = names, figures
        self.rows: dict[str, Evaluation] = {}
        self.count = 0
        self._folder = contextlib.ExitStack()      # the folder is this study's while it runs
        self._folder.enter_context(held(path.parent))
        try:
            if path.exists() and path.stat().st_size:    # claimed empty: a new record
                drop_torn_line(path)
                self._read()
            fresh = not path.exists() or path.stat().st_size == 0
            self.file = Record(path)
        except BaseException:
            self._folder.close()
            raise
        if fresh:
            self._write(self.columns)

    def _read(self) -> None:
        with open(self.path, newline="", encoding="utf-8", errors="replace") as f:
            reader = csv.reader(f)
            header = next(reader, None)
            if header != self.columns:
                # another study's record (other parameters or figures): kept beside, not mixed
                aside = set_aside(self.path)
                claim(self.path.parent, [self.path.name])    # the new record, listed
                _warn(f"{self.path} records other parameters or figures; moved to {aside.name}, "
                      f"and this study starts a new record")
                return
            damaged = 0
            for line in reader:
                evaluation = self._parse(line)
                self.count += 1
                if evaluation is None:
                    damaged += 1
                elif evaluation.status != FAILED:
                    self.rows[evaluation.key] = evaluation
        if damaged:
            _warn(f"{self.path}: skipped {damaged} damaged line(s); those points run again")

    def _parse(self, line: list[str]) -> Evaluation | None:
        if len(line) != len(self.columns):
            return None
        row = dict(zip(self.columns, line))
        if not _KEY.match(row["key"]) or row["status"] not in (OK, INFEASIBLE, FAILED):
            return None
        try:
            values = tuple(float(row[n]) for n in self.names)
            figures = {f: _number(row[f]) for f in self.figures}
            index = int(row["index"])
        except ValueError:
            return None
        return Evaluation(values, row["status"], figures, row["error"], row["key"], index,
                          reused=True)

    def _write(self, cells: list) -> None:
        buffer = io.StringIO()
        csv.writer(buffer).writerow(cells)
        self.file.write(buffer.getvalue())

    def append(self, e: Evaluation) -> int:
        index = self.count
        self.count += 1
        figures = [_cell(e.figures.get(f)) for f in self.figures]
        self._write([index, *(repr(v) for v in e.values), e.status, *figures, e.error, e.key])
        return index

    def close(self) -> None:
        self.file.close()
        self._folder.close()


def _cell(value) -> str:
    """A figure as written: every digit (a rerun reads back the very number), empty for none."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return ""
    return repr(value)


def _number(text: str):
    if text == "":
        return None
    value = float(text)
    return int(value) if re.fullmatch(r"-?\d+", text) else value


def _warn(message: str) -> None:
    print(f"sewfmu: warning: {message}", file=sys.stderr)
