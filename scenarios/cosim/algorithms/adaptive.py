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

from sewfmu.scenarios.cosim.algorithms.fixed_step import Jacobi
from sewfmu.scenarios.cosim.algorithms.iterative import rate_chains
from sewfmu.scenarios.cosim.fmi_calls import CosimError, FmiCallError
from sewfmu.scenarios.cosim.rollback import Rollback, declares
from sewfmu.scenarios.format.master_settings import AdaptiveSettings

GROWTH = 4.0
SHRINK = 0.25
SAFETY = 0.9
EVENT_FRACTION = 1.0 / 16
MIN_FRACTION = 1e-3
MAX_FACTOR = 16.0


class Adaptive(Jacobi):
    name = AdaptiveSettings.master
    Settings = AdaptiveSettings
    rolls_back = True
    variable_step = True

    def plan(self, system):
        # every Boolean output is watched for switches, recorded or not
        for inst in system.instances:
            for v in inst.md.modelVariables:
                if v.causality == "output" and v.type == "Boolean":
                    inst.want_output(v.name, f"{inst.name}.{v.name}")

    def start(self, system, step):
        fixed = [i for i in system.instances
                 if not declares(i, "canHandleVariableCommunicationStepSize")]
        if fixed:
            raise CosimError(f"{', '.join(f'{i.name} ({i.md.modelName})' for i in fixed)} takes "
                             f"only steps of one size (canHandleVariableCommunicationStepSize = "
                             f"false), and the adaptive master varies them: run it with a "
                             f"fixed-step master (jacobi, gauss-seidel, iterative)")
        self.h = step
        self.h_min, self.h_max = step * MIN_FRACTION, step * MAX_FACTOR
        self.h_event = step * EVENT_FRACTION
        self.rollback = Rollback(system.instances)
        self.chains = rate_chains(system.instances)
        self.scale = np.array([abs(c.instance.in_buf[c.value]) for c in self.chains])
        self.rejected = 0

    def advance(self, system, t, remaining):
        # the end is met by the step or by two halves, never by a sliver after a full step
        h = self.h if self.h < 0.5 * remaining else \
            remaining if self.h >= remaining else 0.5 * remaining
        self.rollback.save()
        switches = [list(inst.bool_buf) for inst in system.instances]
        while True:
            try:
                super().advance(system, t, h)
                error = self._error(self.rollback.inputs, h)
                switched = any(list(inst.bool_buf) != before
                               for inst, before in zip(system.instances, switches))
            except FmiCallError as err:
                # after Fatal no call may follow, not even a rollback
                if h <= self.h_min or err.fatal or any(i.failed for i in system.instances):
                    err.when = f"from t = {t:g} to {t + h:g} s"
                    raise
                error, switched = math.inf, False          # refused: try a shorter step
            if (error <= 1.0 or h <= self.h_min) and (not switched or h <= self.h_event):
                break
            self.rejected += 1
            self.rollback.restore()
            if switched and h > self.h_event:
                h = max(h * SHRINK, self.h_event)
            else:
                h = max(self.h_min, h * max(SHRINK, SAFETY * error ** (-1 / 3)))
        self.scale = np.maximum(self.scale, [abs(c.source.out_buf[c.output])
                                             for c in self.chains])
        growth = GROWTH if error == 0.0 else min(GROWTH, SAFETY * error ** (-1 / 3))
        self.h = min(self.h_max, max(self.h_min, h * max(growth, SHRINK)))
        return h

    def _error(self, inputs, h: float) -> float:
        """The largest extrapolation error of the step, relative to tolerance × amplitude."""
        worst = 0.0
        tolerance = self.settings.tolerance
        for j, c in enumerate(self.chains):
            values = inputs[c.position]
            predicted = values[c.value] + h * (values[c.rate] + (
                0.5 * h * values[c.second] if c.second is not None else 0.0))
            actual = c.source.out_buf[c.output]
            scale = max(self.scale[j], abs(actual), 1e-300)
            worst = max(worst, abs(actual - predicted) / (tolerance * scale))
        return worst

    def close(self):
        if getattr(self, "rollback", None) is not None:
            self.rollback.free()

    def report(self, steps):
        return {"steps": steps, "rejected_steps": self.rejected}, []
