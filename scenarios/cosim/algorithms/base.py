"""What a co-simulation algorithm is to the run loop (scenarios/cosim/master.py): how one communication
step exchanges and steps, behind a narrow interface, with its typed settings
(scenarios/format/master_settings.py). The loop owns everything else: the instances' life, the clock,
the records, progress, interruption and failure reports.

An algorithm sees the run's System (scenarios/cosim/system.py): `instances` in dependency order,
`in_loops` (those on a feedback loop) and `passes` (exchanges needed to settle them).
"""
from __future__ import annotations

from typing import ClassVar


class Algorithm:
    name: ClassVar[str]
    Settings: ClassVar[type]
    # it takes steps again (with scenarios/cosim/rollback.py): the loop then tells the FMUs that
    # their state may be set back (noSetFMUStatePriorToCurrentPoint = false)
    rolls_back: ClassVar[bool] = False
    # it sizes its own steps: the loop gives it the time left instead of a step
    variable_step: ClassVar[bool] = False

    def __init__(self, settings):
        self.settings = settings

    def plan(self, system) -> None:
        """Before the instances' buffers are made: refuse a system it cannot run (one line), ask
        for the outputs it watches besides the recorded ones."""

    def start(self, system, step: float) -> None:
        """After initialization; `step` is experiment.step."""

    def advance(self, system, t: float, limit: float) -> float:
        """One communication step from t, of `limit` (fixed-step), or of at most `limit` (variable
        step); returns its length. A failed FMI call raises FmiCallError."""
        raise NotImplementedError

    def report(self, steps: int) -> tuple[dict, list[str]]:
        """What it did over the run's `steps` steps (summary.json's "coupling"), and warnings for
        the log."""
        return {}, []

    def close(self) -> None:
        """Free what it holds (saved FMU states); the instances are still alive."""
