"""Optimization of a scenario's key figures over its parameters, with scipy.optimize.

The optimizers work in the unit cube (every variable from 0 at its lower bound to 1 at its
upper), so that one tolerance means the same share of every range whatever its unit. Which
scipy method runs (`algorithm` in optimize.json):

- one variable and a target of one figure: brentq on figure - target where the bounds bracket
  it, else the bounded scalar minimization of the squared miss (the closest the range comes);
- one variable, minimize or maximize: minimize_scalar, method "bounded";
- several variables: Nelder-Mead within the bounds; with constraints SLSQP (finite-difference
  gradients with a step of 1e-4 of each range, far above the runs' numerical noise);
- method "global": differential_evolution, its population evaluated as one batch in the worker
  processes (its `workers` is the batch's map); constraints enter it as a penalty, because
  scipy evaluates the constraints of a population one point after another in this process.

The best point is the best evaluation that ran and meets the constraints (within 1e-6 of each
bound); `converged` is what scipy says of its own stopping test. A point that fails is
infeasible: in evaluations.csv with its reason, and to the optimizer a value worse than any
feasible one (PENALTY), never a figure.
"""
from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy import optimize as so
from scipy.stats import qmc

from sewfmu.extras import require
from sewfmu.scenarios.design.evaluations import (
    LOG_FILE,
    OK,
    Evaluation,
    Evaluator,
    progress_bar,
    study_folder,
)
from sewfmu.scenarios.design.space import (
    CONSTRAINT_TOLERANCE,
    Constraint,
    Goal,
    Variable,
    evaluation_budget,
    figures_of_scenario,
    seconds_per_run_over,
)
from sewfmu.scenarios.files.outputs import replacing, write_atomic
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import ScenarioError
from sewfmu.scenarios.runs import budget as runs_budget
from sewfmu.scenarios.runs.budget import worker_count

METHODS = ("local", "global")
PENALTY = 1e9              # an infeasible point, to the optimizer: worse than any feasible one
VIOLATION = 1e6            # a constraint not met (global method), plus the relative violation
DEFAULT_EVALUATIONS = {"local": 200, "global": 400}
FD_STEP = 1e-4             # SLSQP's finite-difference step, as a share of each range
SETTINGS = {
    "brentq": {"xtol": 1e-6},
    "bounded": {"xatol": 1e-5},
    "Nelder-Mead": {"xatol": 1e-4, "fatol": 1e-9, "initial_step": 0.2},
    "SLSQP": {"ftol": 1e-9, "eps": FD_STEP},
    "differential_evolution": {"popsize": 10, "tol": 0.01, "mutation": [0.5, 1.0],
                               "recombination": 0.7, "seed": 1, "init": "latinhypercube",
                               "updating": "deferred", "polish": False},
}


class _OutOfEvaluations(Exception):
    """The study's budget of evaluations is spent: the optimizer stops where it is."""


@dataclass
class Optimum:
    """An optimization: `best` (each varied parameter in its declared unit), `figures` (the key
    figures there), `evaluations` (every point, a numpy structured array), `converged`."""
    scenario: str
    best: dict[str, float] | None
    figures: dict
    units: dict[str, str]
    evaluations: Any
    converged: bool
    feasible: bool
    method: str
    algorithm: str
    settings: dict
    message: str
    computed: int
    wall_time_s: float
    out: Path | None = None
    summary: dict = field(default_factory=dict)          # what optimize.json holds

    def to_pandas(self):
        return require("pandas", "to_pandas()").DataFrame(self.evaluations)

    def __repr__(self) -> str:
        best = ", ".join(f"{k}={v:.6g}" for k, v in (self.best or {}).items())
        return (f"<sewfmu.Optimum {self.scenario}: {best}; {len(self.evaluations)} evaluations, "
                f"{'converged' if self.converged else 'not converged'}>")


class _Problem:
    """The goal and constraints at points u of the unit cube, through the evaluator."""

    def __init__(self, variables: list[Variable], goal: Goal, constraints: list[Constraint],
                 evaluator: Evaluator, budget: int):
        self.variables, self.goal, self.constraints = variables, goal, constraints
        self.evaluator, self.budget = evaluator, budget
        self.offset, self.scale = 0.0, 1.0          # the objective as the optimizer sees it

    def x(self, u) -> tuple[float, ...]:
        return tuple(v.at(ui) for v, ui in zip(self.variables, np.atleast_1d(u)))

    def evaluate(self, u) -> Evaluation:
        x = self.x(u)
        if len(self.evaluator.history) >= self.budget and \
                self.evaluator.key(x) not in self.evaluator.known:
            raise _OutOfEvaluations
        return self.evaluator(x)

    def objective_of(self, e: Evaluation) -> float | None:
        value = self.goal.objective(e.figures) if e.status == OK else None
        return None if value is None else (value - self.offset) / self.scale

    def margins_of(self, e: Evaluation) -> list[float | None]:
        return [c.margin(e.figures) if e.status == OK else None for c in self.constraints]

    def objective(self, u) -> float:
        value = self.objective_of(self.evaluate(u))
        return PENALTY if value is None else value

    def margin(self, k: int, u) -> float:
        value = self.margins_of(self.evaluate(u))[k]
        return -1.0 if value is None else value

    def penalized(self, u) -> float:
        """The global method's value: the objective where the constraints hold, else beyond
        every feasible value by the violation."""
        e = self.evaluate(u)
        value, margins = self.objective_of(e), self.margins_of(e)
        if value is None or any(m is None for m in margins):
            return PENALTY
        violation = sum(max(0.0, -m) for m in margins)
        return value if violation <= CONSTRAINT_TOLERANCE else VIOLATION + violation

    def batch_map(self, func, points):
        """differential_evolution's `workers`: the population run as one batch, then func
        reads each point from what the batch left."""
        points = [np.asarray(p) for p in points]
        room = max(0, self.budget - len(self.evaluator.history))
        self.evaluator.batch([self.x(u) for u in points][:room])
        return [func(u) for u in points]


def optimize(scenario: Scenario, fmu_paths: dict, variables: list[Variable], goal: Goal,
             constraints: list[Constraint], method: str = "local", workers: int | None = None,
             out: Path | None = None, plot: bool = False,
             max_evaluations: int | None = None, progress: bool = False,
             max_runs: int | None = None) -> Optimum:
    """Optimize the goal under the constraints over the variables' ranges (module docstring);
    with `out`, evaluations.csv as the points run, optimize.json and with `plot` convergence.png.
    The budget of evaluations is checked against the bound on runs (runs/budget.py) and said,
    with a time estimate, before the first run."""
    if method not in METHODS:
        raise ScenarioError(f"--method: one of {', '.join(METHODS)}, got {method!r}")
    # the local methods run here; the global one on every core
    workers = worker_count(workers, (os.cpu_count() or 1) if method == "global" else 1)
    budget = evaluation_budget(max_evaluations, DEFAULT_EVALUATIONS[method])
    parallel = workers if method == "global" else 1
    what, per_run = f"optimize {scenario.name}", seconds_per_run_over(scenario, variables)
    runs_budget.check(budget, what, runs_budget.max_runs(max_runs),
                      f"--max-evaluations {budget}", per_run, parallel)
    outputs = ["optimize.json", *(["convergence.png"] if plot else [])]
    with study_folder(out, [LOG_FILE], outputs):
        runs_budget.announce(what, budget, per_run, parallel, shown=progress, most=True)
        return _optimize(scenario, fmu_paths, variables, goal, constraints, method, workers,
                         out, plot, budget, progress)


def _optimize(scenario: Scenario, fmu_paths: dict, variables: list[Variable], goal: Goal,
              constraints: list[Constraint], method: str, workers: int, out: Path | None,
              plot: bool, budget: int, progress: bool) -> Optimum:
    units = figures_of_scenario(scenario)
    started = time.perf_counter()
    evaluator = Evaluator(scenario, fmu_paths, [v.name for v in variables], list(units),
                          Path(out) if out is not None else None, workers,
                          progress_bar(progress, f"optimize {scenario.name}", budget))
    problem = _Problem(variables, goal, constraints, evaluator, budget)
    try:
        if goal.sense != "target":          # min and max relative to the start: one scale
            first = problem.objective_of(problem.evaluate(_start(variables)))
            problem.scale = abs(first) if first else 1.0
        algorithm, settings, converged, message, answer = (_local if method == "local"
                                                           else _global)(problem)
        best, feasible = _best(problem, answer)
    except _OutOfEvaluations:
        algorithm, settings = _algorithm_of(problem, method), {}
        converged, message = False, f"stopped after {budget} evaluations (max_evaluations)"
        best, feasible = _best(problem, None)
    finally:
        evaluator.close()
    wall = time.perf_counter() - started
    units = {**{v.name: v.unit for v in variables}, **units}
    summary = {
        "scenario": scenario.name, "source": scenario.source, **goal.describe(),
        "constraints": [str(c) for c in constraints],
        "vary": {v.name: {"low": v.lo, "high": v.hi, "start": v.start, "unit": v.unit}
                 for v in variables},
        "best": dict(zip(evaluator.names, best.values)) if best else None,
        "feasible": feasible, "figures": dict(best.figures) if best else {},
        "units": units, "evaluations": len(evaluator.history), "computed": evaluator.computed,
        "converged": bool(converged), "method": method, "algorithm": algorithm,
        "settings": settings, "message": message, "wall_time_s": round(wall, 3),
        "evaluations_per_s": round(evaluator.computed / evaluator.run_seconds, 3)
        if evaluator.run_seconds else None,
    }
    if goal.sense == "target" and best is not None:     # how far the best point misses
        reached = {f: best.figures.get(f) for f, _ in goal.targets}
        summary["misses"] = {f: None if reached[f] is None else reached[f] - t
                             for f, t in goal.targets}
    objective = [problem.objective_of(e) for e in evaluator.history]
    table = evaluator.table({"objective": [math.nan if o is None else o for o in objective]})
    if out is not None:             # in place of the last study's files, with its record
        with replacing(Path(out), kept=[LOG_FILE]) as staging:
            _write_json(staging / "optimize.json", summary)
            if plot:
                from sewfmu.scenarios.design.plots import (  # matplotlib: only when drawing
                    convergence,
                )

                convergence(staging / "convergence.png", scenario.name, goal, constraints,
                            table, [problem.margins_of(e) for e in evaluator.history], units)
    if best is None:
        reasons = sorted({e.error for e in evaluator.history if e.error})
        wanted = ", ".join(dict.fromkeys(goal.figures + [c.figure for c in constraints]))
        raise ScenarioError((f"every evaluation failed ({reasons[0]})" if reasons else
                             f"no evaluation gave {wanted} a value")
                            + (f"; see {Path(out) / 'evaluations.csv'}" if out is not None
                               else ""))
    return Optimum(scenario.name, summary["best"], summary["figures"], units, table,
                   bool(converged), feasible, method, algorithm, settings, message,
                   evaluator.computed, round(wall, 3), Path(out) if out is not None else None,
                   summary)


def _start(variables: list[Variable]) -> np.ndarray:
    return np.array([v.fraction(v.start) for v in variables])


def _algorithm_of(problem: _Problem, method: str) -> str:
    if method == "global":
        return "differential_evolution"
    if problem.constraints:
        return "SLSQP"
    if len(problem.variables) > 1:
        return "Nelder-Mead"
    return "brentq" if problem.goal.sense == "target" and len(problem.goal.targets) == 1 \
        else "bounded"


def _local(p: _Problem) -> tuple[str, dict, bool, str]:
    algorithm = _algorithm_of(p, "local")
    if algorithm == "brentq":
        found = _root(p)
        if found is not None:
            return found
        algorithm = "bounded"
    settings = dict(SETTINGS[algorithm])
    if algorithm == "bounded":
        r = so.minimize_scalar(p.objective, bounds=(0.0, 1.0), method="bounded",
                               options={**settings, "maxiter": p.budget})
        return algorithm, settings, bool(r.success), str(r.message), np.atleast_1d(r.x)
    u0 = _start(p.variables)
    bounds = [(0.0, 1.0)] * len(u0)
    if algorithm == "Nelder-Mead":
        step = settings["initial_step"]      # a simplex that spans a fifth of each range
        simplex = [u0] + [u0 + np.eye(len(u0))[i] * (step if u0[i] + step <= 1.0 else -step)
                          for i in range(len(u0))]
        r = so.minimize(p.objective, u0, method="Nelder-Mead", bounds=bounds,
                        options={"xatol": settings["xatol"], "fatol": settings["fatol"],
                                 "maxfev": p.budget, "initial_simplex": np.array(simplex)})
    else:
        constraints = [{"type": "ineq", "fun": (lambda u, k=k: p.margin(k, u))}
                       for k in range(len(p.constraints))]
        r = so.minimize(p.objective, u0, method="SLSQP", bounds=bounds, constraints=constraints,
                        options={**settings, "maxiter": p.budget})
    return algorithm, settings, bool(r.success), str(r.message), r.x


class _Undefined(Exception):
    """The target figure has no value at a point: no root to bracket there."""


def _root(p: _Problem):
    """brentq on the miss of the one target, where the bounds bracket it; None where they do
    not (or a point on the way has no value): the caller minimizes the miss instead."""
    figure, target = p.goal.targets[0]

    def miss(u: float) -> float:
        e = p.evaluate([u])
        value = e.figures.get(figure) if e.status == OK else None
        if value is None:
            raise _Undefined
        return value - target

    try:
        low, high = miss(0.0), miss(1.0)
        if low == 0.0 or high == 0.0:
            return ("brentq", dict(SETTINGS["brentq"]), True, "a bound meets the target",
                    np.array([0.0 if low == 0.0 else 1.0]))
        if low * high > 0:
            return None
        root, r = so.brentq(miss, 0.0, 1.0, xtol=SETTINGS["brentq"]["xtol"], full_output=True,
                            maxiter=p.budget)
    except _Undefined:
        return None
    return "brentq", dict(SETTINGS["brentq"]), bool(r.converged), str(r.flag), np.array([root])


def _global(p: _Problem) -> tuple[str, dict, bool, str]:
    settings = dict(SETTINGS["differential_evolution"])
    n = len(p.variables)
    size = settings["popsize"] * n
    settings["maxiter"] = max(1, p.budget // size - 1)
    # the first generation: scipy's Latin hypercube, the start point first, run as one batch
    init = qmc.LatinHypercube(d=n, seed=settings["seed"]).random(size)
    init[0] = _start(p.variables)
    if p.goal.sense != "target":
        _scale_by_first_generation(p, init)
    options = {k: tuple(v) if isinstance(v, list) else v for k, v in settings.items()}
    options["init"] = init
    r = so.differential_evolution(p.penalized, [(0.0, 1.0)] * n, workers=p.batch_map,
                                  **options)
    return "differential_evolution", settings, bool(r.success), str(r.message), r.x


def _scale_by_first_generation(p: _Problem, init: np.ndarray) -> None:
    """differential_evolution stops when its population's values spread less than tol times
    their mean: for a figure that moves by less than tol of its size over the ranges (a weld's
    duration: 135.14 to 135.21°) that holds at once, in the first generation. Measured from
    the first generation's mean and spread instead, the values spread by about 1 at first,
    whatever the figure's size."""
    try:
        p.batch_map(lambda u: None, list(init))
        values = [p.goal.objective(e.figures) for e in (p.evaluate(u) for u in init)
                  if e.status == OK]
    except _OutOfEvaluations:         # a budget below one generation: the search stops anyway
        return
    values = [v for v in values if v is not None]
    if len(values) >= 2 and np.std(values) > 0:
        p.offset, p.scale = float(np.mean(values)), float(np.std(values))


def _best(p: _Problem, answer) -> tuple[Evaluation | None, bool]:
    """scipy's answer where it meets the constraints (not a finite-difference neighbour that
    meets them as closely); else the best evaluation that meets them; where none does, the one
    closest to meeting them (feasible False); None where no evaluation gave the goal's
    figures."""
    if answer is not None:
        try:
            e = p.evaluate(answer)
        except _OutOfEvaluations:
            e = None
        value, margins = (p.objective_of(e), p.margins_of(e)) if e else (None, [None])
        if value is not None and all(m is not None and m >= -CONSTRAINT_TOLERANCE
                                     for m in margins):
            return e, True
    scored = []
    for e in p.evaluator.history:
        value, margins = p.objective_of(e), p.margins_of(e)
        if value is None or any(m is None for m in margins):
            continue
        violation = sum(max(0.0, -m) for m in margins)
        scored.append((violation > CONSTRAINT_TOLERANCE, violation, value, e))
    if not scored:
        return None, False
    infeasible, _, _, e = min(scored, key=lambda s: s[:3] if s[0] else (False, 0.0, s[2]))
    return e, not infeasible


def _write_json(path: Path, data: dict) -> None:
    write_atomic(path, lambda f: json.dump(data, f, indent=2, default=_plain))


def _plain(value):
    """numpy numbers as JSON numbers."""
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON: {type(value).__name__}")
