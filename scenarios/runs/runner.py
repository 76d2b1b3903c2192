"""A scenario co-simulated: its FMUs found or built, the run, its key figures (summarize)."""
from __future__ import annotations

import warnings
from pathlib import Path

from sewfmu.scenarios.cosim.master import RunResult, run
from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.mechanisms.base import MissingRecord


def simulate(scenario: Scenario, fmu_dir: Path | None = None) -> RunResult:
    return run(scenario, fmus_for(scenario, fmu_dir))


def summarize(result: RunResult) -> dict:
    sc = result.scenario
    figures, units = {}, {}
    if sc.analysis:
        try:
            figures = sc.mechanism.summary_of_run(result)
        except MissingRecord as err:    # a narrowed record: the series still count
            warnings.warn(f"{sc.name}: the key figures are left out: {err}", stacklevel=2)
            figures = {}
        declared = sc.mechanism.figures
        units = {key: declared[key] for key in figures if key in declared}
    # what the master did: the iterative master's passes, the adaptive master's steps
    master = {f"master_{k}": v for k, v in result.coupling.items()}
    units = {"step": "s", "stop_time": "s", "wall_time_s": "s", **units}
    return {"scenario": sc.name, "master": sc.master, "step": sc.even_steps()[1],
            "stop_time": float(result.time[-1]), "wall_time_s": round(result.wall_time, 4),
            **master, **figures, "units": units}
