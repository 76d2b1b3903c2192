"""What a design study varies and what it asks of the key figures.

A variable is an `instance.parameter` between two bounds, written as --set writes a value
("800..1200 rpm", "15..40", ("10 mm", "12 mm"), (0.01, 0.012); a unit after the upper bound
applies to both, format/value_lists.py), converted into the unit its FMU declares and checked
against the range the FMU declares, before anything runs. A goal (minimize, maximize,
a target) and constraints (`F2_peak<=25 N`) name key figures of the scenario's analysis, with
their values in any unit that fits the figure's.
"""
from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from sewfmu.components.parameters import (
    ParameterError,
    check_value,
    did_you_mean,
    parameter_info,
)
from sewfmu.components.registry import FMUS
from sewfmu.components.units import UnitError
from sewfmu.scenarios.cosim.divergence import declared_bound
from sewfmu.scenarios.cosim.fmi_calls import kind_of
from sewfmu.scenarios.format.parameter_table import range_text, slave_class
from sewfmu.scenarios.format.quantities import in_declared_unit
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.value_lists import check_units_agree, range_in_text
from sewfmu.scenarios.format.values import ScenarioError, plain, short
from sewfmu.scenarios.runs.budget import mean_seconds
from sewfmu.scenarios.runs.sweep import Point, seconds_of_points

_CONSTRAINT = re.compile(r"^\s*([A-Za-z_]\w*)\s*(<=|>=)\s*(\S.*?)\s*$")
_TARGET = re.compile(r"^\s*([A-Za-z_]\w*)\s*=\s*(\S.*?)\s*$")
# a constraint's margin (relative to its bound) that still counts as met: what SLSQP leaves
CONSTRAINT_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Variable:
    """A varied parameter: bounds in the unit its FMU declares, and where a local method starts
    (the scenario's value where it lies within the bounds, else the middle)."""
    name: str
    lo: float
    hi: float
    unit: str
    start: float

    def at(self, u: float) -> float:
        """The value at u in [0, 1]: the optimizers work in the unit cube, where every variable
        has the same scale whatever its unit."""
        return self.lo + min(max(float(u), 0.0), 1.0) * (self.hi - self.lo)

    def fraction(self, x: float) -> float:
        return (x - self.lo) / (self.hi - self.lo)


def variables(scenario: Scenario, ranges: Mapping[str, Any], descriptions: Mapping[str, Any],
              option: str = "--vary") -> list[Variable]:
    """The variables of `ranges` ({"instance.parameter": "LO..HI unit" or (lo, hi)}), each
    checked: a parameter of the scenario, a real number, bounds in order and within the range its
    FMU declares (`descriptions`: instance -> modelDescription)."""
    if not isinstance(ranges, Mapping):
        raise ScenarioError(f"{option}: expected {{\"instance.parameter\": (low, high)}} (a "
                            f"dict: each parameter and its two bounds), got {short(ranges)}")
    if not ranges:
        raise ScenarioError(f"{option}: nothing to vary: give at least one "
                            f"instance.parameter=LO..HI")
    out = []
    for name, spec in ranges.items():
        name = str(name).strip()
        where = f"{option} {name}"
        inst, dot, key = name.partition(".")
        if inst == "experiment":
            raise ScenarioError(f"{where}: only parameters of instances can be varied (the "
                                f"experiment's settings are given with --set)")
        lo_text, hi_text = _bounds(spec, where)
        lo, hi = (_in_declared_unit(scenario, name, v, option) for v in (lo_text, hi_text))
        md = descriptions[inst]
        var = next((v for v in md.modelVariables if v.name == key
                    and v.causality in ("parameter", "input")), None)
        if var is None:                     # an FMU from elsewhere: set_value took its word
            names = [v.name for v in md.modelVariables if v.causality == "parameter"]
            raise ScenarioError(f"{where}: {inst} ({md.modelName}) has no parameter {key!r}"
                                f"{did_you_mean(key, names)}")
        unit = var.unit or ""
        if kind_of(var) != "Real":
            raise ScenarioError(f"{where}: {key} is an {kind_of(var).lower()} parameter of {inst} "
                                f"({md.modelName}); only real parameters can be varied")
        if not lo < hi:
            raise ScenarioError(f"{where}: the lower bound {lo:g} {unit} is not below the upper "
                                f"bound {hi:g} {unit}")
        _within_the_range(scenario, inst, key, var, (("lower", lo), ("upper", hi)), where,
                          unit, md.modelName)
        given = scenario.instances[inst].parameters.get(key, var.start)
        try:
            start = float(given)
        except (TypeError, ValueError):
            start = math.nan
        start = start if lo <= start <= hi else 0.5 * (lo + hi)
        out.append(Variable(name, lo, hi, unit, start))
    return out


def seconds_per_run_over(scenario: Scenario, variables: Sequence[Variable]) -> float | None:
    """About how long one run takes over the variables' ranges (runs/budget.py): the mean of
    the runs at the corners of their box (a varied speed changes a run's length), its middle
    beyond 8 variables (256 corners)."""
    names = [v.name for v in variables]
    corners = list(itertools.product(*((v.lo, v.hi) for v in variables))) if len(variables) <= 8 \
        else [tuple(0.5 * (v.lo + v.hi) for v in variables)]
    return mean_seconds(seconds_of_points(scenario, [Point(i, tuple(zip(names, c)))
                                                     for i, c in enumerate(corners)]))


def _within_the_range(scenario: Scenario, inst: str, key: str, var, bounds, where: str,
                      unit: str, model: str) -> None:
    """Each bound within the range the FMU declares and, for sewfmu's own FMUs, as a run
    checks the value (runs/checks.py: also the sign the model allows, which the declared
    minimum cannot say: omega0 in (0, 2000] rad/s): a range is refused before any run, in one
    line that shows the range as declared, its brackets open or closed, and the bound with as
    many digits as tell it from the range's end (2000.0000000000005, not 2000)."""
    low, high = declared_bound(var.min), declared_bound(var.max)
    fmu = scenario.instances[inst].fmu
    params = slave_class(fmu).params_class if fmu in FMUS and fmu not in scenario.fmu_files \
        else None
    info = next((i for i in parameter_info(params) if i.name == key), None) if params else None
    shown = range_text(info) if info is not None else \
        f"[{'-inf' if low is None else f'{low:g}'}, {'inf' if high is None else f'{high:g}'}]"
    ends = [b for b in (low, high, *(info.bounds if info is not None else ())) if b is not None]
    for which, value in bounds:
        outside = (low is not None and value < low) or (high is not None and value > high)
        if not outside and info is not None:
            try:
                check_value(info, value)
            except ParameterError:
                outside = True
        if outside:
            raise ScenarioError(f"{where}: the {which} bound {_digits(value, ends)} {unit} lies "
                                f"outside the range {shown} {unit} that {inst} ({model}) "
                                f"declares for {key}")


def _digits(value: float, ends) -> str:
    """The value as %g, or every digit where %g would show it equal to a range's end."""
    text = f"{value:g}"
    return repr(value) if any(value != e and text == f"{e:g}" for e in ends) else text


def _bounds(spec: Any, where: str) -> tuple[Any, Any]:
    """The two bounds as --set takes values: numbers, or strings with their units."""
    if isinstance(spec, str):             # "800..1200 rpm": the rule of lists (value_lists.py)
        return range_in_text(spec, where)
    if isinstance(spec, np.ndarray) and spec.ndim == 1:        # np.array([lo, hi]): numbers
        spec = spec.tolist()
    if isinstance(spec, (tuple, list)) and len(spec) == 2:
        check_units_agree(list(spec), where)
        return spec[0], spec[1]
    raise ScenarioError(f"{where}: expected (low, high) or \"LO..HI unit\", got {short(spec)}")


def _in_declared_unit(scenario: Scenario, name: str, value: Any, option: str) -> float:
    """A bound as the scenario would take it with --set (units converted, names checked)."""
    probe = scenario.copy()
    probe.set_value(name, value, origin=option)
    inst, _, key = name.partition(".")
    return float(probe.instances[inst].parameters[key])


def figures_of_scenario(scenario: Scenario) -> dict[str, str]:
    """The key figures a study may ask for (figure -> unit): its analysis's."""
    if scenario.compare:
        raise ScenarioError(f"{scenario.source}: the scenario compares several runs ([compare]); "
                            f"a design study runs one: take a scenario without [compare]")
    if not scenario.analysis:
        raise ScenarioError(f"{scenario.source}: the scenario has no analysis, so no key figures "
                            f"for a design study to read")
    return scenario.figure_units()


def check_figure(name: str, known: Mapping[str, str], where: str) -> str:
    if name not in known:
        raise ScenarioError(f"{where}: unknown key figure {name!r}{did_you_mean(name, known)} "
                            f"(the figures: {', '.join(known)})")
    return name


def figures_named(known: Mapping[str, str], figures: Any) -> list[str]:
    """The figures a sensitivity analysis reads: one name or several, each a key figure."""
    figures = [figures] if isinstance(figures, str) else list(figures or [])
    if not figures:
        raise ScenarioError("--figure: name at least one key figure")
    return [check_figure(str(f), known, "--figure") for f in figures]


def figure_value(value: Any, unit: str, where: str, figure: str) -> float:
    """A figure's value given as a number (in the figure's unit) or a string with any unit of
    its kind ("25 N", "2.5 kgf", "1.9 rad" for a figure in degrees), converted as --set values
    are (format/quantities.py)."""
    value = plain(value)                  # np.float32(25), np.array(25.0): the number
    if isinstance(value, str):
        try:
            value = in_declared_unit(value, unit, figure)
        except UnitError as err:
            raise ScenarioError(f"{where}: {err}") from None
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not math.isfinite(float(value)):
        raise ScenarioError(f"{where}: expected a finite number, with its unit where it has one, "
                            f"got {short(value)}")
    return float(value)


@dataclass(frozen=True)
class Goal:
    """minimize or maximize one figure, or reach target values of one or more."""
    sense: str                                     # "minimize", "maximize", "target"
    targets: tuple[tuple[str, float], ...]         # (figure, value); value unused but in target

    @property
    def figures(self) -> list[str]:
        return [f for f, _ in self.targets]

    def objective(self, figures: Mapping[str, Any]) -> float | None:
        """What the optimizer minimizes; None where a figure has no value at the point."""
        values = [figures.get(f) for f, _ in self.targets]
        if any(not isinstance(v, (int, float)) or not math.isfinite(v) for v in values):
            return None
        if self.sense == "minimize":
            return float(values[0])
        if self.sense == "maximize":
            return -float(values[0])
        # relative misses: targets of different units weigh alike
        return float(sum(((v - t) / (abs(t) or 1.0)) ** 2
                         for v, (_, t) in zip(values, self.targets)))

    def describe(self) -> dict:
        if self.sense == "target":
            return {"target": dict(self.targets)}
        return {self.sense: self.targets[0][0]}


def goal_of(known: Mapping[str, str], minimize: str | None = None, maximize: str | None = None,
            target: Any = None) -> Goal:
    """The one goal: minimize=FIGURE, maximize=FIGURE or target={FIGURE: value} (a value
    may carry its unit; "FIGURE=VALUE unit" as the command line writes it)."""
    given = [k for k, v in (("minimize", minimize), ("maximize", maximize), ("target", target))
             if v is not None]
    if len(given) != 1:
        raise ScenarioError("give one goal: --minimize FIGURE, --maximize FIGURE or --target "
                            "\"FIGURE=VALUE unit\"" + (f" (got {', '.join(given)})" if given
                                                       else ""))
    if minimize is not None or maximize is not None:
        sense, figure = ("minimize", minimize) if minimize is not None else ("maximize", maximize)
        return Goal(sense, ((check_figure(str(figure).strip(), known, f"--{sense}"), math.nan),))
    items = _target_items(target)
    return Goal("target", tuple(
        (check_figure(f, known, "--target"), figure_value(v, known[f], "--target", f))
        for f, v in items))


def _target_items(target: Any) -> list[tuple[str, Any]]:
    texts = [target] if isinstance(target, str) else target
    if isinstance(texts, Mapping):
        items = [(str(f).strip(), v) for f, v in texts.items()]
    elif isinstance(texts, Sequence) and all(isinstance(t, str) for t in texts):
        items = []
        for text in texts:
            match = _TARGET.match(text)
            if match is None:
                raise ScenarioError(f"--target {text}: expected FIGURE=VALUE with an optional "
                                    f"unit, like \"F2_weld_mean=25 N\"")
            items.append(match.groups())
    else:
        raise ScenarioError(f"target: expected {{figure: value}}, got {short(target)}")
    if not items:
        raise ScenarioError("target: no figure given")
    return items


@dataclass(frozen=True)
class Constraint:
    figure: str
    op: str             # ">=" or "<="
    value: float
    unit: str

    def margin(self, figures: Mapping[str, Any]) -> float | None:
        """How far inside (> 0) or outside (< 0) the constraint a point lies, relative to the
        bound; None where the figure has no value there."""
        v = figures.get(self.figure)
        if not isinstance(v, (int, float)) or not math.isfinite(v):
            return None
        scale = abs(self.value) or 1.0
        return (v - self.value) / scale if self.op == ">=" else (self.value - v) / scale

    def __str__(self) -> str:
        return f"{self.figure}{self.op}{self.value:g}{' ' + self.unit if self.unit else ''}"


def constraints_of(known: Mapping[str, str], given: Sequence | None) -> list[Constraint]:
    """Constraints from "FIGURE>=VALUE unit" texts or (figure, op, value) tuples."""
    out = []
    if isinstance(given, (str, tuple)):       # one constraint, not a list of its characters
        given = [given]
    for item in given or []:
        if isinstance(item, str):
            match = _CONSTRAINT.match(item)
            if match is None:
                raise ScenarioError(f"--constraint {item}: expected FIGURE>=VALUE or "
                                    f"FIGURE<=VALUE with an optional unit, like \"F2_peak<=25 N\"")
            figure, op, value = match.groups()
        elif isinstance(item, (tuple, list)) and len(item) == 3 and item[1] in (">=", "<="):
            figure, op, value = item
        else:
            raise ScenarioError(f"constraint: expected \"FIGURE>=VALUE unit\" or (figure, '>=' or "
                                f"'<=', value), got {short(item)}")
        where = f"--constraint {figure}{op}{value}"
        check_figure(str(figure), known, where)
        out.append(Constraint(str(figure), op, figure_value(value, known[figure], where, figure),
                              known[figure]))
    return out


def evaluation_budget(max_evaluations: Any, default: int) -> int:
    """A study's budget of evaluations: None is the default; otherwise a whole number >= 1 (the
    command line's --max-evaluations takes the same), never 0 read as "the default"."""
    if max_evaluations is None:
        return default
    max_evaluations = plain(max_evaluations)
    if isinstance(max_evaluations, bool) or not isinstance(max_evaluations, int) \
            or max_evaluations < 1:
        raise ScenarioError(f"max_evaluations: a whole number >= 1, got {short(max_evaluations)}")
    return max_evaluations
