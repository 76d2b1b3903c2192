"""Iterative coupling: a communication step repeated until the values exchanged around a feedback
loop agree with those assumed.

The FMUs on a loop (here PunchBody and Fabric) take, within a step, an input that a partner
computes from their own motion (F2 from y). An input X that comes with a rate input X_dot on the
same FMU is an *interpolated input*: the master sets X to its value at t and X_dot so that it
reaches an assumed end value u at t + h (a linear interpolation; pythonfmu cannot take input
derivatives the FMI way). One pass steps the loop's FMUs and reads what their partners give at
t + h; the residual r = (given - assumed) says how wrong the assumption was. The FMUs are then put
back to t (their saved states) and stepped again with a better u, until |r| is within the
tolerance. Converged, each FMU has seen over the step the force that its partner's law gives for
its end state, linearly interpolated from the step's start: a trapezoidal coupling, without the
explicit coupling's stability limit.

The better u comes from an acceleration of the fixed-point iteration u <- u + r:
- Aitken: a dynamic under-relaxation, u <- u + ω·r with ω from the last two residuals;
- IQN-ILS (interface quasi-Newton, inverse Jacobian from least squares): the secant information of
  all iterations of the step, which for one interface value is the secant method.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from sewfmu.scenarios.cosim.algorithms.fixed_step import Jacobi
from sewfmu.scenarios.cosim.rollback import Rollback
from sewfmu.scenarios.cosim.system import reaches
from sewfmu.scenarios.format.master_settings import IterativeSettings

MAX_ITERATIONS = 25
INITIAL_RELAXATION = 0.5


class Acceleration:
    """Proposes the next assumed end values from the residuals of one step's iterations."""

    def __init__(self, kind: str):
        self.kind = kind          # one of IterativeSettings.ACCELERATIONS

    def start(self) -> None:
        self.us, self.rs = [], []
        self.omega = INITIAL_RELAXATION

    def next(self, u: np.ndarray, r: np.ndarray) -> np.ndarray:
        self.us.append(u.copy())
        self.rs.append(r.copy())
        if self.kind == "none" or len(self.rs) == 1:
            return u + (r if self.kind == "none" else self.omega * r)
        if self.kind == "aitken":
            dr = self.rs[-1] - self.rs[-2]
            denominator = float(dr @ dr)
            if denominator > 0.0:
                self.omega = -self.omega * float(self.rs[-2] @ dr) / denominator
            return u + self.omega * r
        # IQN-ILS: differences of residuals V and of outputs W (u + r) over the iterations; the
        # step that best cancels the residual in their span
        given = [uu + rr for uu, rr in zip(self.us, self.rs)]
        V = np.column_stack([self.rs[-1] - rk for rk in self.rs[:-1]])
        W = np.column_stack([given[-1] - gk for gk in given[:-1]])
        alpha, *_ = np.linalg.lstsq(V, -r, rcond=None)
        return given[-1] + W @ alpha


class RateChain(NamedTuple):
    """A connected input X that comes with its rate X_dot (and X_ddot) on the same FMU: the FMU
    extrapolates X within a step from them."""
    position: int          # of the FMU in the list the chains were found in
    instance: object       # the Instance
    value: int             # index of X in the FMU's connected inputs
    rate: int              # of X_dot
    second: int | None     # of X_ddot, if connected
    source: object         # the Instance that gives X
    output: int            # index of X in the source's Real outputs


def rate_chains(instances) -> list[RateChain]:
    """Every rate-paired input of the given FMUs (the iterative master interpolates them, the
    adaptive master measures their extrapolation error)."""
    chains = []
    for position, inst in enumerate(instances):
        names = [name for name, _, _ in inst.inputs]
        for k, (name, src, out) in enumerate(inst.inputs):
            if f"{name}_dot" in names:
                second = names.index(f"{name}_ddot") if f"{name}_ddot" in names else None
                chains.append(RateChain(position, inst, k, names.index(f"{name}_dot"), second,
                                        src, src.real_out.index(out)))
    return chains


def converged(r: np.ndarray, given: np.ndarray, tolerance: float) -> bool:
    return bool(np.all(np.abs(r) <= tolerance * np.maximum(1.0, np.abs(given))))


def finite(values: np.ndarray) -> bool:
    return math.isfinite(float(np.sum(values)))


class Iterative(Jacobi):
    """Jacobi, with every communication step around a feedback loop repeated until the values
    exchanged on it agree with those assumed (see the module docstring). Without a loop it is
    Jacobi."""

    name = IterativeSettings.master
    Settings = IterativeSettings
    rolls_back = True

    def start(self, system, step):
        loop = system.in_loops
        downstream = [i for i in system.instances if i not in loop
                      and any(reaches(i, member) for member in loop)]
        self.before = [i for i in system.instances if i not in loop and i not in downstream]
        self.loop, self.after = loop, downstream
        # the inputs interpolated over a step: those fed from the loop itself
        self.pairs = [c for c in rate_chains(loop) if c.source in loop]
        self.rollback = Rollback(loop) if self.pairs else None
        self.acceleration = Acceleration(self.settings.acceleration)
        self.iterations = 0            # passes over all steps
        self.unconverged: list[tuple[float, float]] = []   # (t, largest |residual|)

    def close(self):
        if getattr(self, "rollback", None) is not None:
            self.rollback.free()

    def advance(self, system, t, h):
        if self.rollback is None:
            return super().advance(system, t, h)
        for inst in self.before:
            inst.do_step(t, h)
        for inst in self.before:
            inst.exchange()
        self.rollback.save()
        start = np.array([c.instance.in_buf[c.value] for c in self.pairs])
        rate = np.array([c.instance.in_buf[c.rate] for c in self.pairs])
        assumed = start + rate * h          # the explicit coupling's own guess
        tolerance = self.settings.tolerance
        self.acceleration.start()
        for iteration in range(MAX_ITERATIONS):
            if iteration:
                self.rollback.restore(read_outputs=False)     # stepped and exchanged below
            for j, c in enumerate(self.pairs):
                c.instance.in_buf[c.rate] = (assumed[j] - start[j]) / h
            for inst in self.loop:
                inst.set_inputs()
                inst.do_step(t, h)
            self.exchange(system, self.loop)
            given = np.array([c.source.out_buf[c.output] for c in self.pairs])
            residual = given - assumed
            self.iterations += 1
            if converged(residual, given, tolerance):
                break
            if not finite(residual):
                break
            assumed = self.acceleration.next(assumed, residual)
        else:
            self.unconverged.append((t, float(np.max(np.abs(residual)))))
        for inst in self.after:
            inst.do_step(t, h)
        if self.after:
            self.exchange(system, system.instances)
        return h

    def report(self, steps):
        coupling = {"iterations_per_step": self.iterations / max(1, steps),
                    "unconverged_steps": len(self.unconverged)}
        warnings = [f"[WARNING] iterative coupling: the step from t = {t:g} s did not converge "
                    f"in its iterations (residual {size:.3g})" for t, size in self.unconverged[:5]]
        return coupling, warnings
