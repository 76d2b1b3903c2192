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
    """Rows of (time, every output the instances read each step), from which `arrays` gives the
    planned columns.

    A row is copied at once, not value by value: the Real outputs from the array the instances
    read them into (System.outputs), the Boolean ones from each instance's buffer that holds a
    recorded one. `plan` is a list of (instance, "real" or "bool", index in that instance's
    buffer), one per column; a Real output's place in `outputs` is the instance's out_at plus its
    index. `rows`: the number of rows the run will record, or None to grow as needed."""

    def __init__(self, columns: list[str], plan: list, outputs: np.ndarray, rows: int | None,
                 source: str, thinning: tuple[int, int, int] | None = None):
        self.columns = columns
        self.plan = plan
        self.source = source
        self.outputs = outputs
        flagged = list(dict.fromkeys(inst for inst, kind, _ in plan if kind == "bool"))
        self._flag_of = {inst: k for k, inst in enumerate(flagged)}
        # each of those instances' Boolean outputs as a numpy view of its buffer
        self._flags_now = [np.ctypeslib.as_array(inst.bool_buf) for inst in flagged]
        width = len(outputs) + sum(len(now) for now in self._flags_now)
        self.limit = max_rows(width)
        if rows is not None:
            check_memory(rows, width, source, thinning=thinning)
        self.grows = rows is None
        size = min(GROWN_ROWS, self.limit) if rows is None else rows
        self.times = np.empty(size)
        self.reals = np.empty((size, len(outputs)))
        self.flags = [np.empty((size, len(now)), now.dtype) for now in self._flags_now]
        self.length = 0

    def record(self, t: float) -> None:
        row = self.length
        if row == len(self.times):
            self._grow(t)
        self.times[row] = t
        self.reals[row] = self.outputs
        for rows, now in zip(self.flags, self._flags_now):
            rows[row] = now
        self.length = row + 1

    def _grow(self, t: float) -> None:
        if not self.grows or self.length >= self.limit:
            raise ScenarioError(f"{self.source}: the records reached {self.length:,} points at "
                                f"t = {t:g} s, the most this machine's memory holds: set "
                                f"experiment.record_every, or a looser tolerance")
        size = min(self.limit, 2 * len(self.times))
        self.times = np.resize(self.times, size)
        self.reals = np.resize(self.reals, (size, self.reals.shape[1]))
        self.flags = [np.resize(rows, (size, rows.shape[1])) for rows in self.flags]

    def truncate(self, length: int) -> None:
        """Forget the rows from `length` on (a rollback to the point they were at)."""
        self.length = length

    def arrays(self) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """(time, {column: values}), copies of the rows recorded (a Boolean as 0.0 or 1.0)."""
        rows = slice(0, self.length)
        columns = {}
        for column, (inst, kind, idx) in zip(self.columns, self.plan):
            if kind == "real":
                columns[column] = self.reals[rows, inst.out_at + idx].copy()
            else:
                columns[column] = self.flags[self._flag_of[inst]][rows, idx].astype(float)
        return self.times[rows].copy(), columns
