"""A scenario run in another FMI host (libcosim, ecos) from its SSP export, beside sewfmu's own
run of it: `sewfmu crosscheck`."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from sewfmu.scenarios.cosim.master import RunResult
from sewfmu.scenarios.files.outputs import replacing
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.interop.hosts import run_in_host
from sewfmu.scenarios.interop.ssp_export import export
from sewfmu.scenarios.mechanisms.base import figures_of
from sewfmu.scenarios.runs.results import write_csv, write_json
from sewfmu.scenarios.runs.runner import simulate, summarize


def _end_at(time: np.ndarray, columns: dict, stop: float):
    """A fixed-step host cannot shorten its last step: end its record at the scenario's stop
    time, interpolating the last row (as sewfmu's master ends exactly there)."""
    if time[-1] <= stop + 1e-12:
        return time, columns
    keep = int(np.searchsorted(time, stop, side="right"))
    new_time = np.append(time[:keep], stop)
    out = {}
    for name, values in columns.items():
        out[name] = np.append(values[:keep], np.interp(stop, time, values))
    return new_time, out


def crosscheck(scenario: Scenario, host: str, out_dir: Path, fmu_dir: Path | None = None):
    """Run the exported scenario in another host; write its results.csv and summary.json;
    return rows (figure, sewfmu, host, difference) and the two summaries."""
    with replacing(out_dir) as staging:
        ssp = export(scenario, staging / f"{scenario.name}.ssp", fmu_dir)
        own = simulate(scenario, fmu_dir)
        time, columns, wall = run_in_host(host, ssp, scenario, list(own.columns),
                                          staging / "results.csv")
        time, columns = _end_at(time, columns, scenario.end_time())
        other = RunResult(scenario, time, columns, wall, units=own.units)
        write_csv(other, staging / "results.csv")
        mine, theirs = summarize(own), summarize(other)
        theirs["host"] = host
        write_json(theirs, staging / "summary.json")
    rows = []
    for key, value in figures_of(mine).items():
        b = theirs.get(key)
        diff = value - b if isinstance(value, (int, float)) and isinstance(b, (int, float)) \
            else None
        rows.append((key, value, b, diff))
    return rows
