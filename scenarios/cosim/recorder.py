"""The run's one recorder: the recorded outputs of every communication point kept, in a numpy
array, within a share of the machine's memory.

A fixed-step run knows its number of rows before it starts (and is refused up front, with the
numbers, if they would not fit); an adaptive run does not, so its array grows as it goes, to at
most the rows that fit. A rollback takes rows back (`truncate`).
"""
from __future__ import annotations

import math
import os

import numpy as np

from sewfmu.scenarios.format.values import ScenarioError

# the records of one run may take this share of the memory available when it starts, and
# never more than RECORD_BUDGET (records beyond it are for a file, not for memory)
MEMORY_SHARE = 0.25
RECORD_BUDGET = 1 << 30
GROWN_ROWS = 4096          # the first size of a growing record


def _available_memory() -> int:
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return 8 << 30


def _budget() -> float:
    return min(RECORD_BUDGET, MEMORY_SHARE * _available_memory())


def max_rows(columns: int) -> int:
    """The most records of `columns` columns a run may keep."""
    return int(_budget() / ((columns + 1) * 8))


def check_memory(rows: int, columns: int, source: str, what: str = "records",
                 thinning: tuple[int, int, int] | None = None) -> None:
    """Refuse, up front and with the numbers, a run whose records would not fit in memory.
    `thinning` = (steps, record_every, rows kept at every step whatever record_every says): the
    record_every that would fit, if one would."""
    need = rows * (columns + 1) * 8
    if need <= _budget():
        return
    advice = "record fewer points (a larger experiment.record_every)"
    if thinning is not None:
        steps, every, dense = thinning
        room = max_rows(columns) - dense - 2
        fits = math.ceil(steps / room) if room > 0 else None
        advice = (f"record fewer points (experiment.record_every = {fits} or more, not "
                  f"{every}; the key figures are read from every step of the last revolution "
                  f"all the same)" if fits and fits > every else
                  "the last revolution alone, kept at every step, does not fit")
    raise ScenarioError(f"{source}: the {what} would take {need / 2**30:.3g} GiB ({rows:,} "
                        f"points × {columns + 1} columns), more than the "
                        f"{_budget() / 2**30:.3g} GiB a run may keep: {advice}, record fewer "
                        f"columns, or take a longer step")


class Recorder:
    """Rows of (time, the planned columns), read from the instances' output buffers.

    `plan` is a list of (instance, "real" or "bool", index in that instance's buffer), one per
    column; `outputs`, if given, is the array every instance reads its Real outputs into
    (System.outputs: an instance's start in it is its out_at). `rows`: the number of rows the
    run will record, or None to grow as needed.

    Where the columns are every output the instances read (a run records every output unless
    its scenario narrows `record`), a row is copied at once: the Real outputs from `outputs`, the
    Boolean ones from each instance's buffer (value by value the row took 3 µs of punch_drive's
    48 µs step: bench/floor.py). Otherwise value by value, so that the records never hold more
    than their columns."""

    def __init__(self, columns: list[str], plan: list, rows: int | None, source: str,
                 thinning: tuple[int, int, int] | None = None,
                 outputs: np.ndarray | None = None):
        self.columns = columns
        self.plan = plan
        self.source = source
        self.limit = max_rows(len(columns))
        if rows is not None:
            check_memory(rows, len(columns), source, thinning=thinning)
        self.grows = rows is None
        size = min(GROWN_ROWS, self.limit) if rows is None else rows
        self.times = np.empty(size)
        self.length = 0
        flagged = list(dict.fromkeys(inst for inst, kind, _ in plan if kind == "bool"))
        whole = outputs is not None \
            and sum(kind == "real" for _, kind, _ in plan) == len(outputs) \
            and all(sum(i is inst and kind == "bool" for i, kind, _ in plan) == inst.n_bool
                    for inst in flagged)
        if whole:
            self.outputs = outputs
            self.reals = np.empty((size, len(outputs)))
            self._flag_of = {inst: k for k, inst in enumerate(flagged)}
            # each of those instances' Boolean outputs as a numpy view of its buffer
            self._flags_now = [np.ctypeslib.as_array(inst.bool_buf) for inst in flagged]
            self.flags = [np.empty((size, len(now)), now.dtype) for now in self._flags_now]
            self.record = self._record_at_once
        else:
            self.data = np.empty((size, len(columns)))
            self._cells = [(inst.out_buf if kind == "real" else inst.bool_buf, idx)
                           for inst, kind, idx in plan]
            self.record = self._record_values
        self.at_once = whole

    def record(self, t: float) -> None:
        """Record the outputs read now as the row of time t."""
        raise NotImplementedError          # one of the two below, chosen in __init__

    def _record_at_once(self, t: float) -> None:
        row = self.length
        if row == len(self.times):
            self._grow(t)
        self.times[row] = t
        self.reals[row] = self.outputs
        for rows, now in zip(self.flags, self._flags_now):
            rows[row] = now
        self.length = row + 1

    def _record_values(self, t: float) -> None:
        row = self.length
        if row == len(self.times):
            self._grow(t)
        self.times[row] = t
        self.data[row] = [buf[idx] for buf, idx in self._cells]
        self.length = row + 1

    def _grow(self, t: float) -> None:
        if not self.grows or self.length >= self.limit:
            raise ScenarioError(f"{self.source}: the records reached {self.length:,} points at "
                                f"t = {t:g} s, the most this machine's memory holds: set "
                                f"experiment.record_every, or a looser tolerance")
        size = min(self.limit, 2 * len(self.times))
        self.times = np.resize(self.times, size)
        if self.at_once:
            self.reals = np.resize(self.reals, (size, self.reals.shape[1]))
            self.flags = [np.resize(rows, (size, rows.shape[1])) for rows in self.flags]
        else:
            self.data = np.resize(self.data, (size, len(self.columns)))

    def truncate(self, length: int) -> None:
        """Forget the rows from `length` on (a rollback to the point they were at)."""
        self.length = length

    def arrays(self) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """(time, {column: values}), copies of the rows recorded (a Boolean as 0.0 or 1.0)."""
        rows = slice(0, self.length)
        if not self.at_once:
            return (self.times[rows].copy(),
                    {c: self.data[rows, j].copy() for j, c in enumerate(self.columns)})
        columns = {}
        for column, (inst, kind, idx) in zip(self.columns, self.plan):
            if kind == "real":
                columns[column] = self.reals[rows, inst.out_at + idx].copy()
            else:
                columns[column] = self.flags[self._flag_of[inst]][rows, idx].astype(float)
        return self.times[rows].copy(), columns
