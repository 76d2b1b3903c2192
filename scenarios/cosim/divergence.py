"""Divergence of a co-simulation: caught and named, never written as results.

An explicit (Jacobi) coupling of a stiff feedback loop is unstable above a step size (punch_split:
about 2·m/b2, 1.5 ms); its exchanged values then grow without bound (a punch pressed metres into
the fabric, forces of 1e117 N) while every FMU still computes. Only values exchanged around a
feedback loop can diverge this way: along a chain each FMU is stable with any input it is given.
So after each step the master looks at the inputs of the FMUs on a loop, with two criteria:

- the declared range: an input (or the output feeding it) outside the min/max its FMU declares
  (sewfmu's FMUs declare the physical range of every input) has left what the mechanism can do;
- growth, for FMUs that declare no range: a signal whose largest magnitude grows tenfold from
  one window of steps to the next, STREAK windows in a row (10^4 in 128 steps), is not physics
  of a mechanism that is driven at a steady speed: it is the coupling's instability.

Either stops the run with one line naming the time, the signal, the FMUs of the loop and the way
out (a shorter step, or the iterative or adaptive master).
"""
from __future__ import annotations

import math

from sewfmu.errors import Error


class Diverged(Error, RuntimeError):
    """The exchanged values of a feedback loop left their range or grew without bound."""


WINDOW = 32          # steps per window of the growth criterion
GROWTH = 10.0        # growth of a window's largest magnitude over the previous window's
STREAK = 4           # windows in a row


def declared_bound(text) -> float | None:
    """A variable's declared min or max as a number; None where it declares none."""
    try:
        return float(text) if text is not None else None
    except ValueError:
        return None


class DivergenceWatch:
    """Watches the inputs of the FMUs on feedback loops (Instance objects of cosim/instances.py)."""

    def __init__(self, loop_instances, step: float, explicit: bool = True,
                 parameters: dict[str, dict] | None = None):
        """`explicit`: the master couples the loop explicitly (Jacobi, Gauss-Seidel), so a
        signal that runs away may be its instability; otherwise (iterative, adaptive) it is the
        mechanism's. `parameters`: the values the scenario sets, by instance, to name them."""
        self.step = step
        self.explicit = explicit
        self.names = ", ".join(u.name for u in loop_instances)
        self.given = ", ".join(f"{u.name}.{k} = {v:g}" if isinstance(v, float) else
                               f"{u.name}.{k} = {v}"
                               for u in loop_instances
                               for k, v in (parameters or {}).get(u.name, {}).items())
        self.signals = []            # (instance, index in in_buf, input name, source text, lo, hi, unit)
        for inst in loop_instances:
            for k, (name, src, out) in enumerate(inst.inputs):
                dst_var, src_var = inst.variables[name], src.variables[out]
                lo = _tighter(max, declared_bound(dst_var.min), declared_bound(src_var.min))
                hi = _tighter(min, declared_bound(dst_var.max), declared_bound(src_var.max))
                self.signals.append((inst, k, name, f"{src.name}.{out}", lo, hi,
                                     dst_var.unit or src_var.unit or ""))
        self.window_max = [0.0] * len(self.signals)
        self.previous = [0.0] * len(self.signals)
        self.streak = [0] * len(self.signals)
        self.count = 0

    def check(self, t: float) -> None:
        """After the step that ended at t: raise Diverged if a watched input diverges."""
        for j, (inst, k, name, source, lo, hi, unit) in enumerate(self.signals):
            value = inst.in_buf[k]
            if (lo is not None and value < lo) or (hi is not None and value > hi) \
                    or not math.isfinite(value):
                self._raise(t, f"{inst.name}.{name} = {value:.6g} {unit} (from {source}) "
                               f"left its declared range [{bound_text(lo, '-inf')}, "
                               f"{bound_text(hi, 'inf')}] {unit}", out_of_range=True)
            magnitude = abs(value)
            if magnitude > self.window_max[j]:
                self.window_max[j] = magnitude
        self.count += 1
        if self.count % WINDOW:
            return
        for j, signal in enumerate(self.signals):
            now, before = self.window_max[j], self.previous[j]
            self.streak[j] = self.streak[j] + 1 if before > 0.0 and now > GROWTH * before else 0
            if self.streak[j] >= STREAK:
                inst, _, name, source, *_ = signal
                self._raise(t, f"{inst.name}.{name} (from {source}) grew {now / before:.3g}-fold "
                               f"in {WINDOW} steps, {STREAK} times in a row (now {now:.3g})")
            self.previous[j], self.window_max[j] = now, 0.0

    def _raise(self, t: float, what: str, out_of_range: bool = False) -> None:
        given = f" (set here: {self.given})" if self.given else ""
        if not self.explicit:
            raise Diverged(f"at t = {t:.6g} s {what}: the mechanism goes beyond what its FMUs "
                           f"declare, with the coupling of ({self.names}) converged at every "
                           f"step: a parameter drives it there{given}")
        if out_of_range:
            raise Diverged(f"the co-simulation diverged at t = {t:.6g} s: {what}: either the "
                           f"explicit coupling of the feedback loop ({self.names}) is unstable at "
                           f"a step of {self.step:.6g} s (a shorter experiment.step, or "
                           f"experiment.master = \"iterative\" or \"adaptive\", tells), or a "
                           f"parameter drives the mechanism there{given}")
        raise Diverged(f"the co-simulation diverged at t = {t:.6g} s: {what}; the explicit "
                       f"coupling of the feedback loop ({self.names}) is unstable at a step of "
                       f"{self.step:.6g} s: take a shorter experiment.step, or "
                       f"experiment.master = \"iterative\" or \"adaptive\"")


def _tighter(pick, a, b):
    return b if a is None else a if b is None else pick(a, b)


def bound_text(bound, unbounded: str) -> str:
    return unbounded if bound is None else f"{bound:g}"
