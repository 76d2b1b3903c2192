"""sewfmu from Python: what the command line does, as functions that return numbers with units.

    import sewfmu
    r = sewfmu.run("punch_drive", set={"shaft.omega0": 300.0})
    r.summary["F2_weld_mean"], r.units["F2_weld_mean"]      # key figures, as in summary.json
    r.series["time"], r.series["punch.F2"]                  # numpy structured array (FMPy's habit)

A scenario is a catalogue name, a path to a TOML file or an SSP archive, or a Scenario from
`load`. `set` takes what `--set` takes: {"instance.parameter": value, "experiment.key": value},
a value a number or a string with its unit ("955 rpm", "0.25 ms"). Nothing is written unless
`out` is given; then the same files as the command line's are written there. Errors are the
command line's: ScenarioError (a bad scenario or value), CosimError (a run that fails), each
with one line that says what is wrong. docs/api.md shows every function at work.
"""
from __future__ import annotations

import contextlib
import tempfile
from pathlib import Path
from typing import Any, Callable, Mapping

from sewfmu.arguments import (
    callback,
    flag,
    mapping,
    one_line,
    progress_of,
    reading,
)
from sewfmu.arguments import folder as _folder
from sewfmu.components.parameters import did_you_mean
from sewfmu.components.registry import FMUS
from sewfmu.results import InaccurateRun, Run, Sweep, SweepFailed, _run_of
from sewfmu.scenarios.cosim.interrupt import (
    Interrupted,
    deferred,
)
from sewfmu.scenarios.files.outputs import cannot_write, held, refuse_theirs
from sewfmu.scenarios.format.built import checked_copy
from sewfmu.scenarios.format.loader import catalogue as catalogue_files
from sewfmu.scenarios.format.loader import load as _load_scenario
from sewfmu.scenarios.format.loader import resolve
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.value_lists import grid_values
from sewfmu.scenarios.format.values import ScenarioError, parse_value, plain
from sewfmu.scenarios.runs import budget
from sewfmu.scenarios.runs.budget import worker_count

__all__ = ["load", "check", "run", "sweep", "compare", "build", "show", "parameters", "catalogue",
           "read_value", "optimize", "fit", "sensitivity", "Run", "Sweep", "Scenario",
           "ScenarioError", "InaccurateRun", "SweepFailed"]


def catalogue() -> list[str]:
    """The names of the catalogue's scenarios."""
    return sorted(catalogue_files())


@one_line
def read_value(text: str) -> Any:
    """A value typed as text, as `--set` reads it: a number, true or false or a quoted string
    (TOML's scalars), else the text itself, a value with its unit for `set=` ("955 rpm"). A form
    reads what a user typed with it (docs/scenarios.md, "Values with units")."""
    return parse_value(text, "value")


@one_line
def load(scenario: str | Path | Scenario, set: Mapping[str, Any] | None = None) -> Scenario:
    """A scenario (catalogue name, TOML or SSP path) with the `set` overrides applied; a Scenario
    given is copied, never changed."""
    set = mapping(set, "set", "'instance.parameter': value", scalars=True)    # read once, here
    if isinstance(scenario, Scenario):
        # built in Python: every field checked as a file's are (format/built.py)
        loaded = checked_copy(scenario)
        for inst in loaded.instances.values():       # a value with a unit, a numpy number:
            for key, value in list(inst.parameters.items()):     # as --set would take it
                if not isinstance(value, (bool, int, float)):
                    loaded.set_value(f"{inst.name}.{key}", value, origin="Instance")
    elif isinstance(scenario, (str, Path)):
        loaded = _load_scenario(str(scenario))
    else:
        raise ScenarioError(f"a scenario is a catalogue name, a path or a Scenario, got "
                            f"{type(scenario).__name__}")
    if set and {"experiment.revolutions", "experiment.stop_time"} <= {str(k).strip() for k in set}:
        from sewfmu.scenarios.runs.sweep import refuse_two_lengths  # only when both are given

        refuse_two_lengths({k: "set=" for k in set})      # a run's length: exactly one of them
    for target, value in (set or {}).items():
        loaded.set_value(str(target), value, origin="set")
    return loaded


@one_line
def check(scenario: str | Path | Scenario, set: Mapping[str, Any] | None = None) -> Scenario:
    """load(), then every value checked as a run checks it before its first step (each against
    its FMU's declared type and range, an input fed by a connection refused), nothing run: the
    Scenario, or a ScenarioError naming the first bad value."""
    from sewfmu.scenarios.runs.checks import check_values

    loaded = load(scenario, set)
    check_values(loaded)
    return loaded


@one_line
def show(scenario: str) -> str:
    """A catalogue scenario's TOML text: save it, change it, run it (`sewfmu show`); one of
    sewfmu's FMUs by name (PunchContact): its inputs, outputs and parameters."""
    from sewfmu.scenarios.format.parameter_table import (
        component_text,
    )

    if isinstance(scenario, str) and scenario in FMUS:
        return component_text(scenario)
    if not isinstance(scenario, (str, Path)):
        raise ScenarioError(f"show: expected a catalogue name, a path to a .toml file or one of "
                            f"sewfmu's FMUs, got {type(scenario).__name__}")
    path = resolve(str(scenario))
    if path.suffix.lower() != ".toml":
        raise ScenarioError(f"{scenario}: only TOML scenarios can be shown (an SSP archive is "
                            f"read by sewfmu, not written back as TOML)")
    return path.read_text(encoding="utf-8-sig")


@one_line
def parameters(name: str | Path | Scenario, set: Mapping[str, Any] | None = None):
    """The parameters a user may set, as a table (a list of dicts with instance, parameter,
    default, value, unit, range, meaning; print() shows it as `sewfmu show NAME --parameters`):
    of one of sewfmu's FMUs by name, or of every instance of a scenario (its values, `set`
    applied, in `value`)."""
    from sewfmu.scenarios.format.parameter_table import (
        component_rows,
        scenario_rows,
    )

    if isinstance(name, str) and name in FMUS:
        if set:
            raise ScenarioError(f"{name}: set= gives values to a scenario's instances; an FMU "
                                f"by name shows its defaults")
        return component_rows(name)
    return scenario_rows(load(name, set))


@one_line
def run(scenario: str | Path | Scenario, set: Mapping[str, Any] | None = None, *,
        out: str | Path | None = None, plot: bool = False, animate: bool = False,
        report: bool = False, fmu_dir: str | Path | None = None, progress: bool = False) -> Run:
    """Run a scenario; with `out`, write what `sewfmu run --out` writes (plot, animate and report
    as its options). A scenario with [compare] gives a Run whose `runs` holds one Run per
    value (its summary is summary.json's, the figures per run under "runs"). `progress` shows
    a progress bar on the terminal; a function instead, `progress(done, total)`, hears of the
    communication steps as they are done (a page's progress bar)."""
    from sewfmu.scenarios.runs import accuracy
    from sewfmu.scenarios.runs.progress import TerminalProgress
    from sewfmu.scenarios.runs.results import (
        outputs_of,
        write_outputs,
    )
    from sewfmu.scenarios.runs.variants import (
        run_variants,
        summary_of_runs,
    )

    sc = load(scenario, set)
    out, fmu_dir = _folder(out, "out"), _folder(fmu_dir, "fmu_dir")
    plot, animate, report = flag(plot, "plot"), flag(animate, "animate"), flag(report, "report")
    progress = progress_of(progress)
    if (plot or animate or report) and out is None:
        raise ScenarioError("plot, animate and report are files: give out= a folder for them")
    # the folder is this run's from its first step to its last file (a sweep's is refused)
    with held(Path(out)) if out is not None else contextlib.nullcontext():
        if out is not None:         # a user's file where it would write: refused before it runs
            refuse_theirs(Path(out), outputs_of(sc, plot, animate, report))
        if sc.study:
            return _study_run(sc, out, plot, animate, report)
        bar = TerminalProgress(sc.name) if progress is True else None
        told = (lambda label, done, total: progress(done, total)) if callable(progress) else bar
        try:
            runs = run_variants(sc, Path(fmu_dir) if fmu_dir else None, told)
        except Interrupted as err:
            # the record so far as a sewfmu.Run (err.result stays the engine's, for the CLI)
            err.run = None if err.result is None else _run_of(
                sc.name, err.result, {}, None, sc.shaft or sc.default_shaft())
            raise
        finally:
            if bar is not None:
                bar.close()
        if out is not None:
            try:
                # a signal while the files are written is answered once they are, whole: the
                # finished run is not thrown away (a few seconds at most; no FMU is called)
                with deferred():
                    write_outputs(sc, runs, Path(out), plot=plot, animate=animate,
                                  report=report)
            except Interrupted as err:
                err.where, err.kept = "after the run", f"its files are written whole in {out}"
                raise
            except OSError as err:
                raise cannot_write(err, out) from None
    out = Path(out) if out is not None else None
    each = {label: _run_of(label or sc.name, result, own, out, sc.shaft or sc.default_shaft())
            for label, result, own in runs}
    made = each[""] if not sc.compare else \
        Run(sc.name, summary_of_runs(sc, runs), None, {}, out, runs=each)
    beyond = [f"{label + ': ' if label else ''}{line}" for label, _, own in runs
              for line in accuracy.beyond(own, sc.accuracy)]
    if beyond and not sc.accept_error:
        raise InaccurateRun(f"{sc.name}: the coupling error is beyond experiment.accuracy = "
                            f"{sc.accuracy:g} of each figure: {'; '.join(beyond)}; take a "
                            f"shorter experiment.step (or another master), or accept it with "
                            f"experiment.accept_error = true", made)
    return made


def _study_run(sc: Scenario, out, plot: bool, animate: bool, report: bool) -> Run:
    from sewfmu.scenarios.runs.studies import run_study

    if animate:
        raise ScenarioError(f"animate: the study {sc.name} is computed, not a run of the "
                            f"mechanism; run a scenario (sewfmu scenarios) to see one move")
    try:
        data, summary = run_study(sc, Path(out) if out is not None else None, plot, report)
    except OSError as err:
        raise cannot_write(err, out) from None
    return Run(sc.name, summary, None, dict(summary["units"]),
               Path(out) if out is not None else None, study=data)


@one_line
def sweep(scenario: str | Path | Scenario, grid: Mapping[str, list] | None = None,
          set: Mapping[str, Any] | None = None, *, workers: int | None = None,
          scheduler: str | None = None, out: str | Path | None = None, plot: bool = False,
          report: bool = False, progress: bool = False, results: bool = False,
          on_point: Callable[[dict], None] | None = None, max_runs: int | None = None) -> Sweep:
    """Run a grid of points in parallel: the scenario's [sweep] table, or `grid`
    ({"instance.parameter": [values]}, added to it). With `out`, what `sewfmu sweep --out`
    writes (and an interrupted sweep into the same folder resumes); `results` keeps each point's
    results.csv there. `on_point(row)` hears of each point as it finishes (its row as in
    `rows`, in the order they finish). A sweep whose every point failed is a ScenarioError.
    The points are counted before any is made: more than `max_runs` (default 10,000, or
    SEWFMU_MAX_RUNS) is refused; the count and a time estimate go to stderr before the first
    run, with `progress` or where it will take long."""
    from sewfmu.scenarios.runs.sweep import (
        count_points,
        declared_unit,
        points_of,
        refuse_fixed_and_varied,
        refuse_lengths_given_twice,
        run_sweep,
        seconds_of_points,
        sweep_pictures,
    )

    set = mapping(set, "set", "'instance.parameter': value", scalars=True)    # read once, here
    sc = load(scenario, set)
    grid = mapping(grid, "grid", "'instance.parameter': [values]") or {}
    spec = sc.sweep or {}
    refuse_fixed_and_varied(set, grid, "swept", "--grid, grid=")
    refuse_fixed_and_varied(set, [*spec.get("grid", {}), *(k for p in spec.get("points", [])
                                                           for k in p)],
                            "swept", f"the [sweep] table of {sc.source}")
    refuse_lengths_given_twice(sc, set, grid)   # one set, the other swept: one ignored
    if scheduler is not None and (not isinstance(scheduler, str) or "://" not in scheduler):
        raise ScenarioError(f"scheduler: expected a Dask scheduler's address such as "
                            f"'tcp://127.0.0.1:8786', got {scheduler!r}")
    workers = worker_count(workers)
    out = _folder(out, "out")
    plot, report, results = flag(plot, "plot"), flag(report, "report"), flag(results, "results")
    progress, on_point = flag(progress, "progress"), callback(on_point, "on_point")
    # counted from the axes' lengths before a list or a point is made (a generator: to the bound)
    limit, what = budget.max_runs(max_runs), f"sweep {sc.name}"
    with reading("grid"):       # a generator, a __len__ of the caller's: what they raise
        grid = {k: budget.counted(v, f"grid {k}", limit, what) for k, v in grid.items()}
    count, cause = count_points(sc, {k: n for k, (n, _) in grid.items()})
    per_run = budget.seconds_per_run(sc) if scheduler is None else None
    parallel = budget.cpu_workers(workers)
    budget.check(count, what, limit, cause, per_run, parallel)
    with reading("grid"):
        grid = {k: grid_values(v, f"grid {k}") for k, (_, v) in grid.items()}
    points = points_of(sc, grid)
    # each point's own steps (its step, length, speed), said before the first run
    per_run = budget.mean_seconds(seconds_of_points(sc, points)) if scheduler is None else None
    swept = [name for name, _ in points[0].values]
    if (plot or report) and out is None:
        raise ScenarioError("plot and report are files: give out= a folder for them")
    drawing = out is not None and (plot or report)
    drawn = [f"{sc.name}_sweep.png"] * bool(sc.analysis) + ["report.html"] * bool(report) \
        if drawing else []

    def pictures(staging: Path, rows: list[dict]) -> None:
        if drawing and any(r["status"] == "ok" for r in rows):
            sweep_pictures(sc, rows, swept, staging, report=report)

    with tempfile.TemporaryDirectory(prefix="sewfmu_sweep_") as scratch:
        folder = Path(out) if out is not None else Path(scratch)
        try:
            rows = run_sweep(sc, points, folder, workers=workers, scheduler=scheduler,
                             keep_results=results and out is not None, progress=progress,
                             on_point=on_point, outputs=drawn, finish=pictures,
                             announce=lambda: budget.announce(what, count, per_run, parallel,
                                                              shown=bool(progress)))
        except OSError as err:
            raise cannot_write(err, folder) from None
        if rows and all(r["status"] != "ok" for r in rows):
            raise SweepFailed(f"every point of the sweep failed ({len(rows)} of {len(rows)}; "
                              f"the first: {rows[0]['error']})"
                              + (f"; see {folder}/sweep.csv" if out is not None else ""), rows)
    units = {target: declared_unit(sc, target) for target in swept}
    units.update({"stop_time": "s", "wall_time_s": "s", **sc.figure_units()})
    units = {k: u for k, u in units.items() if any(k in r for r in rows)}
    return Sweep(sc.name, swept, rows, units, Path(out) if out is not None else None)


@one_line
def compare(scenario: str | Path | Scenario, set: Mapping[str, Any] | None = None, *,
            rtol: float | None = None) -> dict[str, dict]:
    """The co-simulation beside the monolithic solution of the same physics (the punch drive's
    scenarios): {figure: {"cosim", "monolithic", "difference", "unit"}}; with `rtol` also the
    monolithic solver at that tolerance ("monolithic_rtol", "rtol_error")."""
    from sewfmu.scenarios.runs.compare import compare as compare_rows

    sc = load(scenario, set)
    rtol = plain(rtol)
    if rtol is not None and (isinstance(rtol, bool) or not isinstance(rtol, (int, float))
                             or not 0.0 < rtol < 1.0):
        raise ScenarioError(f"rtol: expected a relative tolerance between 0 and 1, got {rtol!r}")
    units = {**sc.figure_units(), "wall_time_s": "s"}
    out = {}
    for row in compare_rows(sc, rtol=rtol):
        if rtol is None:
            key, a, b, d = row
            out[key] = {"cosim": a, "monolithic": b, "difference": d}
        else:
            key, a, c, b, ea, ec = row
            out[key] = {"cosim": a, "monolithic": b, "difference": ea, "monolithic_rtol": c,
                        "rtol_error": ec}
        out[key]["unit"] = units.get(key, "")
    return out


@one_line
def build(fmi: int = 2, dest: str | Path | None = None,
          names: list[str] | None = None, native: bool = False) -> list[Path]:
    """Build sewfmu's FMUs (all, or those named) for FMI 2.0 or 3.0 into dest (default fmus/,
    fmus/fmi3/); native=True: the native FMUs (C, no Python on the target) into its native/
    (native/fmi3/), from the Python FMUs there; return their paths."""
    from sewfmu.scenarios.fmu_build.build import (
        build_fmu,
        default_fmu_dir,
    )

    if isinstance(fmi, bool) or fmi not in (2, 3):
        raise ScenarioError(f"fmi: the FMI version, 2 or 3, got {fmi!r}")
    names = [names] if isinstance(names, str) else names
    if names is not None and (not isinstance(names, (list, tuple))
                              or not all(isinstance(n, str) for n in names)):
        raise ScenarioError(f"names: expected a list of FMU names ({', '.join(FMUS)}), got "
                            f"{type(names).__name__}")
    dest = _folder(dest, "dest")
    for name in names or []:
        if name not in FMUS:
            raise ScenarioError(f"unknown FMU {name!r}{did_you_mean(name, FMUS)} "
                                f"(known: {', '.join(FMUS)})")
    folder = default_fmu_dir(fmi, Path(dest) if dest else None)
    # the folder the user named made here: one it cannot be is their OSError, which the
    # guard words as "build: '<dest>': <reason>" (a rebuild in a run says it its own way)
    folder.mkdir(parents=True, exist_ok=True)
    if native:
        from sewfmu.scenarios.fmu_build.native import (  # the C builder: only when asked
            build_native_fmus,
            default_native_dir,
        )

        native_folder = default_native_dir(fmi, Path(dest) if dest else None)
        return build_native_fmus(names or list(FMUS), native_folder, fmi=fmi, python_dir=folder)
    return [build_fmu(name, folder, fmi=fmi) for name in (names or list(FMUS))]


# --- the design studies (docs/design.md; the commands: sewfmu/design_cli.py) -----------------
def _refuse_fixed_and_varied(fixed, ranges, role: str, where: str) -> None:
    """A parameter given both a value (set=) and a range (vary=, free=): one line, before the
    FMUs are built (the range's shape is checked later, with its bounds)."""
    from sewfmu.scenarios.runs.sweep import (
        refuse_fixed_and_varied,
    )

    if isinstance(ranges, Mapping) and isinstance(fixed, Mapping):
        refuse_fixed_and_varied(fixed, ranges, role, where)


def _design_scenario(scenario, set):
    """The scenario, its FMU files (built where missing) and their modelDescriptions by
    instance: what a design study checks its ranges and data against before anything runs."""
    from sewfmu.scenarios.cosim.instances import extracted_fmu
    from sewfmu.scenarios.fmu_build.up_to_date import fmus_for

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
    from sewfmu.scenarios.design import optimize as design
    from sewfmu.scenarios.design import space

    out = _folder(out, "out")
    plot, progress = flag(plot, "plot"), flag(progress, "progress")
    workers = worker_count(workers)
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
    from sewfmu.scenarios.design import fit as design
    from sewfmu.scenarios.design import space

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
    from sewfmu.scenarios.design import sensitivity as design
    from sewfmu.scenarios.design import space

    out = _folder(out, "out")
    progress, workers = flag(progress, "progress"), worker_count(workers)
    if not isinstance(figures, (str, tuple, list)):
        raise ScenarioError(f"figures: expected a key figure's name or a list of them, got "
                            f"{type(figures).__name__}")
    _refuse_fixed_and_varied(set, vary, "varied", "--vary, vary=")
    sc, _, described = _design_scenario(scenario, set)
    named = space.figures_named(space.figures_of_scenario(sc), figures)
    variables = space.variables(sc, vary, described)
    return design.sensitivity(sc, variables, named, space.figures_of_scenario(sc), method,
                              samples, workers, out, progress, max_runs)
