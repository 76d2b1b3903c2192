"""The masters by name (experiment.master), and `run`: a scenario run by its master.

The run loop, recording and rollback are Master's (scenarios/master.py); the algorithms are
beside it: Jacobi and Gauss–Seidel (fixed_step.py), iterative (coupling.py), adaptive
(adaptive.py).
"""
from __future__ import annotations

from pathlib import Path

from .adaptive import AdaptiveMaster
from .coupling import IterativeMaster
from .fixed_step import GaussSeidelMaster, JacobiMaster
from .format import Scenario
from .master import RunResult

MASTERS = {cls.name: cls for cls in (JacobiMaster, GaussSeidelMaster, IterativeMaster,
                                     AdaptiveMaster)}


def run(scenario: Scenario, fmu_paths: dict[str, Path], progress=None) -> RunResult:
    """Run the scenario with its experiment.master on these FMU files."""
    return MASTERS[scenario.master](scenario, fmu_paths).run(progress)
