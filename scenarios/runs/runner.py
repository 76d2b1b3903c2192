"""Run a scenario end to end: build what is missing, co-simulate, write results, plot, compare.

The functions behind the command line and behind sewfmu's Python API (sewfmu/api.py).
"""
from __future__ import annotations

import json
import math
import time as clock
from pathlib import Path

import numpy as np

from sewfmu.scenarios import analyses
from sewfmu.scenarios.cosim.master import RunResult, run
from sewfmu.scenarios.files.outputs import folder_for, replacing, write_atomic
from sewfmu.scenarios.fmu_build.build import default_fmu_dir, ensure_built
from sewfmu.scenarios.format.experiment import experiment_of
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import ScenarioError, label_of


def run_study(name: str, out_dir: Path, plot: bool = False, report: bool = False) -> dict:
    """Run a study into out_dir: study.json (everything), summary.json (the headline figures)
    and, with plot, NAME.png; with report, report.html; return the headline figures."""
    _, study = analyses.studies()[name]
    data = study.compute()
    headline = study.headline(data)
    with replacing(out_dir) as staging:
        write_json(data, staging / "study.json")
        write_json(headline, staging / "summary.json")
        if plot or report:
            study.plot(data, staging / f"{name}.png")
        if report:
            from sewfmu.scenarios.runs.report import study_report
            study_report(staging / "report.html", name, study, headline, staging / f"{name}.png")
    return headline


def fmus_for_names(names: list[str], fmu_dir: Path | None = None,
                   fmi: int = 2) -> dict[str, Path]:
    """sewfmu's FMUs of these names for FMI `fmi`, built where missing or stale, in fmu_dir
    (default: fmus/; FMI 3.0: its folder fmi3/)."""
    return ensure_built(sorted(names), default_fmu_dir(fmi, fmu_dir), fmi=fmi)


def fmus_for(scenario: Scenario, fmu_dir: Path | None = None) -> dict[str, Path]:
    from sewfmu.components.registry import FMUS

    names = sorted({inst.fmu for inst in scenario.instances.values()})
    if scenario.fmu_files:                  # a system read from SSP brings its own FMUs
        return {name: scenario.fmu_files[name] for name in names}
    unknown = [n for n in names if n not in FMUS]
    if unknown:
        raise ScenarioError(f"{scenario.source}: unknown FMU {unknown[0]!r} "
                            f"(known: {', '.join(FMUS)})")
    return fmus_for_names(names, fmu_dir, scenario.fmi)


def simulate(scenario: Scenario, fmu_dir: Path | None = None) -> RunResult:
    return run(scenario, fmus_for(scenario, fmu_dir))


def summarize(result: RunResult) -> dict:
    sc = result.scenario
    figures, units = {}, {}
    if sc.analysis:
        figures = analyses.module(sc.analysis).summary_of_run(result)
        declared = analyses.mechanism(sc.analysis).figures
        units = {key: declared[key] for key in figures if key in declared}
    # what the master did: the iterative master's passes, the adaptive master's steps
    master = {f"master_{k}": v for k, v in result.coupling.items()}
    units = {"step": "s", "stop_time": "s", "wall_time_s": "s", **units}
    return {"scenario": sc.name, "master": sc.master, "step": sc.even_steps()[1],
            "stop_time": float(result.time[-1]), "wall_time_s": round(result.wall_time, 4),
            **master, **figures, "units": units}


def write_csv(result: RunResult, path: Path) -> None:
    names = list(result.columns)
    table = np.column_stack([result.time] + [result.columns[n] for n in names])
    # each column says its unit, as "name [unit]" (a Boolean, which has none, its name alone)
    header = ",".join(["time [s]"] + [f"{n} [{result.units[n]}]" if result.units.get(n) else n
                                      for n in names])
    write_atomic(path, lambda f: np.savetxt(f, table, delimiter=",", header=header, comments="",
                                             fmt="%.17g"))


def write_json(data, path: Path) -> None:
    write_atomic(path, lambda f: (json.dump(data, f, indent=2), f.write("\n")))


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


def provenance(scenario: Scenario, fmu_paths: dict[str, Path]) -> dict:
    """What produced a run: the scenario (file and its hash), every parameter value each instance
    ran with (defaults included; `set` marks the scenario's own values), the master and step,
    sewfmu's version and each FMU's version with the hash of the code it carries."""
    from sewfmu.scenarios.cosim.instances import extracted_fmu
    from sewfmu.scenarios.fmu_build.build import VERSION

    described = {fmu: extracted_fmu(Path(path))[1] for fmu, path in fmu_paths.items()}
    instances = {}
    for name, inst in scenario.instances.items():
        declared = [v for v in described[inst.fmu].modelVariables if v.causality == "parameter"]
        instances[name] = {"fmu": inst.fmu, "parameters": {
            v.name: {"value": inst.parameters.get(v.name, _number(v.start)), "unit": v.unit or "1",
                     "set": v.name in inst.parameters}
            for v in declared}}
    return {"scenario": {"name": scenario.name, "source": scenario.source,
                         "sha256": scenario.digest or None},
            "instances": instances, "master": scenario.master, "step": scenario.step,
            **scenario.master_settings(), "experiment": experiment_of(scenario),
            "end_time": scenario.end_time(), "sewfmu": VERSION,
            "fmus": {fmu: md.version for fmu, md in sorted(described.items())},
            "fmi": {fmu: md.fmiVersion for fmu, md in sorted(described.items())}}


def _number(text: str) -> float | int:
    """A start value of the modelDescription as the number it is."""
    value = float(text)
    return int(value) if value.is_integer() and "." not in text and "e" not in text.lower() \
        else value


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
        runs.append((label, result, {**summarize(result), "provenance": provenance(sc, paths)}))
    return runs


def summary_of_runs(scenario: Scenario, runs: list[tuple[str, RunResult, dict]]) -> dict:
    """What summary.json holds: the run's summary, or for [compare] each variant's by label."""
    if scenario.compare:
        return {"scenario": scenario.name, "compare": scenario.compare["parameter"],
                "runs": {label: s for label, _, s in runs}}
    return runs[0][2]


def run_scenario(scenario: Scenario, out_dir: Path, plot: bool = False,
                 fmu_dir: Path | None = None, progress=None, animate: bool = False,
                 report: bool = False) -> dict:
    """Run (each variant of) a scenario into out_dir; return the summary written there."""
    runs = run_variants(scenario, fmu_dir, progress)
    write_outputs(scenario, runs, out_dir, plot=plot, animate=animate, report=report)
    return summary_of_runs(scenario, runs)


def write_outputs(scenario: Scenario, runs: list[tuple[str, RunResult, dict]], out_dir: Path,
                  plot: bool = False, animate: bool = False, report: bool = False) -> None:
    """Write the runs into out_dir: results.csv and summary.json (a folder per variant), and
    as asked PNG plots, GIF animations, report.html.

    Every run is done before out_dir is touched, and what is written then takes the place of
    what the previous run wrote (outputs.replacing): a failed or interrupted run leaves the
    previous results as they were. `report` is a self-contained page with the plots, the
    animations and, for the punch drive, the comparison with the monolithic solution."""
    from sewfmu.scenarios import animations

    summary = summary_of_runs(scenario, runs)
    against_monolithic = {}
    if report and scenario.analysis and analyses.mechanism(scenario.analysis).monolithic:
        for label, result, own in runs:
            against_monolithic[label] = comparison_rows(own, monolithic_summary(result.scenario)[0])
    with replacing(out_dir) as staging:
        pictures = []
        for label, result, own in runs:
            where = folder_for(staging, label) if label else staging
            write_csv(result, where / "results.csv")
            write_json(own, where / "summary.json")
            if (animate or report) and animations.can_animate(scenario):
                gif = where / f"{scenario.name}.gif"
                animations.animate(result, gif)
                pictures.append((f"the mechanism moving{', ' + label if label else ''} "
                                 f"(last revolution, recorded run)", gif))
        if scenario.compare:
            write_json(summary, staging / "summary.json")
        if (plot or report) and scenario.analysis:
            curves = [(label or scenario.name, result) for label, result, _ in runs]
            png = staging / f"{scenario.name}.png"
            analyses.module(scenario.analysis).plot(curves, png, scenario.description)
            pictures.insert(0, ("key curves of the last revolution", png))
        if report:
            from sewfmu.scenarios.runs.report import run_report
            run_report(staging / "report.html", scenario, runs, pictures, against_monolithic)


def comparison_rows(cosim: dict, monolithic: dict) -> list[tuple[str, object, object, object]]:
    """(figure, co-simulation, monolithic, difference) for every key figure of the punch."""
    rows = []
    for key in analyses.mechanism("punch").figures:
        a, b = cosim.get(key), monolithic.get(key)
        diff = a - b if isinstance(a, (int, float)) and isinstance(b, (int, float)) else None
        rows.append((key, a, b, diff))
    return rows


def monolithic_summary(scenario: Scenario, rtol: float | None = None) -> tuple[dict, float]:
    """Key figures of the monolithic solution (the punch drive as one ODE, DOP853, tight
    tolerances, or `rtol` with atol = rtol/1000) and its wall time."""
    if not (scenario.analysis and analyses.mechanism(scenario.analysis).monolithic):
        raise ScenarioError(f"{scenario.source}: no monolithic solution for analysis "
                            f"{scenario.analysis!r}")
    from sewfmu.scenarios.analyses.solutions import punch_monolithic

    params = {role: dict(scenario.instances[name].parameters)
              for role, name in scenario.roles.items()}
    if scenario.analysis == "punch_split":       # the same physics: body and fabric as one punch
        params["punch"] = {**params.pop("body"), **params.pop("fabric")}
    t_end = scenario.end_time()
    omega = params["shaft"].get("omega0", 100.0)
    started = clock.perf_counter()
    tolerances = {} if rtol is None else {"rtol": rtol, "atol": rtol * 1e-3}
    solution = punch_monolithic.solve(params["shaft"], params["linkage"], params["punch"], t_end,
                                      sample_step=math.radians(0.01) / omega,
                                      sample_from=max(0.0, t_end - 2.2 * math.pi / omega),
                                      **tolerances)
    wall = clock.perf_counter() - started
    return analyses.module("punch").summary_of_monolithic(solution), wall


def compare(scenario: Scenario, fmu_dir: Path | None = None,
            rtol: float | None = None) -> list[tuple]:
    """Rows (figure, co-simulation, monolithic solution, difference), plus the wall times.
    With `rtol`, the monolithic solver also runs at that tolerance, and each row is (figure,
    co-simulation, monolithic at rtol, tight monolithic, error of each against the tight)."""
    result = simulate(scenario, fmu_dir)
    cosim = summarize(result)
    ref, ref_wall = monolithic_summary(scenario)
    if rtol is None:
        rows = comparison_rows(cosim, ref)
        rows.append(("wall_time_s", round(result.wall_time, 3), round(ref_wall, 3), None))
        return rows
    loose, loose_wall = monolithic_summary(scenario, rtol)
    rows = []
    for key, a, b, _ in comparison_rows(cosim, ref):
        c = loose.get(key)
        numbers = all(isinstance(x, (int, float)) for x in (a, b, c))
        rows.append((key, a, c, b, a - b if numbers else None, c - b if numbers else None))
    rows.append(("wall_time_s", round(result.wall_time, 3), round(loose_wall, 3),
                 round(ref_wall, 3), None, None))
    return rows


def export(scenario: Scenario, path: Path, fmu_dir: Path | None = None) -> Path:
    """The scenario as an SSP 1.0 archive for other co-simulation tools."""
    from sewfmu.scenarios.interop.ssp_export import export_ssp

    return export_ssp(scenario, Path(path), fmus_for(scenario, fmu_dir))


def _end_at(time: np.ndarray, columns: dict, stop: float):
    """A fixed-step host cannot shorten its last step: end its record at the scenario's stop
    time, interpolating the last row (as sewfmu's master ends exactly there)."""
    if time[-1] <= stop + 1e-12:
        return time, columns
    keep = int(np.searchsorted(time, stop, side="right"))
    new_time = np.append(time[:keep], stop)
    out = {}
    for name, values in columns.items():
        out[name] = np.append(values[:keep], np.interp(stop, time, values))
    return new_time, out


def crosscheck(scenario: Scenario, host: str, out_dir: Path, fmu_dir: Path | None = None):
    """Run the exported scenario in another host; write its results.csv and summary.json;
    return rows (figure, sewfmu, host, difference) and the two summaries."""
    from sewfmu.scenarios.interop.hosts import run_in_host

    with replacing(out_dir) as staging:
        ssp = export(scenario, staging / f"{scenario.name}.ssp", fmu_dir)
        own = simulate(scenario, fmu_dir)
        time, columns, wall = run_in_host(host, ssp, scenario, list(own.columns),
                                          staging / "results.csv")
        time, columns = _end_at(time, columns, scenario.end_time())
        other = RunResult(scenario, time, columns, wall, units=own.units)
        write_csv(other, staging / "results.csv")
        mine, theirs = summarize(own), summarize(other)
        theirs["host"] = host
        write_json(theirs, staging / "summary.json")
    rows = []
    for key, value in mine.items():
        if key in ("scenario", "master", "step", "stop_time") or isinstance(value, dict):
            continue
        b = theirs.get(key)
        diff = value - b if isinstance(value, (int, float)) and isinstance(b, (int, float)) \
            else None
        rows.append((key, value, b, diff))
    return rows
