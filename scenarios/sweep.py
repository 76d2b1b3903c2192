"""Parameter sweeps: every point its own co-simulation, in worker processes or on a Dask cluster.

A sweep is a list of points, each a set of `instance.parameter = value` (or `experiment.key`)
overrides of one scenario: the Cartesian product of a grid, or an explicit list. Points run in
worker *processes* (the FMUs' Python holds one interpreter lock, so threads would not help): a
local process pool by default, Dask distributed when a scheduler address is given.

Every finished point is appended at once, as one JSON line, to `points.jsonl` in the output
folder, so an interrupted sweep resumes where it stopped: points already there are skipped. A
point that fails is recorded with its error and the sweep goes on. At the end `sweep.csv` holds
one row per point: the swept parameters, the status, and every key figure.
"""
from __future__ import annotations

import concurrent.futures as cf
import csv
import io
import itertools
import json
import multiprocessing
import os
from dataclasses import dataclass
from pathlib import Path

from .format import Scenario, ScenarioError, parse_value

POINTS_FILE = "points.jsonl"
TABLE_FILE = "sweep.csv"


@dataclass(frozen=True)
class Point:
    index: int
    values: tuple[tuple[str, object], ...]      # (instance.parameter, value), in grid order

    @property
    def key(self) -> str:
        return json.dumps(dict(self.values), sort_keys=True)

    @property
    def label(self) -> str:
        return ",".join(f"{k}={v:g}" if isinstance(v, (int, float)) else f"{k}={v}"
                        for k, v in self.values)


def grid_points(grid: dict[str, list]) -> list[Point]:
    """The Cartesian product of the grid, the first parameter varying slowest."""
    names = list(grid)
    return [Point(i, tuple(zip(names, combo)))
            for i, combo in enumerate(itertools.product(*(grid[n] for n in names)))]


def parse_grid_option(text: str) -> tuple[str, list]:
    """`instance.parameter=v1,v2,...` from the command line."""
    target, eq, values = text.partition("=")
    if not eq or not values.strip():
        raise ScenarioError(f"--grid {text}: expected instance.parameter=v1,v2,...")
    return target.strip(), [parse_value(v.strip(), f"--grid {text}") for v in values.split(",")]


def points_of(scenario: Scenario, extra_grid: dict[str, list] | None = None) -> list[Point]:
    """The points of a scenario's [sweep] table, or of the grid given on the command line."""
    spec = scenario.sweep or {}
    grid = dict(spec.get("grid", {}))
    grid.update(extra_grid or {})
    if grid and spec.get("points"):
        raise ScenarioError(f"{scenario.source}: [sweep] has both grid and points; give one")
    if spec.get("points"):
        points = [Point(i, tuple(p.items())) for i, p in enumerate(spec["points"])]
    elif grid:
        points = grid_points(grid)
    else:
        raise ScenarioError(f"{scenario.source}: nothing to sweep: no [sweep] table and no --grid")
    for point in points:                        # every override must be valid before any runs
        probe = scenario.copy()
        for target, value in point.values:
            probe.set_value(target, value, origin=f"{scenario.source}: sweep")
    return points


def run_point(scenario: Scenario, point: Point, results_dir: str | None = None) -> dict:
    """One co-simulation (in a worker): its key figures, or the error that stopped it."""
    from .runner import simulate, summarize, write_csv

    row = {"index": point.index, "key": point.key, **dict(point.values)}
    try:
        sc = scenario.copy()
        for target, value in point.values:
            sc.set_value(target, value)
        result = simulate(sc)
        figures = summarize(result)
        if results_dir:
            write_csv(result, Path(results_dir) / point.label / "results.csv")
    except Exception as err:                     # recorded, and the sweep goes on
        return {**row, "status": "failed", "error": " ".join(str(err).split())}
    figures = {k: v for k, v in figures.items() if k not in ("scenario", "master", "step")}
    return {**row, "status": "ok", **figures}


def _cost(scenario: Scenario, point: Point) -> float:
    """Expected work of a point: its number of communication steps."""

    sc = scenario.copy()
    for target, value in point.values:
        sc.set_value(target, value)
    try:
        return sc.end_time() / sc.step
    except ScenarioError:
        return 0.0


def _done(out_dir: Path) -> dict[str, dict]:
    """Points finished by an earlier (perhaps interrupted) run; a torn last line is ignored."""
    done = {}
    path = out_dir / POINTS_FILE
    if path.exists():
        for line in path.read_text().splitlines():
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                continue
            done[row["key"]] = row
    return done


def run_sweep(scenario: Scenario, points: list[Point], out_dir: Path, workers: int | None = None,
              scheduler: str | None = None, keep_results: bool = False,
              progress: bool = True) -> list[dict]:
    """Run every point not yet in out_dir; return all rows, in point order."""
    from .runner import fmus_for

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    done = _done(out_dir)
    # longest first: the last points to finish are then short ones, and the workers end together
    todo = sorted((p for p in points if p.key not in done), key=lambda p: -_cost(scenario, p))
    fmus_for(scenario)            # build once here, not concurrently in every worker
    results_dir = str(out_dir / "points") if keep_results else None
    rows = {p.key: done[p.key] for p in points if p.key in done}
    bar = _progress(len(points), len(rows), progress, scenario.name)
    with open(out_dir / POINTS_FILE, "a") as log:
        for row in _execute(scenario, todo, results_dir, workers, scheduler):
            log.write(json.dumps(row) + "\n")
            log.flush()
            rows[row["key"]] = row
            bar.update(1)
    bar.close()
    ordered = [rows[p.key] for p in points]
    _write_table(ordered, [name for name, _ in points[0].values], out_dir / TABLE_FILE)
    return ordered


def _execute(scenario, todo, results_dir, workers, scheduler):
    """Yield finished rows as they complete: Dask when a scheduler is given, else processes."""
    if not todo:
        return
    if scheduler:
        from distributed import Client, as_completed
        with Client(scheduler) as client:
            futures = [client.submit(run_point, scenario, p, results_dir, pure=False)
                       for p in todo]
            for future in as_completed(futures):
                yield future.result()
        return
    workers = workers or os.cpu_count() or 1
    # forkserver: workers fork from a clean server process that has imported sewfmu once, so
    # they start fast and do not inherit this process's loaded FMU libraries and threads
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["scenarios.runner"])
    pool = cf.ProcessPoolExecutor(max_workers=min(workers, len(todo)), mp_context=context)
    try:
        futures = [pool.submit(run_point, scenario, p, results_dir) for p in todo]
        for future in cf.as_completed(futures):
            yield future.result()
    except BaseException:
        # Ctrl-C (or any error): stop the workers now rather than after their current point;
        # what finished is already in points.jsonl, and a rerun resumes from there
        workers_alive = list(getattr(pool, "_processes", {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for process in workers_alive:
            process.terminate()
        for process in workers_alive:
            process.join(timeout=5)
        raise
    pool.shutdown(wait=True)


def _write_table(rows: list[dict], swept: list[str], path: Path) -> None:
    from .runner import _write_atomic

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

    _write_atomic(path, write)


class _NoBar:
    def update(self, n):
        pass

    def close(self):
        pass


def _progress(total: int, already: int, enabled: bool, name: str):
    if not enabled:
        return _NoBar()
    from tqdm import tqdm
    return tqdm(total=total, initial=already, desc=f"sweep {name}", unit="point")


def plot_table(rows: list[dict], swept: list[str], figures: list[str], path: Path,
               title: str) -> None:
    """Each key figure against each swept parameter; one line per combination of the others."""
    import textwrap

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in rows if r["status"] == "ok"]
    fig, axes = plt.subplots(len(figures), len(swept), figsize=(4.2 * len(swept),
                                                                  2.6 * len(figures)),
                             squeeze=False)
    for j, param in enumerate(swept):
        others = [s for s in swept if s != param]
        groups: dict[tuple, list[dict]] = {}
        for r in ok:
            groups.setdefault(tuple(r[o] for o in others), []).append(r)
        for i, figure in enumerate(figures):
            ax = axes[i][j]
            for group, members in sorted(groups.items()):
                members = sorted(members, key=lambda r: r[param])
                ys = [r.get(figure) for r in members]
                if any(y is None for y in ys):
                    continue
                ax.plot([r[param] for r in members], ys, "o-", ms=3, lw=1, alpha=0.8,
                        label=", ".join(f"{o.split('.')[-1]}={g:g}" for o, g in zip(others, group)))
            ax.set(xlabel=param if i == len(figures) - 1 else "", ylabel=figure if j == 0 else "")
            ax.grid(alpha=0.3)
        axes[0][j].legend(fontsize=6, ncol=1, loc="best")
    failed = len(rows) - len(ok)
    fig.suptitle("\n".join(textwrap.wrap(title + (f" ({failed} points failed)" if failed else ""),
                                         100)), fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
