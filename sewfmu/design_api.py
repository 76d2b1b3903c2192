"""The design studies of the API (docs/design.md): sewfmu.optimize, sewfmu.fit and
sewfmu.sensitivity, each what its command does (sewfmu/design_cli.py), over the wing
scenarios/design/. A module of its own beside sewfmu/api.py (that one's size)."""
from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from sewfmu.api import _folder, load
from sewfmu.arguments import flag, one_line, workers_of
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import ScenarioError


def _refuse_fixed_and_varied(fixed, ranges, role: str, where: str) -> None:
    """A parameter given both a value (set=) and a range (vary=, free=): one line, before the
    FMUs are built (the range's shape is checked later, with its bounds)."""
    from sewfmu.scenarios.runs.sweep import (  # loaded on first use (start-up time)
        refuse_fixed_and_varied,
    )

    if isinstance(ranges, Mapping) and isinstance(fixed, Mapping):
        refuse_fixed_and_varied(fixed, ranges, role, where)


def _design_scenario(scenario, set):
    """The scenario, its FMU files (built where missing) and their modelDescriptions by
    instance: what a design study checks its ranges and data against before anything runs."""
    from sewfmu.scenarios.cosim.instances import extracted_fmu  # loaded on first use (start-up time)
    from sewfmu.scenarios.fmu_build.up_to_date import fmus_for  # loaded on first use (start-up time)

    sc = load(scenario, set)
    paths = fmus_for(sc)
    return sc, paths, {n: extracted_fmu(Path(paths[i.fmu]))[1] for n, i in sc.instances.items()}


@one_line
def optimize(scenario: str | Path | Scenario, vary: Mapping[str, Any], *,
             minimize: str | None = None, maximize: str | None = None,
             target: Mapping[str, Any] | None = None, constraints: list | None = None,
             set: Mapping[str, Any] | None = None, method: str = "local",
             workers: int | None = None, out: str | Path | None = None, plot: bool = False,
             max_evaluations: int | None = None, progress: bool = False,
             max_runs: int | None = None):
    """`sewfmu optimize`: vary {"inst.param": (lo, hi) or "LO..HI unit"}, one of
    minimize=FIGURE, maximize=FIGURE, target={FIGURE: value}; constraints ["FIGURE>=VALUE unit"].
    An Optimum (.best, .figures, .evaluations, .converged); with `out` evaluations.csv (a rerun
    there resumes), optimize.json, with `plot` convergence.png. `progress` shows a bar on the
    terminal. max_evaluations above `max_runs` (default 10,000, or SEWFMU_MAX_RUNS) is
    refused before any run."""
    from sewfmu.scenarios.design import optimize as design  # loaded on first use (start-up time)
    from sewfmu.scenarios.design import space  # loaded on first use (start-up time)

    out = _folder(out, "out")
    plot, progress = flag(plot, "plot"), flag(progress, "progress")
    workers = workers_of(workers)
    if constraints is not None and not isinstance(constraints, (str, tuple, list)):
        raise ScenarioError(f"constraints: expected a list of \"FIGURE>=VALUE unit\" texts or "
                            f"(figure, op, value) tuples, got {type(constraints).__name__}")
    _refuse_fixed_and_varied(set, vary, "varied", "--vary, vary=")
    sc, paths, described = _design_scenario(scenario, set)
    known = space.figures_of_scenario(sc)
    goal = space.goal_of(known, minimize, maximize, target)
    limits = space.constraints_of(known, constraints)
    variables = space.variables(sc, vary, described)
    if plot and out is None:
        raise ScenarioError("plot is a file: give out= a folder for it")
    return design.optimize(sc, paths, variables, goal, limits, method, workers, out, plot,
                           max_evaluations, progress, max_runs)


@one_line
def fit(scenario: str | Path | Scenario, data: Any, free: Mapping[str, Any], *,
        set: Mapping[str, Any] | None = None, out: str | Path | None = None,
        max_evaluations: int | None = None, progress: bool = False,
        max_runs: int | None = None):
    """`sewfmu fit`: data a CSV file (a `time` column, columns named like recorded outputs) or a
    structured array; free {"inst.param": (lo, hi)}. A Fit (.estimates, .standard_errors,
    .residuals); with `out` fit.json, fit.png and fit_evaluations.jsonl (a rerun there
    resumes). `progress` shows a bar on the terminal. A budget that allows more runs than
    `max_runs` (default 10,000, or SEWFMU_MAX_RUNS) is refused before any run."""
    from sewfmu.scenarios.design import fit as design  # loaded on first use (start-up time)
    from sewfmu.scenarios.design import space  # loaded on first use (start-up time)

    out = _folder(out, "out")
    progress = flag(progress, "progress")
    _refuse_fixed_and_varied(set, free, "free", "--free, free=")
    sc, paths, described = _design_scenario(scenario, set)
    measured = design.read_data(data)
    ends = {"experiment.stop_time", "experiment.revolutions"}
    sc = design.check_data(measured, sc, described, keep_end=bool(ends & {*(set or {})}))
    free = space.variables(sc, free, described, option="--free")
    return design.fit(sc, paths, free, measured, out, True, max_evaluations, progress,
                      max_runs)


@one_line
def sensitivity(scenario: str | Path | Scenario, vary: Mapping[str, Any], figures: list[str],
                *, set: Mapping[str, Any] | None = None, method: str = "sobol",
                samples: int | None = None, workers: int | None = None,
                out: str | Path | None = None, progress: bool = False,
                max_runs: int | None = None):
    """`sewfmu sensitivity`: SALib's Sobol or Morris indices of key figures over parameter
    ranges, the samples run as a sweep (resumable into `out`). A Sensitivity whose `table`
    ranks the parameters for each figure. More runs than `max_runs` (default 10,000, or
    SEWFMU_MAX_RUNS) are refused before a sample is drawn."""
    from sewfmu.scenarios.design import sensitivity as design  # loaded on first use (start-up time)
    from sewfmu.scenarios.design import space  # loaded on first use (start-up time)

    out = _folder(out, "out")
    progress, workers = flag(progress, "progress"), workers_of(workers)
    if not isinstance(figures, (str, tuple, list)):
        raise ScenarioError(f"figures: expected a key figure's name or a list of them, got "
                            f"{type(figures).__name__}")
    _refuse_fixed_and_varied(set, vary, "varied", "--vary, vary=")
    sc, _, described = _design_scenario(scenario, set)
    named = space.figures_named(space.figures_of_scenario(sc), figures)
    variables = space.variables(sc, vary, described)
    return design.sensitivity(sc, variables, named, space.figures_of_scenario(sc), method,
                              samples, workers, out, progress, max_runs)
