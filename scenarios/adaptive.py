"""The adaptive master: communication steps that grow where the exchanged signals are smooth and
shrink where a component switches, every rejected step rolled back with the FMUs' saved states.

Each FMU extrapolates its inputs within a step from their values and rates at its start (the
Taylor polynomial of ξ, ξ', ξ''; of F2, F2'). What that extrapolation misses is the error the
co-simulation makes, so the master measures it after each step: for every input X that comes with
its rate X_dot (and X_ddot), the source's X at t + h against X + X_dot·h (+ X_ddot·h²/2), relative
to the tolerance times the signal's amplitude so far. A step whose error is above 1 is taken
again, shorter; the next step is sized from the error (third order: h·(1/err)^(1/3), at most
4 times longer). A step in which a component's Boolean output changes (the punch lands on the
fabric or leaves it) is taken again in quarters until it is at most EVENT_FRACTION of the nominal
step: the recorded samples then bracket every switch closely, so that figures read from the
samples (the onset where y crosses zero, the loss where F2 reaches zero) are as exact as the
motion, and steps between switches are as long as the tolerance allows. The samples are not
uniform; the analyses read them by time and crank angle.

`experiment.step` is the first step; steps stay within [step/1000, 16·step].
"""
from __future__ import annotations

import math

import numpy as np
from fmpy.fmi1 import FMICallException

from .coupling import SavedStates, rate_chains
from .fixed_step import JacobiMaster
from .format import ScenarioError
from .master import RunResult, max_rows

GROWTH = 4.0
SHRINK = 0.25
SAFETY = 0.9
EVENT_FRACTION = 1.0 / 16
MIN_FRACTION = 1e-3
MAX_FACTOR = 16.0


class AdaptiveMaster(JacobiMaster):
    name = "adaptive"

    def open(self) -> None:
        super().open()
        nominal = self.scenario.step
        self.h = nominal
        self.h_min, self.h_max = nominal * MIN_FRACTION, nominal * MAX_FACTOR
        self.h_event = nominal * EVENT_FRACTION
        self.t = 0.0
        self.states = SavedStates(self.instances)
        self.chains = rate_chains(self.instances)
        self.scale = np.array([abs(c.unit.in_buf[c.value]) for c in self.chains])
        self.rejected = 0
        self.dense_t = self.scenario.last_revolution_start() - nominal if self.every > 1 else 0.0
        self.max_rows = max_rows(len(self.columns))
        self.times: list[float] = [0.0]
        self.rows: list[np.ndarray] = [self._data[0].copy()]

    def _plan(self, units):
        # every Boolean output is watched for switches, recorded or not
        for unit in units:
            for v in unit.md.modelVariables:
                if v.causality == "output" and v.type == "Boolean":
                    unit.want_output(v.name, f"{unit.name}.{v.name}")
        return super()._plan(units)

    def finished(self) -> bool:
        return self.t >= self.stop * (1 - 1e-12)

    def progress_point(self) -> tuple[int, int]:
        return int(1000 * self.t / self.stop), 1000

    def step(self) -> None:
        t = self.t
        # the end is met by the step or by two halves, never by a sliver after a full step
        remaining = self.stop - t
        h = self.h if self.h < 0.5 * remaining else \
            remaining if self.h >= remaining else 0.5 * remaining
        self.states.save()
        inputs = [list(unit.in_buf) for unit in self.instances]
        switches = [list(unit.bool_buf) for unit in self.instances]
        while True:
            try:
                self.exchange_and_step(self.instances, t, h)
                error = self._error(inputs, h)
                switched = any(list(unit.bool_buf) != before
                               for unit, before in zip(self.instances, switches))
            except FMICallException as err:
                # after fmi2Fatal no call may follow, not even a rollback
                if h <= self.h_min or any(unit.failed for unit in self.instances):
                    raise self._failure(err, f"from t = {t:g} to {t + h:g} s") from None
                error, switched = math.inf, False          # refused: try a shorter step
            if (error <= 1.0 or h <= self.h_min) and (not switched or h <= self.h_event):
                break
            self.rejected += 1
            self._roll_back(inputs)
            if switched and h > self.h_event:
                h = max(h * SHRINK, self.h_event)
            else:
                h = max(self.h_min, h * max(SHRINK, SAFETY * error ** (-1 / 3)))
        self.t = t + h if t + h < self.stop * (1 - 1e-12) else self.stop
        if self.watch is not None:
            self.watch.check(self.t)
        self.k += 1
        self.scale = np.maximum(self.scale, [abs(c.source.out_buf[c.output])
                                             for c in self.chains])
        growth = GROWTH if error == 0.0 else min(GROWTH, SAFETY * error ** (-1 / 3))
        self.h = min(self.h_max, max(self.h_min, h * max(growth, SHRINK)))
        # experiment.record_every thins the records, but never in the last revolution
        if self.k % self.every == 0 or self.finished() or self.t >= self.dense_t:
            if len(self.rows) >= self.max_rows:
                raise ScenarioError(
                    f"{self.scenario.source}: the adaptive master's records reached "
                    f"{len(self.rows):,} points at t = {self.t:g} s, the most this machine's "
                    f"memory holds: set experiment.record_every, or a looser tolerance")
            row = np.empty(len(self.columns))
            self._record(row[None, :], 0)
            self.times.append(self.t)
            self.rows.append(row)

    def _error(self, inputs, h: float) -> float:
        """The largest extrapolation error of the step, relative to tolerance × amplitude."""
        worst = 0.0
        tolerance = self.scenario.coupling_tolerance()
        for j, c in enumerate(self.chains):
            values = inputs[c.position]
            predicted = values[c.value] + h * (values[c.rate] + (
                0.5 * h * values[c.second] if c.second is not None else 0.0))
            actual = c.source.out_buf[c.output]
            scale = max(self.scale[j], abs(actual), 1e-300)
            worst = max(worst, abs(actual - predicted) / (tolerance * scale))
        return worst

    def _roll_back(self, inputs) -> None:
        self.states.restore()
        for unit, values in zip(self.instances, inputs):
            unit.in_buf[:] = values
            unit.read_outputs()

    def close(self) -> None:
        if getattr(self, "states", None) is not None:
            self.states.free()
        super().close()

    def result(self) -> RunResult:
        return RunResult(self.scenario, np.array(self.times),
                         {c: np.array([row[j] for row in self.rows])
                          for j, c in enumerate(self.columns)},
                         0.0, self.log.lines,
                         {"steps": self.k, "rejected_steps": self.rejected}, self.units)
