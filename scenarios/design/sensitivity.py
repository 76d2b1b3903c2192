"""What matters: SALib's global sensitivity analysis of key figures over parameter ranges.

SALib draws the samples (Sobol: Saltelli's scheme, N·(D+2) runs for D parameters, first and
total order; Morris: N trajectories of D+1 runs, elementary effects), the sweep engine runs
them (runs/sweep.py: worker processes or one, each finished point in points.jsonl, so a study
run again into its folder resumes), and SALib turns the figures into indices with their 95 %
confidence intervals (bootstrap). The sampling's seed is fixed: the same study draws the same
points, which is what lets it resume.

A sample that fails, or where a figure has no value, takes its whole group out of that
figure's analysis (a Sobol block of D+2 runs, a Morris trajectory): the estimators need whole
groups. sensitivity.json says how many groups each figure used.
"""
from __future__ import annotations

import json
import math
import re
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sewfmu.extras import require
from sewfmu.scenarios.design.space import Variable
from sewfmu.scenarios.files.outputs import write_atomic
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import ScenarioError, plain
from sewfmu.scenarios.runs import budget as runs_budget
from sewfmu.scenarios.runs.sweep import Point, run_sweep, seconds_of_points

METHODS = ("sobol", "morris")
DEFAULT_SAMPLES = {"sobol": 64, "morris": 16}
MORRIS_LEVELS = 4
SEED = 1
CONFIDENCE = 0.95
_GROUP = {"sobol": "Saltelli block", "morris": "trajectory"}
INDICES = {"sobol": ("S1", "S1_conf", "ST", "ST_conf"),
           "morris": ("mu", "mu_star", "mu_star_conf", "sigma")}


@dataclass
class Sensitivity:
    """Sensitivity indices: `table` (numpy structured array, a row per figure and parameter,
    ranked within each figure), `indices` ({figure: {parameter: {index: value}}})."""
    scenario: str
    method: str
    table: Any
    indices: dict
    runs: int
    failed: int
    out: Path | None = None
    summary: dict = field(default_factory=dict)          # what sensitivity.json holds

    def to_pandas(self):
        return require("pandas", "to_pandas()").DataFrame(self.table)

    def __repr__(self) -> str:
        return (f"<sewfmu.Sensitivity {self.scenario} ({self.method}): {self.runs} runs, "
                f"{len(self.indices)} figures>")


def sample(method: str, problem: dict, samples: int) -> np.ndarray:
    if method == "sobol":
        sobol = require("SALib.sample.sobol", "a Sobol study")
        return sobol.sample(problem, samples, calc_second_order=False, seed=SEED)
    morris = require("SALib.sample.morris", "a Morris study")
    return morris.sample(problem, samples, num_levels=MORRIS_LEVELS, seed=SEED)


def analyze(method: str, problem: dict, X: np.ndarray, Y: np.ndarray) -> dict[str, np.ndarray]:
    if method == "sobol":
        sobol = require("SALib.analyze.sobol", "a Sobol study")
        si = sobol.analyze(problem, Y, calc_second_order=False, conf_level=CONFIDENCE,
                           print_to_console=False, seed=SEED)
    else:
        morris = require("SALib.analyze.morris", "a Morris study")
        si = morris.analyze(problem, X, Y, conf_level=CONFIDENCE, print_to_console=False,
                            num_levels=MORRIS_LEVELS, seed=SEED)
    return {k: np.asarray(si[k], dtype=float) for k in INDICES[method]}


def sensitivity(scenario: Scenario, variables: list[Variable], figures: list[str],
                units: dict[str, str], method: str = "sobol", samples: int | None = None,
                workers: int | None = None, out: Path | None = None,
                progress: bool = False, max_runs: int | None = None) -> Sensitivity:
    """Sample, run (a sweep), analyze; with `out`, sensitivity.json, the sweep's files and a
    bar chart per figure (sensitivity_FIGURE.png), in place of the last study's (the sweep's
    one rule of files: runs/sweep.py). The runs are counted from the samples before SALib draws
    them: over the bound on runs (runs/budget.py) refused, else said with a time estimate."""
    if method not in METHODS:
        raise ScenarioError(f"--method: one of {', '.join(METHODS)}, got {method!r}")
    samples = DEFAULT_SAMPLES[method] if samples is None else plain(samples)
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 2:
        raise ScenarioError(f"--samples: a whole number >= 2, got {samples!r}")
    if method == "sobol" and samples & (samples - 1):       # Saltelli's scheme needs it
        raise ScenarioError(f"--samples: Sobol sampling takes a power of 2, got {samples}")
    group = len(variables) + (2 if method == "sobol" else 1)
    what, per_run = f"sensitivity {scenario.name}", runs_budget.seconds_per_run(scenario)
    parallel = runs_budget.cpu_workers(workers)
    runs_budget.check(samples * group, what, runs_budget.max_runs(max_runs),
                      f"--samples {samples} × {group} runs a {_GROUP[method]}", per_run,
                      parallel)
    names = [v.name for v in variables]
    problem = {"num_vars": len(variables), "names": names,
               "bounds": [[v.lo, v.hi] for v in variables]}
    X = sample(method, problem, samples)
    points = [Point(i, tuple(zip(names, map(float, row)))) for i, row in enumerate(X)]
    # each sample's own run (a varied speed changes its length), said before the first
    per_run = runs_budget.mean_seconds(seconds_of_points(scenario, points))
    made: dict[str, Any] = {}
    pictures = [f"sensitivity_{_file_name(f)}.png" for f in figures]

    def analysis(staging: Path, rows: list[dict]) -> None:
        """The indices, written beside the sweep's table in one piece with it; a study whose
        samples give no indices leaves the table alone (its points say why)."""
        try:
            made["result"], table_rows = _analyzed(scenario, variables, figures, units, method,
                                                   samples, problem, X, rows, out)
        except ScenarioError as err:
            made["error"] = err
            return
        if out is not None:
            summary = made["result"].summary
            write_atomic(staging / "sensitivity.json", lambda f: json.dump(summary, f, indent=2))
            from sewfmu.scenarios.design.plots import sensitivity_bars  # matplotlib: to draw

            for f, picture in zip(figures, pictures):
                sensitivity_bars(staging / picture, f, units.get(f, ""), method,
                                 [r for r in table_rows if r["figure"] == f])

    with tempfile.TemporaryDirectory(prefix="sewfmu_sensitivity_") as scratch:
        folder = Path(out) if out is not None else Path(scratch)
        run_sweep(scenario, points, folder, workers=workers, progress=progress,
                  outputs=["sensitivity.json", *pictures] if out is not None else [],
                  finish=analysis,
                  announce=lambda: runs_budget.announce(what, samples * group, per_run,
                                                        parallel, shown=progress))
    if "error" in made:
        raise made["error"]
    return made["result"]


def _analyzed(scenario: Scenario, variables: list[Variable], figures: list[str],
              units: dict[str, str], method: str, samples: int, problem: dict, X: np.ndarray,
              rows: list[dict], out: Path | None) -> tuple[Sensitivity, list[dict]]:
    """SALib's indices of each figure from the sweep's rows, and the table's rows."""
    names = problem["names"]
    failed = sum(r["status"] != "ok" for r in rows)
    if failed == len(rows):
        raise ScenarioError(f"every sample failed ({rows[0].get('error')})"
                            + (f"; see {Path(out) / 'sweep.csv'}" if out is not None else ""))
    group = len(variables) + (2 if method == "sobol" else 1)
    indices, used, table_rows = {}, {}, []
    for figure in figures:
        Y = np.array([_number(r.get(figure)) if r["status"] == "ok" else math.nan
                      for r in rows])
        whole = np.isfinite(Y).reshape(-1, group).all(axis=1)
        used[figure] = int(whole.sum())
        if used[figure] < 2:
            raise ScenarioError(f"{figure}: fewer than two whole groups of samples have it "
                                f"({failed} of {len(rows)} samples failed)")
        keep = np.repeat(whole, group)
        Xf, Yf = X[keep], Y[keep]
        if np.ptp(Yf) == 0.0:       # a figure that does not move: no variance to share out
            si = {k: np.zeros(len(names)) for k in INDICES[method]}
        else:
            si = analyze(method, problem, Xf, Yf)
        ranked = np.argsort(-si["ST" if method == "sobol" else "mu_star"], kind="stable")
        indices[figure] = {}
        for rank, k in enumerate(ranked, 1):
            entry = {key: _finite(si[key][k]) for key in INDICES[method]}
            indices[figure][names[k]] = entry
            table_rows.append({"figure": figure, "parameter": names[k], "rank": rank, **entry})
    table = _table(table_rows, method)
    summary = {
        "scenario": scenario.name, "source": scenario.source, "method": method,
        "samples": samples, "runs": len(rows), "failed": failed, "seed": SEED,
        "confidence_level": CONFIDENCE,
        "vary": {v.name: {"low": v.lo, "high": v.hi, "unit": v.unit} for v in variables},
        "figures": {f: {"unit": units.get(f, ""), "groups_used": used[f],
                        "groups": len(rows) // group, "indices": indices[f],
                        "ranking": list(indices[f])} for f in figures},
    }
    return Sensitivity(scenario.name, method, table, indices, len(rows), failed,
                       Path(out) if out is not None else None, summary), table_rows


def _table(rows: list[dict], method: str):
    width = max([len(r["figure"]) for r in rows] + [len(r["parameter"]) for r in rows] + [1])
    data = np.zeros(len(rows), dtype=[("figure", f"U{width}"), ("parameter", f"U{width}"),
                                      ("rank", "i4")] + [(k, "f8") for k in INDICES[method]])
    for i, r in enumerate(rows):
        for key, value in r.items():
            data[key][i] = math.nan if value is None else value
    return data


def _number(value) -> float:
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) \
        else math.nan


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _file_name(figure: str) -> str:
    return re.sub(r"[^\w.-]", "_", figure)
