"""A run's files (and a study's): results.csv (a column per recorded output, its unit in the header),
summary.json, and as asked the plots, animations and report.html, written into the output folder
in one piece (files.outputs.replacing); run_scenario runs and writes (a study: runs/studies.py).

A run that did not finish (interrupted, or a step beyond experiment.step_timeout) keeps what it
recorded in OUT/interrupted/ (`keep_unfinished`: results.csv with every row recorded,
summary.json saying why and where it stopped), written whole with a manifest of its own, beside
the previous run's files, which stay as they were; the next run into OUT that finishes removes it.
"""
from __future__ import annotations

import contextlib
import json
import os
import stat
import time
import warnings
from pathlib import Path

import numpy as np

from sewfmu.scenarios.cosim.master import RunResult
from sewfmu.scenarios.files.outputs import (
    MANIFEST,
    OutputError,
    folder_for,
    remove_debris,
    replacing,
    write_atomic,
)
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import check_scenario_name
from sewfmu.scenarios.mechanisms.base import MissingRecord
from sewfmu.scenarios.runs.compare import comparison_rows, monolithic_summary
from sewfmu.scenarios.runs.variants import run_variants, summary_of_runs, variants


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


def write_outputs(scenario: Scenario, runs: list[tuple[str, RunResult, dict]], out_dir: Path,
                  plot: bool = False, animate: bool = False, report: bool = False) -> None:
    """Write the runs into out_dir: results.csv and summary.json (a folder per variant), and
    as asked PNG plots, GIF animations, report.html.

    Every run is done before out_dir is touched, and what is written then takes the place of
    what the previous run wrote (outputs.replacing): a failed or interrupted run leaves the
    previous results as they were. `report` is a self-contained page with the plots, the
    animations and, for the punch drive, the comparison with the monolithic solution."""
    check_scenario_name(scenario.name)      # NAME.png, NAME.gif: never a path out of out_dir
    if animate or report:   # a run without pictures does not load the animations
        from sewfmu.scenarios.mechanisms import animation  # matplotlib, pillow: only for pictures

    summary = summary_of_runs(scenario, runs)
    if (plot or animate) and not scenario.analysis:        # asked for, and nothing to draw
        warnings.warn(f"{'--plot' if plot else '--animate'}: {scenario.name} has no analysis (no "
                      f"mechanism of sewfmu's named by `analysis`), so there is nothing to draw; "
                      f"results.csv holds every recorded series", stacklevel=2)
    elif animate and not animation.can_animate(scenario):
        warnings.warn(f"--animate: no animation draws {scenario.analysis}'s mechanism",
                      stacklevel=2)
    against_monolithic = {}
    if report and scenario.mechanism and scenario.mechanism.monolithic:
        for label, result, own in runs:
            against_monolithic[label] = comparison_rows(own, monolithic_summary(result.scenario)[0],
                                                       scenario.mechanism.figures)
    with replacing(out_dir) as staging:
        pictures = []
        for label, result, own in runs:
            where = folder_for(staging, label) if label else staging
            write_csv(result, where / "results.csv")
            write_json(own, where / "summary.json")
            if (animate or report) and animation.can_animate(scenario):
                gif = where / f"{scenario.name}.gif"
                if _drawn(lambda: animation.animate(result, gif), "the animation"):
                    pictures.append((f"the mechanism moving{', ' + label if label else ''} "
                                     f"(last revolution, recorded run)", gif))
        if scenario.compare:
            write_json(summary, staging / "summary.json")
        if (plot or report) and scenario.analysis:
            curves = [(label or scenario.name, result) for label, result, _ in runs]
            png = staging / f"{scenario.name}.png"
            title = f"{scenario.description} ({as_run(scenario)})"
            if _drawn(lambda: scenario.mechanism.plot(curves, png, title),
                      "the plot"):
                pictures.insert(0, ("key curves of the last revolution", png))
        if report:
            from sewfmu.scenarios.runs.report import run_report  # only with --report
            run_report(staging / "report.html", scenario, runs, pictures, against_monolithic)
    forget_unfinished(out_dir)         # an earlier run's that did not finish: this one did


def outputs_of(scenario: Scenario, plot: bool = False, animate: bool = False,
               report: bool = False) -> list[str]:
    """Every name a run of the scenario may write into its output folder (write_outputs, or a
    study's run_study), as asked: checked before the run by the check its files pass at the
    end (files/outputs.refuse_theirs), so that a user's file there refuses the run before its
    first step, not after it. A picture whose drawing fails is not written: these are the
    most a run writes."""
    if scenario.study:
        return ["study.json", "summary.json"] + [f"{scenario.name}.png"] * (plot or report) \
            + ["report.html"] * report
    moving = (animate or report) and scenario.mechanism is not None and \
        scenario.mechanism.animated                # animation.can_animate, without matplotlib
    names = []
    for label, _ in variants(scenario):
        where = f"{folder_for(Path('.'), label).name}/" if label else ""
        names += [f"{where}results.csv", f"{where}summary.json"] + \
            [f"{where}{scenario.name}.gif"] * moving
    return names + ["summary.json"] * bool(scenario.compare) \
        + [f"{scenario.name}.png"] * bool((plot or report) and scenario.analysis) \
        + ["report.html"] * report


UNFINISHED = "interrupted"      # the folder in OUT of the record of a run that did not finish


# s of CSV formatting an interrupted record may take: the 2 s from the signal to the exit hold
# (400,000 rows of 8 columns take 2.5 s as CSV on this project's machine, 0.03 s as .npy)
CSV_BUDGET = 0.7
CSV_CHUNK = 20000           # rows formatted between two looks at the clock


def keep_unfinished(result: RunResult, reason: str, out_dir: Path) -> str:
    """Write the record of a run that did not finish into OUT/interrupted/: results.csv, or
    where its formatting would take beyond CSV_BUDGET, the whole record as results.npy (a
    structured array whose fields are the CSV's columns); where it is, as a line says it."""
    folder = _unfinished_folder(out_dir)
    if folder is None:
        raise OutputError(f"{Path(out_dir) / UNFINISHED}: is a symbolic link or not a folder, "
                          f"and sewfmu writes inside an output folder only into plain folders; "
                          f"move it away to keep the record of the next run that does not "
                          f"finish")
    with replacing(folder) as staging:
        name = _write_within(result, staging, CSV_BUDGET)
        write_json({"scenario": result.scenario.name, "unfinished": reason,
                    "recorded_until": float(result.time[-1]), "rows": len(result.time),
                    "file": name, "units": {"recorded_until": "s"}}, staging / "summary.json")
    said = f"the record up to t = {result.time[-1]:g} s is in {folder / name}"
    if name.endswith(".npy"):
        said += (f" ({len(result.time)} rows, too many to write as CSV within the 2 s an "
                 f"interruption takes: numpy.load reads it)")
    return said


def _write_within(result: RunResult, staging: Path, budget: float) -> str:
    """results.csv if its rows are formatted within `budget` seconds, else results.npy."""
    names = list(result.columns)
    header = ",".join(["time [s]"] + [f"{n} [{result.units[n]}]" if result.units.get(n) else n
                                      for n in names])
    table = np.column_stack([result.time] + [result.columns[n] for n in names])
    row = ",".join(["%.17g"] * table.shape[1]) + "\n"
    deadline, text = time.monotonic() + budget, [header + "\n"]
    for start in range(0, len(table), CSV_CHUNK):
        text.append("".join(row % tuple(r) for r in table[start:start + CSV_CHUNK].tolist()))
        if time.monotonic() > deadline and start + CSV_CHUNK < len(table):
            record = np.empty(len(table), dtype=[(h, "f8") for h in header.split(",")])
            for k, field in enumerate(record.dtype.names):
                record[field] = table[:, k]
            write_atomic(staging / "results.npy", lambda f: np.save(f, record), binary=True)
            return "results.npy"
    write_atomic(staging / "results.csv", lambda f: f.writelines(text))
    return "results.csv"


def forget_unfinished(out_dir: Path) -> None:
    """Remove the record of an earlier unfinished run from OUT: the files its manifest lists
    (a folder of that name without one is the user's, and stays)."""
    folder = _unfinished_folder(out_dir)
    if folder is None or not folder.is_dir():    # a link, a file: the user's, never followed
        return
    remove_debris(folder, recursive=True)       # a writer killed (kill -9) while it wrote
    if not stat.S_ISREG(_lmode(folder / MANIFEST)):
        return
    with replacing(folder):           # nothing staged: what the manifest lists goes
        pass
    with contextlib.suppress(OSError):
        (folder / MANIFEST).unlink()
        folder.rmdir()                # only if nothing else is in it


def _lmode(path: Path) -> int:
    try:
        return os.lstat(path).st_mode
    except OSError:
        return 0


def _unfinished_folder(out_dir: Path) -> Path | None:
    """OUT/interrupted, a folder inside the output folder under its rule: None where it is a
    symbolic link or anything but a folder (never followed: it is the user's)."""
    folder = Path(out_dir) / UNFINISHED
    mode = _lmode(folder)
    return folder if mode == 0 or stat.S_ISDIR(mode) else None


def as_run(scenario: Scenario) -> str:
    """What was run, as it was run, for a title: the description may name a length that --set
    changed (it says 10 revolutions; the run had 3)."""
    if scenario.revolutions is not None:
        n = scenario.revolutions
        length = f"{n:g} revolution{'s' if n != 1 else ''} of " \
                 f"{scenario.shaft or scenario.default_shaft() or 'the shaft'}"
    else:
        length = f"stop time {scenario.stop_time:g} s"
    return f"as run: {length}, step {scenario.step * 1e3:g} ms, {scenario.master} master"


def _drawn(draw, what: str) -> bool:
    """Draw a picture; one that needs a column the run did not record is left out with a
    warning line naming it, and the rest is written."""
    try:
        draw()
    except MissingRecord as err:
        warnings.warn(f"{what} is left out: {err}", stacklevel=2)
        return False
    return True


def run_scenario(scenario: Scenario, out_dir: Path, plot: bool = False,
                 fmu_dir: Path | None = None, progress=None, animate: bool = False,
                 report: bool = False) -> dict:
    """Run (each variant of) a scenario into out_dir; return the summary written there."""
    runs = run_variants(scenario, fmu_dir, progress)
    write_outputs(scenario, runs, out_dir, plot=plot, animate=animate, report=report)
    return summary_of_runs(scenario, runs)
