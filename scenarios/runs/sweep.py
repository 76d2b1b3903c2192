"""Parameter sweeps: every point its own co-simulation, in worker processes or on a Dask cluster.

A sweep is a list of points, each a set of `instance.parameter = value` (or `experiment.key`)
overrides of one scenario: the Cartesian product of a grid, or an explicit list. Points run in
worker *processes* (the FMUs' Python holds one interpreter lock, so threads would not help): a
local pool (scenarios/runs/workers.py) by default, Dask distributed when a scheduler address is given.

Every finished point is appended at once, as one JSON line, to `points.jsonl` in the output
folder. A point is identified by everything that decides its result: the scenario's content with
the fixed settings, the point's own values and the code of the FMUs. A rerun into the same folder
reuses the points whose identity it finds there (an interrupted sweep resumes), recomputes what
changed, and tries again the points that failed. A point that fails, or whose worker process
dies, is recorded with its cause and the sweep goes on. At the end `sweep.csv` holds one row per
point: the swept parameters, the status, and every key figure.
"""
from __future__ import annotations

import csv
import hashlib
import io
import itertools
import json
import os
import textwrap
from dataclasses import dataclass
from pathlib import Path

from sewfmu.components.registry import FMUS
from sewfmu.extras import require
from sewfmu.scenarios.files.matplotlib_home import pyplot
from sewfmu.scenarios.files.outputs import (
    Placing,
    claim,
    folder_for,
    held,
    refuse_theirs,
    remove_debris,
    replacing,
    write_atomic,
)
from sewfmu.scenarios.fmu_build.sources import fmu_version
from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
from sewfmu.scenarios.format.declared_units import parameter_units
from sewfmu.scenarios.format.experiment import EXPERIMENT_KEYS, experiment_of
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.value_lists import grid_values, values_in_text
from sewfmu.scenarios.format.values import ScenarioError, check_scenario_name, label_of
from sewfmu.scenarios.mechanisms.base import figures_of
from sewfmu.scenarios.runs.budget import product, seconds_per_run, worker_count
from sewfmu.scenarios.runs.checks import check_values
from sewfmu.scenarios.runs.progress import bar as progress_line
from sewfmu.scenarios.runs.report import sweep_report
from sewfmu.scenarios.runs.results import as_run, write_csv
from sewfmu.scenarios.runs.runner import simulate, summarize
from sewfmu.scenarios.runs.studies import study_summary
from sewfmu.scenarios.runs.sweep_record import (
    POINTS_FILE,
    TABLE_FILE,
    finished_points,
    open_log,
    warn,
)
from sewfmu.scenarios.runs.workers import run_tasks


@dataclass(frozen=True)
class Point:
    index: int
    values: tuple[tuple[str, object], ...]      # (instance.parameter, value), in grid order

    @property
    def label(self) -> str:
        return ",".join(label_of(k, v) for k, v in self.values)

    def identity(self, settings: str) -> str:
        """The point's key: a hash of the sweep's settings (see `settings_of`) and its values."""
        text = json.dumps({"settings": settings, "point": dict(self.values)}, sort_keys=True)
        return hashlib.sha256(text.encode("utf-8")).hexdigest()[:32]


def settings_of(scenario: Scenario, fmu_paths: dict[str, Path]) -> str:
    """Everything besides a point's own values that decides its result: the scenario's content
    with the fixed settings applied, and the version (with code hash) of every FMU it runs."""

    content = {
        "instances": {n: {"fmu": i.fmu, "parameters": i.parameters}
                      for n, i in scenario.instances.items()},
        "connections": [str(c) for c in scenario.connections],
        "record": scenario.record, "analysis": scenario.analysis, "roles": scenario.roles,
        "study": scenario.study,
        "experiment": experiment_of(scenario),
        "fmus": {fmu: fmu_version(Path(path)) for fmu, path in sorted(fmu_paths.items())},
    }
    return json.dumps(content, sort_keys=True, default=repr)


def grid_points(grid: dict[str, list]) -> list[Point]:
    """The Cartesian product of the grid, the first parameter varying slowest."""
    names = list(grid)
    return [Point(i, tuple(zip(names, combo)))
            for i, combo in enumerate(itertools.product(*(grid[n] for n in names)))]


def parse_grid_option(text: str) -> tuple[str, list]:
    """`instance.parameter=v1,v2,... unit` from the command line (a unit after the last value
    applies to all: format/value_lists.py)."""
    target, eq, values = text.partition("=")
    if not eq or not values.strip():
        raise ScenarioError(f"--grid {text}: expected instance.parameter=v1,v2,...")
    return target.strip(), values_in_text(values, f"--grid {target.strip()}")


def refuse_fixed_and_varied(fixed, varied, role: str, where: str) -> None:
    """A parameter both given a value for every run (--set, set=) and varied (`role`: swept,
    varied, free; `where`: the option that varies it) is refused in one line: one of the two
    would be silently ignored."""
    fixed_names = {str(name).strip() for name in (fixed or {})}
    both = [str(name).strip() for name in varied if str(name).strip() in fixed_names]
    if both:
        raise ScenarioError(f"{both[0]} is both fixed (--set, set=) and {role} ({where}): a "
                            f"parameter is either fixed for every run or {role}; give it in "
                            f"one of the two")


LENGTHS = ("experiment.revolutions", "experiment.stop_time")


def refuse_lengths_given_twice(scenario: Scenario, fixed, grid) -> None:
    """refuse_two_lengths for each point a sweep makes: the fixed values (--set, set=) with the
    swept names (--grid, grid=, the [sweep] table's grid, each of its points)."""
    table, spec = f"the [sweep] table of {scenario.source}", scenario.sweep or {}
    given = {str(k): "--set, set=" for k in (fixed or {})}
    refuse_two_lengths({**given, **{k: table for k in spec.get("grid", {})},
                        **{k: "--grid, grid=" for k in grid}})
    for each in spec.get("points", []):
        refuse_two_lengths({**given, **{k: table for k in each}})


def refuse_two_lengths(given: dict[str, str]) -> None:
    """A run's length is exactly one of experiment.revolutions and experiment.stop_time: both
    given for one run (`given`: each name set or swept -> where, "--set, set=", "--grid,
    grid=", a [sweep] table) is refused in one line, since the one given last would silently
    replace the other."""
    names = {str(name).strip(): where for name, where in given.items()}
    if all(length in names for length in LENGTHS):
        (a, b) = LENGTHS
        raise ScenarioError(f"{a} ({names[a]}) and {b} ({names[b]}) are both given: a run "
                            f"takes exactly one of revolutions and stop_time, and one would be "
                            f"silently ignored; give one of the two")


def seconds_of_points(scenario: Scenario, points: list[Point]) -> list[float | None]:
    """About how long each point's run takes (runs/budget.py), with its own values: a point
    that changes the step, the length or the shaft's speed changes its number of steps."""
    out = []
    for point in points:
        sc = scenario.copy()
        for target, value in point.values:
            sc.set_value(target, value)
        out.append(seconds_per_run(sc))
    return out


def count_points(scenario: Scenario, lengths: dict[str, int]) -> tuple[int, str]:
    """How many points the scenario's [sweep] table with a grid of these lengths (parameter ->
    number of values, added to the table's grid) makes, and what makes them, without making
    them: a grid is checked against the bound on runs before it takes any memory."""
    spec = scenario.sweep or {}
    axes = {**{k: len(v) for k, v in spec.get("grid", {}).items()}, **lengths}
    if spec.get("points") and not axes:
        return len(spec["points"]), "the [sweep] table's points"
    return product(axes.values()), "a grid of " + " × ".join(f"{n:,}" for n in axes.values())


def points_of(scenario: Scenario, extra_grid: dict[str, list] | None = None) -> list[Point]:
    """The points of a scenario's [sweep] table, or of the grid given on the command line."""
    spec = scenario.sweep or {}
    grid = {name: grid_values(values, f"{scenario.source}: sweep.grid.{name}")
            for name, values in spec.get("grid", {}).items()}
    grid.update({name: grid_values(values, f"grid {name}")
                 for name, values in (extra_grid or {}).items()})
    if grid and spec.get("points"):
        raise ScenarioError(f"{scenario.source}: [sweep] has both grid and points; give one")
    if spec.get("points"):
        points = [Point(i, tuple(p.items())) for i, p in enumerate(spec["points"])]
    elif grid:
        points = grid_points(grid)
    else:
        raise ScenarioError(f"{scenario.source}: nothing to sweep: no [sweep] table and no --grid")
    seen = {}
    for point in points:
        values = json.dumps(dict(point.values), sort_keys=True)
        if values in seen:
            raise ScenarioError(f"{scenario.source}: sweep: points {seen[values]} and "
                                f"{point.index} are the same ({point.label})")
        seen[values] = point.index
    folders = {}
    for point in points:                        # each point's results go to a folder of its own
        name = folder_for(Path("."), point.label).name
        if name in folders:
            raise ScenarioError(f"{scenario.source}: sweep: points {folders[name]} and "
                                f"{point.index} would share the folder {name!r}")
        folders[name] = point.index
    numeric = []
    for point in points:                        # every override must be valid before any runs
        probe = scenario.copy()
        for target, value in point.values:
            probe.set_value(target, value, origin=swept_from(scenario, target))
        probe.refuse_converted_beyond_range()   # as given, while its unit is known
        # "30 N/mm" and 30000 are one value: the table, the plots and the folders hold the
        # number in the declared unit, as the run used it
        numeric.append(Point(point.index, tuple((target, _as_used(probe, target, value))
                                                for target, value in point.values)))
    return numeric


def swept_from(scenario: Scenario, target: str) -> str:
    """Where a swept value was given, for a refusal to name: the scenario's [sweep] table, or
    the grid the command line or the API added (a file the user never touched is no origin)."""
    spec = scenario.sweep or {}
    table = {*spec.get("grid", {}), *(k for p in spec.get("points", []) for k in p)}
    return f"{scenario.source}: sweep" if target in table else "--grid (grid=)"


def _as_used(scenario: Scenario, target: str, given):
    """A swept value as the scenario holds it after set_value (a parameter with a unit: the
    number in the declared unit); an experiment key as given."""
    inst, _, key = target.partition(".")
    if inst != "experiment" and isinstance(given, str):
        return scenario.instances[inst].parameters.get(key, given)
    return given


# what the worker processes' fork server imports once, so that no worker imports it again
# (multiprocessing ignores a name it cannot import: tests/runs/test_sweep.py imports them)
WORKER_PRELOAD = ["sewfmu.scenarios.runs.runner", "sewfmu.scenarios.cosim.master"]


# a row's field (never logged) naming the results.csv a worker wrote for the sweep to place
PENDING = "_results_written"


def run_point(scenario: Scenario, point: Point, key: str, results_dir: str | None = None) -> dict:
    """One co-simulation (in a worker): its key figures, or the error that stopped it. With
    results_dir (the output folder), its results.csv is written there under a temporary name
    (PENDING in the row): the sweep's process checks and moves it to the point's folder
    (outputs.Placing), so that no worker writes over a file or through a link."""

    row = {"index": point.index, "key": key, **dict(point.values)}
    try:
        sc = scenario.copy()
        for target, value in point.values:
            sc.set_value(target, value)
        if sc.study:                             # computed, not co-simulated
            figures = study_summary(sc)[1]
            return {**row, "status": "ok", **figures_of(figures)}
        result = simulate(sc)
        figures = summarize(result)
        pending = Path(results_dir) / f".point-{key}.results.csv.sewfmu-{os.getpid()}.tmp" \
            if results_dir else None
        if pending is not None:
            write_csv(result, pending)
    except Exception as err:                     # recorded, and the sweep goes on
        return failed_row(row, err)
    return {**row, "status": "ok", "stop_time": figures["stop_time"], **figures_of(figures),
            **({PENDING: str(pending)} if pending is not None else {})}


def run_points(scenario: Scenario, points: list[Point], keys: list[str],
               results_dir: str | None = None) -> list[dict]:
    """Several points, one after another (a Dask task): their rows."""
    return [run_point(scenario, p, key, results_dir) for p, key in zip(points, keys)]


def failed_row(row: dict, err: Exception) -> dict:
    return {**row, "status": "failed", "error": " ".join(str(err).split())}


def run_sweep(scenario: Scenario, points: list[Point], out_dir: Path, workers: int | None = None,
              scheduler: str | None = None, keep_results: bool = False,
              progress: bool = True, on_point=None, outputs=(), finish=None,
              announce=None) -> list[dict]:
    """Run every point not yet done in out_dir; return all rows, in point order.
    `on_point(row)`, if given, hears of each row as it is logged; `announce()` is called once
    the folder is checked, before the first run (the count and the estimate: a refused folder
    is the command's one line). The folder's files follow
    files/outputs.py's one rule: every file the sweep will write (its record, its table, each
    point's results, and `outputs`, the names `finish(staging, rows)` writes at the end: the
    pictures, a study's files) is checked before the first point runs, and a file of one of
    those names that sewfmu did not write there is refused in one line."""

    workers = worker_count(workers)
    out_dir = Path(out_dir)
    paths = fmus_for(scenario)            # built once here, not concurrently in every worker
    for point in points:                  # a misspelt parameter fails here, before any point
        probe = scenario.copy()
        for target, value in point.values:
            probe.set_value(target, value, origin=swept_from(scenario, target))
        check_values(probe, paths)
    results = {p.index: f"points/{folder_for(Path('.'), p.label).name}/results.csv"
               for p in points} if keep_results else {}
    with held(out_dir):         # its record is this sweep's alone while it runs
        # every file the sweep will write, checked before anything is written: the check
        # its files pass again as they take their places (outputs.replacing, Placing)
        refuse_theirs(out_dir, [POINTS_FILE, TABLE_FILE, *results.values(), *outputs])
        if announce is not None:
            announce()
        out_dir.mkdir(parents=True, exist_ok=True)
        remove_debris(out_dir, recursive=True)
        settings = settings_of(scenario, paths)
        keys = {p.index: p.identity(settings) for p in points}
        claim(out_dir, [POINTS_FILE])
        done = finished_points(out_dir)
        # longest first: the last points to finish are then short ones, and the workers end together
        todo = [p for p in points if keys[p.index] not in done]
        cost = dict(zip((p.index for p in todo), seconds_of_points(scenario, todo)))
        todo.sort(key=lambda p: -(cost[p.index] or 0.0))
        placing = Placing(out_dir) if keep_results else None
        index_of = {keys[p.index]: p.index for p in points}
        rows = {keys[p.index]: done[keys[p.index]] for p in points if keys[p.index] in done}
        bar = progress_line(len(points), f"sweep {scenario.name}", "point", initial=len(rows),
                            enabled=progress)
        with open_log(out_dir / POINTS_FILE) as log:
            for row in _execute(scenario, todo, keys, str(out_dir) if keep_results else None,
                                workers, scheduler):
                pending = row.pop(PENDING, None)
                if pending is not None:          # listed before its point is: never unlisted
                    placing.place(Path(pending), results[index_of[row["key"]]])
                log.write(json.dumps(row) + "\n")
                rows[row["key"]] = row
                bar.update(1)
                if on_point is not None:
                    on_point(dict(row))
        bar.close()
        ordered = [{**rows[keys[p.index]], "index": p.index} for p in points]
        with replacing(out_dir, kept=[POINTS_FILE, *results.values()]) as staging:
            _write_table(ordered, [name for name, _ in points[0].values], staging / TABLE_FILE)
            if finish is not None:
                finish(staging, ordered)
        return ordered


def _execute(scenario, todo, keys, results_dir, workers, scheduler):
    """Yield finished rows as they complete: Dask when a scheduler is given, else processes."""
    if not todo:
        return
    if scheduler:
        distributed = require("distributed", "a sweep on a Dask scheduler")
        Client, as_completed = distributed.Client, distributed.as_completed
        with Client(scheduler) as client:
            # the scenario goes to every worker once, not with every point; the points go in
            # batches, a few per worker slot, so that a point costs its run and not a task's
            # round trip through the scheduler
            shared = client.scatter(scenario, broadcast=True)
            slots = max(1, sum(client.nthreads().values()))
            size = max(1, min(8, len(todo) // (4 * slots)))
            batches = [todo[k:k + size] for k in range(0, len(todo), size)]
            futures = [client.submit(run_points, shared, batch,
                                     [keys[p.index] for p in batch], results_dir, pure=False)
                       for batch in batches]
            for future in as_completed(futures):
                yield from future.result()
        return

    by_key = {keys[p.index]: p for p in todo}
    tasks = [(keys[p.index], run_point, (scenario, p, keys[p.index], results_dir)) for p in todo]
    for key, answer in run_tasks(tasks, workers or os.cpu_count() or 1,
                                 preload=WORKER_PRELOAD):
        if isinstance(answer, Exception):      # the worker died, or run_point itself failed
            point = by_key[key]
            yield failed_row({"index": point.index, "key": key, **dict(point.values)}, answer)
        else:
            yield answer


def _write_table(rows: list[dict], swept: list[str], path: Path) -> None:
    columns = ["index"] + swept + ["status"]
    for row in rows:
        for key in row:
            if key not in columns and key not in ("key", "error"):
                columns.append(key)
    columns.append("error")

    def write(f: io.TextIOBase):
        writer = csv.DictWriter(f, fieldnames=columns, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(rows)

    write_atomic(path, write)


def _numeric(values) -> bool:
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)


def _shown(value, unit: str) -> str:
    return f"{value:g}{' ' + unit if unit else ''}" if _numeric([value]) else str(value)


def declared_unit(scenario: Scenario, target: str) -> str:
    """The unit a swept `instance.parameter` (as its FMU declares it) or experiment key is held
    in: the unit of its axis."""
    inst, _, key = target.partition(".")
    if inst == "experiment":
        return EXPERIMENT_KEYS[key].unit if key in EXPERIMENT_KEYS else ""
    fmu = scenario.instances[inst].fmu if inst in scenario.instances else None
    # an FMU from another tool declares its units in its file: the axis names none
    if fmu not in FMUS or fmu in scenario.fmu_files:
        return ""
    return parameter_units(fmu).get(key, "")


def sweep_title(scenario: Scenario, rows: list[dict], swept: list[str]) -> str:
    """What was run, as it was run: the scenario's description may name a length the sweep's
    settings changed (it says 10 revolutions; --set made them 3)."""

    failed = sum(1 for r in rows if r["status"] != "ok")
    head = (f"{scenario.name}: {', '.join(swept)} swept, {len(rows)} points"
            f"{f' ({failed} failed)' if failed else ''}")
    if scenario.study:                     # computed at each point, not co-simulated
        return f"{head}; the study computed at each"
    if "experiment.revolutions" in swept or "experiment.stop_time" in swept:
        return f"{head}; each of the length as swept, step {scenario.step * 1e3:g} ms, " \
               f"{scenario.master} master"
    return f"{head}; each {as_run(scenario).removeprefix('as run: ')}"


def sweep_figure(rows: list[dict], swept: list[str], figures: dict[str, str],
                 units: dict[str, str], title: str):
    """Each key figure (figure -> unit) against each swept parameter (units: parameter ->
    unit), one line per combination of the others: a matplotlib Figure. A numeric parameter is
    spaced by its values; any other (a master's name) is one tick per value."""
    plt = pyplot()          # matplotlib, its files out of the user's home

    ok = [r for r in rows if r["status"] == "ok"]
    # one column is wide enough for the title's lines; constrained layout keeps the title and
    # the labels inside the picture (tight_layout left a long suptitle clipped)
    width = max(6.4, 4.2 * len(swept))
    fig, axes = plt.subplots(len(figures), len(swept), figsize=(width, 0.6 + 2.6 * len(figures)),
                             squeeze=False, layout="constrained")
    for j, param in enumerate(swept):
        others = [s for s in swept if s != param]
        values = list(dict.fromkeys(r[param] for r in rows))
        numeric = _numeric(values)
        where = (lambda v: v) if numeric else values.index
        groups: dict[tuple, list[dict]] = {}
        for r in ok:
            groups.setdefault(tuple(r[o] for o in others), []).append(r)
        for i, (figure, unit) in enumerate(figures.items()):
            ax = axes[i][j]
            # numbers in their order (5 before 10), names after them: mixed values sort too
            for group, members in sorted(groups.items(), key=lambda g: [
                    (0, v, "") if _numeric([v]) else (1, 0, str(v)) for v in g[0]]):
                members = sorted(members, key=lambda r: where(r[param]))
                ys = [r.get(figure) for r in members]
                if any(y is None for y in ys):
                    continue
                ax.plot([where(r[param]) for r in members], ys, "o-", ms=3, lw=1, alpha=0.8,
                        label=", ".join(f"{o.split('.')[-1]}={_shown(g, units.get(o, ''))}"
                                        for o, g in zip(others, group)))
            if not numeric:
                ax.set_xticks(range(len(values)), [str(v) for v in values])
            axis = f"{param} [{units[param]}]" if units.get(param) else param
            # a long figure name on lines of its own, so that it stays inside the picture
            ylabel = "\n".join(textwrap.wrap(figure.replace("_", " "), 24)) if len(figure) > 24 \
                else figure
            ax.set(xlabel=axis if i == len(figures) - 1 else "",
                   ylabel=f"{ylabel} [{unit}]" if unit else ylabel)
            ax.grid(alpha=0.3)
        if axes[0][j].get_legend_handles_labels()[0]:      # one swept parameter: no legend
            axes[0][j].legend(fontsize=6, ncol=1, loc="best")
    # about 0.6 of the font size per character: the lines fit the figure's width
    fig.suptitle("\n".join(textwrap.wrap(title, int(width * 72 / (10 * 0.6)) - 4)), fontsize=10)
    return fig


def plot_table(rows: list[dict], swept: list[str], figures: dict[str, str], path: Path,
               title: str, units: dict[str, str]) -> None:
    """The figure of sweep_figure, as a PNG."""
    plt = pyplot()          # matplotlib, its files out of the user's home
    fig = sweep_figure(rows, swept, figures, units, title)
    write_atomic(path, lambda f: fig.savefig(f, dpi=100, format="png"), binary=True)
    plt.close(fig)


def sweep_pictures(scenario: Scenario, rows: list[dict], swept: list[str], out_dir: Path,
                   report: bool = False) -> None:
    """The plot of every key figure against the swept parameters (SCENARIO_sweep.png) and, with
    report, report.html beside sweep.csv."""
    check_scenario_name(scenario.name)      # NAME_sweep.png: never a path out of out_dir
    picture = out_dir / f"{scenario.name}_sweep.png"
    if scenario.analysis:
        figures = {f: unit for f, unit in scenario.figure_units().items()
                   if f != "n_contacts"}
        plot_table(rows, swept, figures, picture, sweep_title(scenario, rows, swept),
                   {param: declared_unit(scenario, param) for param in swept})
    else:                                   # asked for, and no key figure to draw
        warn(f"the sweep's plot is left out: {scenario.name} has no analysis (no mechanism of "
             f"sewfmu's named by `analysis`), so its points have no key figures to draw; "
             f"sweep.csv holds each point's status")
    if report:
        sweep_report(out_dir / "report.html", scenario, rows, swept,
                     picture if scenario.analysis else None)
