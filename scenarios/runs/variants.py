"""The runs of one scenario: one, or one per value of its [compare] table, each with its summary
and provenance; what summary.json holds for them."""
from __future__ import annotations

from pathlib import Path

from sewfmu.scenarios.cosim import watchdog
from sewfmu.scenarios.cosim.interrupt import Interrupted
from sewfmu.scenarios.cosim.master import RunResult, run
from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import label_of
from sewfmu.scenarios.runs import accuracy
from sewfmu.scenarios.runs.provenance import provenance
from sewfmu.scenarios.runs.runner import summarize


def variants(scenario: Scenario) -> list[tuple[str, Scenario]]:
    """(label, scenario) for each run: one, or one per value of [compare]."""
    if not scenario.compare:
        return [("", scenario)]
    out = []
    param = scenario.compare["parameter"]
    for value in scenario.compare["values"]:
        sc = scenario.copy()
        sc.set_value(param, value, origin=f"{scenario.source}: compare")
        out.append((label_of(param, value), sc))
    return out


def run_variants(scenario: Scenario, fmu_dir: Path | None = None,
                 progress=None) -> list[tuple[str, RunResult, dict]]:
    """Run each variant of a scenario (one, or one per value of [compare]): (label, result,
    its summary with provenance) for each. `progress(label, done, total)` hears of the steps."""
    runs = []
    for label, sc in variants(scenario):
        paths = fmus_for(sc, fmu_dir)
        report_steps = None if progress is None else \
            (lambda done, total, label=label: progress(label, done, total))
        result = run(sc, paths, report_steps)
        summary = summarize(result)
        # interrupted now, the run finished is what is kept, not the estimate's coarser one
        after = "while estimating the coupling error, after the run"
        try:
            with watchdog.keeping_instead(result, after):
                found = accuracy.estimate(sc, result, summary, fmu_dir)
        except Interrupted as err:
            err.result, err.where = result, after
            raise
        if found is not None:
            summary["coupling_error"] = found
        runs.append((label, result, {**summary, "provenance": provenance(sc, paths)}))
    return runs


def summary_of_runs(scenario: Scenario, runs: list[tuple[str, RunResult, dict]]) -> dict:
    """What summary.json holds: the run's summary, or for [compare] each variant's by label."""
    if scenario.compare:
        return {"scenario": scenario.name, "compare": scenario.compare["parameter"],
                "runs": {label: s for label, _, s in runs}}
    return runs[0][2]
