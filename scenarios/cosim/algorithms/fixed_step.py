"""The fixed-step masters: Jacobi and Gauss–Seidel. They differ in how one communication step
exchanges and steps; the run loop is scenarios/cosim/master.py's.

- Jacobi: every FMU steps from the values at t; then, in dependency order, each FMU's inputs are
  set from its sources' outputs at t + h (a direct-feedthrough FMU's outputs follow its new inputs
  before the next FMU reads them).
- Gauss–Seidel: FMUs step one after another, each fed its sources' newest outputs just before
  its own step. The sweep runs against the data flow (consumers first): along a chain every FMU
  still starts its step from inputs at t, as the contract above requires, while a feedback signal
  reaches the FMU that steps after its source fresh, at t + h (the point of Gauss–Seidel). The
  textbook producers-first sweep would hand each consumer values of t + h as if they were of t:
  FMUs that extrapolate their inputs then run one step early per link, a first-order error
  (1.15° of crank angle at h = 1e-4 s on punch_drive, two links).
"""
from __future__ import annotations

from sewfmu.scenarios.cosim.algorithms.base import Algorithm
from sewfmu.scenarios.cosim.fmi_calls import WARNING_LEVEL
from sewfmu.scenarios.format.master_settings import GaussSeidelSettings, JacobiSettings
from sewfmu.scenarios.format.values import ScenarioError


class Jacobi(Algorithm):
    name = JacobiSettings.master
    Settings = JacobiSettings

    def advance(self, system, t, h):
        # inst.do_step(t, h) written out: this loop runs every step (a call less per instance).
        # Its compiled twin, with exchange's, is cosim/jacobi_loop.c: a change here goes there
        instances = system.instances
        for inst in instances:
            inst.board[2] = inst.at + 1           # guardian.WHERE: doStep
            status = inst._do_step(t, h)
            if status > WARNING_LEVEL:
                inst.check("doStep", status)
        self.exchange(system, instances)
        return h

    @staticmethod
    def exchange(system, instances) -> None:
        """Every input from its source's outputs now (dependency order: along a chain
        feedthrough settles in one pass; around a loop in one more pass per instance on it)."""
        for inst in instances:
            inst.exchange()
        if system.in_loops:
            system.settle_loops()


class GaussSeidel(Algorithm):
    name = GaussSeidelSettings.master
    Settings = GaussSeidelSettings

    def plan(self, system):
        # around a loop the consumers-first sweep hands an FMU its partner's values of t + h
        # (extrapolated from t) as if they were of t: on punch_split a one-step lead of the
        # fabric's force that makes the punch chatter (7 contacts instead of 1)
        if system.in_loops:
            raise ScenarioError(f"{system.scenario.source}: experiment.master = "
                                f"\"gauss-seidel\" cannot run the feedback loop of "
                                f"{', '.join(i.name for i in system.in_loops)}; use \"jacobi\", "
                                f"\"iterative\" or \"adaptive\"")

    def advance(self, system, t, h):
        for inst in reversed(system.instances):      # consumers first: see the module docstring
            inst.pull_inputs()
            inst.do_step(t, h)
            inst.read_outputs()
        return h
