"""The fixed-step masters: Jacobi (every FMU steps from the same values, then all exchange) and
Gauss–Seidel (consumers first, each fed its sources' values of the step start). They differ in
how one communication step exchanges and steps; the run loop is Master's (scenarios/master.py).
"""
from __future__ import annotations

from .format import ScenarioError
from .master import Master


class JacobiMaster(Master):
    name = "jacobi"

    def exchange_and_step(self, units, t, h):
        for unit in units:
            unit.do_step(t, h)
        self.exchange(units)

    def exchange(self, units) -> None:
        """Every input from its source's outputs now (dependency order: along a chain
        feedthrough settles in one pass; around a loop in one more pass per unit on it)."""
        for unit in units:
            unit.pull_inputs()
            unit.read_outputs()
        self.settle_loops()

    def settle_loops(self) -> None:
        for _ in range(self.passes - 1):
            for unit in self.in_loops:
                if unit.pull_changed_inputs():    # unchanged: the outputs read stand
                    unit.read_outputs()


class GaussSeidelMaster(Master):
    name = "gauss-seidel"

    def _plan(self, units):
        # around a loop the consumers-first sweep hands an FMU its partner's values of t + h
        # (extrapolated from t) as if they were of t: on punch_split a one-step lead of the
        # fabric's force that makes the punch chatter (7 contacts instead of 1)
        if self.in_loops:
            raise ScenarioError(f"{self.scenario.source}: experiment.master = \"gauss-seidel\" "
                                f"cannot run the feedback loop of "
                                f"{', '.join(u.name for u in self.in_loops)}; use \"jacobi\", "
                                f"\"iterative\" or \"adaptive\"")
        return super()._plan(units)

    def exchange_and_step(self, units, t, h):
        for unit in reversed(units):      # consumers first: see the module docstring
            unit.pull_inputs()
            unit.do_step(t, h)
            unit.read_outputs()
