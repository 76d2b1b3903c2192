"""The co-simulation beside the monolithic solution of the same physics (`sewfmu compare`): the
key figures of both, their differences, and the monolithic solver at a looser tolerance."""
from __future__ import annotations

from pathlib import Path

from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import ScenarioError
from sewfmu.scenarios.runs.runner import simulate, summarize


def comparison_rows(cosim: dict, monolithic: dict,
                    figures: dict) -> list[tuple[str, object, object, object]]:
    """(figure, co-simulation, monolithic, difference) for every key figure of `figures`."""
    rows = []
    for key in figures:
        a, b = cosim.get(key), monolithic.get(key)
        diff = a - b if isinstance(a, (int, float)) and isinstance(b, (int, float)) else None
        rows.append((key, a, b, diff))
    return rows


def monolithic_summary(scenario: Scenario, rtol: float | None = None) -> tuple[dict, float]:
    """Key figures of the scenario's monolithic solution (tight tolerances, or `rtol`) and its
    wall time; its mechanism solves it (`monolithic_figures`)."""
    if not (scenario.mechanism and scenario.mechanism.monolithic):
        raise ScenarioError(f"{scenario.source}: no monolithic solution for analysis "
                            f"{scenario.analysis!r}")
    return scenario.mechanism.monolithic_figures(scenario, rtol)


def compare(scenario: Scenario, fmu_dir: Path | None = None,
            rtol: float | None = None) -> list[tuple]:
    """Rows (figure, co-simulation, monolithic solution, difference), plus the wall times.
    With `rtol`, the monolithic solver also runs at that tolerance, and each row is (figure,
    co-simulation, monolithic at rtol, tight monolithic, error of each against the tight)."""
    result = simulate(scenario, fmu_dir)
    cosim = summarize(result)
    ref, ref_wall = monolithic_summary(scenario)
    if rtol is None:
        rows = comparison_rows(cosim, ref, scenario.mechanism.figures)
        rows.append(("wall_time_s", round(result.wall_time, 3), round(ref_wall, 3), None))
        return rows
    loose, loose_wall = monolithic_summary(scenario, rtol)
    rows = []
    for key, a, b, _ in comparison_rows(cosim, ref, scenario.mechanism.figures):
        c = loose.get(key)
        numbers = all(isinstance(x, (int, float)) for x in (a, b, c))
        rows.append((key, a, c, b, a - b if numbers else None, c - b if numbers else None))
    rows.append(("wall_time_s", round(result.wall_time, 3), round(loose_wall, 3),
                 round(ref_wall, 3), None, None))
    return rows
