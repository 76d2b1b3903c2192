"""Parameters learnt from measurements: scipy.optimize.least_squares over the scenario's runs.

The data are a table with a `time` column and columns named like recorded outputs
(`punch.F2`, or `punch.F2 [N]` as results.csv writes them). The model runs from t = 0 to the
data's last time (or to the end the study was given, which the data must not pass) and is read
at the data's times (linear interpolation between communication points). Each column's
residuals are divided by its spread (standard deviation), so that columns of different units
and sizes weigh alike. least_squares works in the unit cube of the free parameters, with
finite-difference steps of 1e-3 of each range (far above the runs' numerical noise).

Standard errors come from the Jacobian at the optimum: cov = s² (JᵀJ)⁻¹ with
s² = Σr² / (m - n), the residuals' variance; they hold where the model is about linear in the
parameters over their errors and the noise is independent between samples.
"""
from __future__ import annotations

import csv
import json
import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from scipy import optimize as so

from sewfmu.components.parameters import did_you_mean
from sewfmu.errors import Error
from sewfmu.scenarios.cosim.master import run
from sewfmu.scenarios.design.evaluations import one_line, progress_bar, study_folder
from sewfmu.scenarios.design.fit_record import RECORD_FILE, FitRecord
from sewfmu.scenarios.design.space import Variable, evaluation_budget, seconds_per_run_over
from sewfmu.scenarios.files.outputs import replacing, write_atomic
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import ScenarioError
from sewfmu.scenarios.runs import budget as runs_budget

SETTINGS = {"method": "trf", "diff_step": 1e-3, "xtol": 1e-8, "ftol": 1e-10, "gtol": 1e-10}
DEFAULT_EVALUATIONS = 100
# the residuals of a point that fails: far worse than any fit, finite (least_squares needs it)
FAILED_RESIDUAL = 1e3
BEYOND_MEASUREMENT = 1e150      # a value whose square overflows a float is no measurement
_HEADER_UNIT = re.compile(r"^\s*(.*?)\s*\[(.*)\]\s*$")


@dataclass
class Data:
    source: str
    time: np.ndarray
    columns: dict[str, np.ndarray]
    units: dict[str, str]


@dataclass
class Fit:
    """A fit: `estimates` and `standard_errors` of the free parameters (their declared units),
    `residuals` (model - data at the data's times, a numpy structured array), `residual_rms`
    per column, `correlation` of the estimates, `converged`."""
    scenario: str
    estimates: dict[str, float]
    standard_errors: dict[str, float]
    correlation: dict[str, dict[str, float]]
    residuals: Any
    residual_rms: dict[str, float]
    units: dict[str, str]
    converged: bool
    message: str
    evaluations: int
    out: Path | None = None
    summary: dict = field(default_factory=dict)           # what fit.json holds

    def __repr__(self) -> str:
        shown = ", ".join(f"{k}={v:.6g}±{self.standard_errors[k]:.2g}"
                          for k, v in self.estimates.items())
        return f"<sewfmu.Fit {self.scenario}: {shown}; {'converged' if self.converged else 'not converged'}>"


def read_data(data: Any) -> Data:
    """A CSV file (path) or a numpy structured array / dict of arrays with a `time` field."""
    if isinstance(data, (str, Path)):
        if not Path(data).is_file():
            raise ScenarioError(f"data: {data}: no such file (a CSV file with a time column)")
        return _read_csv(Path(data))
    names = getattr(getattr(data, "dtype", None), "names", None)
    if names is not None:
        columns = {n: data[n] for n in names}
    elif isinstance(data, Mapping):
        columns = {str(k): v for k, v in data.items()}
    else:
        raise ScenarioError(f"data: a CSV file or a table of columns (numpy structured array or "
                            f"dict), got {type(data).__name__}")
    table = {}
    for name, values in columns.items():        # what a CSV file's reading checks, for a table
        try:
            column = np.asarray(values, dtype=float)
        except (TypeError, ValueError):
            raise ScenarioError(f"data: column {name!r} is not numbers") from None
        if column.ndim != 1:
            raise ScenarioError(f"data: column {name!r} must be one row of numbers, got shape "
                                f"{column.shape}")
        if np.any(np.isinf(column)):
            raise ScenarioError(f"data: column {name!r} holds an infinite value, which is not a "
                                f"measurement (NaN marks a missing one)")
        table[name] = column
    lengths = {len(c) for c in table.values()}
    if len(lengths) > 1:
        raise ScenarioError(f"data: the columns differ in length ("
                            f"{', '.join(f'{n}: {len(c)}' for n, c in table.items())})")
    return _checked("data", table, {})


def _read_csv(path: Path) -> Data:
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            rows = [row for row in csv.reader(f) if row and not row[0].startswith("#")]
    except UnicodeDecodeError:
        raise ScenarioError(f"{path}: not a UTF-8 text file") from None
    if not rows:
        raise ScenarioError(f"{path}: no header line and no data")
    names, units = [], {}
    for text in rows[0]:
        match = _HEADER_UNIT.match(text)
        name = (match.group(1) if match else text).strip()
        if name in names:                   # the second would silently replace the first
            raise ScenarioError(f"{path}: column {name!r} is given twice in the header")
        names.append(name)
        if match:
            units[name] = match.group(2).strip()
    values = np.full((len(rows) - 1, len(names)), np.nan)
    for i, row in enumerate(rows[1:]):
        if len(row) != len(names):
            raise ScenarioError(f"{path}: line {i + 2} has {len(row)} cells, the header "
                                f"{len(names)}")
        for j, cell in enumerate(row):
            try:
                values[i, j] = float(cell) if cell.strip() else math.nan
            except ValueError:
                raise ScenarioError(f"{path}: line {i + 2}, column {names[j]}: not a number: "
                                    f"{cell!r}") from None
            if math.isinf(values[i, j]):        # a measurement is finite (NaN: a missing one)
                raise ScenarioError(f"{path}: line {i + 2}, column {names[j]}: {cell.strip()} "
                                    f"is not a measurement (leave the cell empty for a missing "
                                    f"one)")
    return _checked(str(path), {n: values[:, j] for j, n in enumerate(names)}, units)


def _checked(source: str, table: dict, units: dict) -> Data:
    if "time" not in table:
        raise ScenarioError(f"{source}: no 'time' column (the columns: {', '.join(table)})")
    t = table.pop("time")
    if units.get("time", "s") != "s":
        raise ScenarioError(f"{source}: the time column is in {units['time']}, not s")
    if not table:
        raise ScenarioError(f"{source}: no column besides time to fit to")
    if len(t) < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise ScenarioError(f"{source}: the times must be finite and increasing (at least two)")
    for name, values in table.items():
        largest = float(np.nanmax(np.abs(values))) if np.any(np.isfinite(values)) else 0.0
        if largest > BEYOND_MEASUREMENT:
            raise ScenarioError(f"{source}: column {name} holds {largest:g}, beyond any "
                                f"measurement (its squares would overflow)")
    return Data(source, t, table, {k: u for k, u in units.items() if k != "time"})


def check_data(data: Data, scenario: Scenario, descriptions: Mapping,
               keep_end: bool = False) -> Scenario:
    """The scenario that runs over the data: every column an output of one of its instances
    (in that output's unit), every time within the run. The run goes from 0 to the data's last
    time, or, with `keep_end`, to the scenario's own end (the study set it), which the data
    must not pass."""
    outputs = {f"{inst}.{v.name}": v.unit or "" for inst, md in descriptions.items()
               for v in md.modelVariables if v.causality == "output"}
    for name in data.columns:
        if name not in outputs:
            raise ScenarioError(f"{data.source}: column {name!r} is not an output of "
                                f"{scenario.name}{did_you_mean(name, outputs)} (outputs: "
                                f"{', '.join(outputs)})")
        given = data.units.get(name)
        if given is not None and given != outputs[name]:
            raise ScenarioError(f"{data.source}: column {name} is given in {given!r}; the "
                                f"output is in {outputs[name]!r}")
        if not np.any(np.isfinite(data.columns[name])):
            raise ScenarioError(f"{data.source}: column {name} holds no number")
        data.units[name] = outputs[name]
    if data.time[0] < 0:
        raise ScenarioError(f"{data.source}: the data begin at t = {data.time[0]:g} s, before "
                            f"the run starts (t = 0)")
    sc = scenario.copy()
    if keep_end:
        end = sc.end_time()
        if data.time[-1] > end * (1 + 1e-9):
            raise ScenarioError(f"{data.source}: the data reach t = {data.time[-1]:g} s, past "
                                f"the run's end at {end:g} s")
    else:
        sc.set_value("experiment.stop_time", float(data.time[-1]), origin="the data's end:")
    if sc.record is not None:               # the data's columns recorded, whatever else is
        sc.record = list(dict.fromkeys([*sc.record, *data.columns]))
    return sc


class _Model:
    """The scenario at points u of the free parameters' unit cube: its outputs at the data's
    times, from the fit's record where a run there is known (a resumed fit), else run now. The
    last runs' whole series are kept: the plot draws the optimum's."""

    def __init__(self, scenario: Scenario, fmu_paths: dict, free: list[Variable], data: Data,
                 record: FitRecord | None = None, bar=None):
        self.scenario, self.fmu_paths, self.free, self.data = scenario, fmu_paths, free, data
        self.record, self.bar = record, bar
        self.spread = {c: (float(np.nanstd(v)) or float(np.nanmax(np.abs(v))) or 1.0)
                       for c, v in data.columns.items()}
        self.mask = {c: np.isfinite(v) for c, v in data.columns.items()}
        self.cache: dict[tuple, dict | None] = {}       # x -> the outputs at the data's times
        self.whole: dict[tuple, tuple] = {}             # x -> (time, whole series), the last few
        self.runs, self.reused, self.failures = 0, 0, []

    def x(self, u) -> tuple[float, ...]:
        return tuple(v.at(ui) for v, ui in zip(self.free, u))

    def at_data(self, u):
        """{column: the model's values at the data's times} at the point, or None where the
        run fails."""
        x = self.x(u)
        if x in self.cache:
            return self.cache[x]
        known = self.record.known.get(self.record.key(x)) if self.record else None
        if known is not None:
            values, error = known
            self.reused += 1
            if values is None:
                self.failures.append((x, error))
        else:
            values = self.run(x)
            if self.record is not None:
                self.record.add(x, values, "" if values is not None else self.failures[-1][1])
        self.cache[x] = values
        if self.bar is not None:
            self.bar.update(1)
        if len(self.cache) > 64:
            self.cache.pop(next(iter(self.cache)))
        return values

    def run(self, x):
        """Run at x: the outputs at the data's times (the whole series kept), None on failure."""
        sc = self.scenario.copy()
        self.runs += 1
        try:
            for v, value in zip(self.free, x):
                sc.set_value(v.name, value, origin="fit")
            result = run(sc, self.fmu_paths)
        except Error as err:
            self.failures.append((x, one_line(err)))
            return None
        series = {c: result[c] for c in self.data.columns}
        self.whole[x] = (result.time, series)
        if len(self.whole) > 4:
            self.whole.pop(next(iter(self.whole)))
        return {c: np.interp(self.data.time, result.time, v) for c, v in series.items()}

    def residuals(self, u) -> np.ndarray:
        found = self.at_data(u)
        parts = []
        for c, values in self.data.columns.items():
            m = self.mask[c]
            if found is None:
                parts.append(np.full(int(m.sum()), FAILED_RESIDUAL))
                continue
            parts.append((found[c][m] - values[m]) / self.spread[c])
        return np.concatenate(parts)


def fit(scenario: Scenario, fmu_paths: dict, free: list[Variable], data: Data,
        out: Path | None = None, plot: bool = True, max_evaluations: int | None = None,
        progress: bool = False, max_runs: int | None = None) -> Fit:
    """Least squares over the free parameters (module docstring) of the scenario that
    check_data made; with `out`, fit.json and fit.png. The most runs the budget allows (each
    evaluation of the residuals and its Jacobian's n runs) is checked against the bound on
    runs (runs/budget.py) and said, with a time estimate, before the first run."""
    budget = evaluation_budget(max_evaluations, DEFAULT_EVALUATIONS)
    # least_squares' max_nfev leaves out the Jacobians' runs: n more per evaluation at most,
    # and the first guess and the optimum's series for the plot besides
    most = budget * (len(free) + 1) + 2
    what, per_run = f"fit {scenario.name}", seconds_per_run_over(scenario, free)
    runs_budget.check(most, what, runs_budget.max_runs(max_runs),
                      f"--max-evaluations {budget} × ({len(free)} free + 1)", per_run)
    outputs = ["fit.json", *(["fit.png"] if plot else [])]
    with study_folder(out, [RECORD_FILE], outputs):
        runs_budget.announce(what, most, per_run, shown=progress, most=True)
        return _fit(scenario, fmu_paths, free, data, out, plot, budget, progress)


def _fit(scenario: Scenario, fmu_paths: dict, free: list[Variable], data: Data,
         out: Path | None, plot: bool, budget: int, progress: bool) -> Fit:
    started = time.perf_counter()
    record = FitRecord(out, scenario, fmu_paths, [v.name for v in free], data) \
        if out is not None else None
    bar = progress_bar(progress, f"fit {scenario.name}", None)
    try:
        model = _Model(scenario, fmu_paths, free, data, record, bar)
        u0 = np.array([v.fraction(v.start) for v in free])
        if model.at_data(u0) is None:
            raise ScenarioError(f"the first guess ({_point(free, model.x(u0))}) fails: "
                                f"{model.failures[-1][1]}")
        r = so.least_squares(model.residuals, u0, bounds=(0.0, 1.0), max_nfev=budget,
                             **SETTINGS)
    finally:
        if bar is not None:
            bar.close()
        if record is not None:
            record.close()
    names = [v.name for v in free]
    estimates = dict(zip(names, model.x(r.x)))
    m, n = len(r.fun), len(free)
    s2 = float(r.fun @ r.fun) / max(m - n, 1)
    cov_u = s2 * np.linalg.pinv(r.jac.T @ r.jac)
    ranges = np.array([v.hi - v.lo for v in free])
    cov = cov_u * np.outer(ranges, ranges)
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    notes = _identifiability(r.jac, free, r.x)
    if notes["undetermined"]:              # pinv's 0 there would claim an exact answer
        se[:] = math.inf
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se)
    x_best = model.x(r.x)
    if x_best not in model.whole:                  # found in the record: its series drawn anew
        model.run(x_best)
    t_run, series = model.whole[x_best]
    residuals = np.full(len(data.time), np.nan, dtype=[("time", "f8")]
                        + [(c, "f8") for c in data.columns])
    residuals["time"] = data.time
    rms = {}
    for c, values in data.columns.items():
        residuals[c] = np.interp(data.time, t_run, series[c]) - values
        rms[c] = float(np.sqrt(np.nanmean(residuals[c] ** 2)))
    units = {**{v.name: v.unit for v in free}, **{c: data.units.get(c, "") for c in data.columns}}
    summary = {
        "scenario": scenario.name, "source": scenario.source, "data": data.source,
        "columns": list(data.columns), "samples": int(m),
        "free": {v.name: {"low": v.lo, "high": v.hi, "start": v.start, "unit": v.unit}
                 for v in free},
        "estimates": estimates,
        "standard_errors": {k: _finite(v) for k, v in zip(names, se.tolist())},
        "warnings": notes["warnings"],
        "units": units, "residual_rms": rms,
        "correlation": {a: {b: _finite(corr[i, j]) for j, b in enumerate(names)}
                        for i, a in enumerate(names)},
        "converged": bool(r.success), "message": str(r.message),
        # this fit's runs, those made now, and those its record held (a resumed fit)
        "evaluations": model.runs + model.reused, "computed": model.runs,
        "reused_evaluations": model.reused,
        "failed_evaluations": [{"point": dict(zip(names, x)), "error": e}
                               for x, e in model.failures],
        "method": "least_squares", "settings": SETTINGS, "end_time": float(t_run[-1]),
        "wall_time_s": round(time.perf_counter() - started, 3),
    }
    if out is not None:             # in place of the last study's files, with its record
        out = Path(out)
        with replacing(out, kept=[RECORD_FILE]) as staging:
            write_atomic(staging / "fit.json", lambda f: json.dump(summary, f, indent=2))
            if plot:
                from sewfmu.scenarios.design.plots import fit_plot  # matplotlib: when drawing

                fit_plot(staging / "fit.png", scenario.name, data.time, data.columns, t_run,
                         series, units)
    return Fit(scenario.name, estimates, dict(zip(names, se.tolist())), summary["correlation"],
               residuals, rms, units, bool(r.success), str(r.message), model.runs + model.reused,
               out, summary)


def _identifiability(jac: np.ndarray, free: list[Variable], u: np.ndarray) -> dict:
    """What the data leave open: parameters the residuals do not change with (or only together:
    a Jacobian of lower rank), whose standard errors are then infinite; estimates at a bound of
    their range, where the best fit may lie beyond it."""
    warnings = []
    norms = np.linalg.norm(jac, axis=0)
    flat = [v.name for v, norm in zip(free, norms) if norm <= 1e-12 * max(norms.max(), 1e-300)]
    undetermined = bool(flat) or np.linalg.matrix_rank(jac) < len(free)
    if flat:
        warnings.append(f"the data do not depend on {', '.join(flat)} near the fit: "
                        f"{'it is' if len(flat) == 1 else 'they are'} not determined (standard "
                        f"error infinite)")
    elif undetermined:
        warnings.append("the data determine the free parameters only together (their effects "
                        "on the residuals are proportional): standard errors infinite")
    for v, ui in zip(free, u):
        if min(ui, 1.0 - ui) <= 1e-6:
            bound = v.lo if ui < 0.5 else v.hi
            warnings.append(f"{v.name} ends at its {'lower' if ui < 0.5 else 'upper'} bound "
                            f"{bound:g} {v.unit}".rstrip() + ": the best fit may lie beyond the "
                            "range")
    return {"undetermined": undetermined, "warnings": warnings}


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _point(free: list[Variable], x) -> str:
    return ", ".join(f"{v.name} = {value:g} {v.unit}".rstrip() for v, value in zip(free, x))
