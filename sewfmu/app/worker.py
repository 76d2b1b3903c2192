"""What a job's process does: one run or one sweep through the public API (sewfmu.run,
sewfmu.sweep), telling the page how far it is through a pipe. A run's files go under its own
folder, which appears whole (written beside it, then renamed) or not at all; report.html, which
takes longer than the run, is made when it is first asked for.

The process leads a group of its own (a sweep's worker processes join it), so that Cancel ends
them all; it ends when the app does (the kernel's parent-death signal, and a pipe that breaks).

A run's process is started before the run is asked for (`standby`): it loads the scenario's FMUs
in a short run of its own, then waits for its job, so that a click on Run pays a warm run, not a
process's first (loading and initializing the FMUs: about as long again as the run)."""
from __future__ import annotations

import ctypes
import math
import os
import shutil
import signal
import time
import warnings
from pathlib import Path

# what a run loads on its first use, loaded once in the fork server rather than in every run:
# fmpy's reading of a modelDescription, and the pythonfmu FMUs' slave classes run in-process
import fmpy.validation  # noqa: F401
import lxml.etree  # noqa: F401
import numpy as np
import pythonfmu.fmi2slave  # noqa: F401
import pythonfmu3.fmi3slave  # noqa: F401

import sewfmu
from sewfmu.app.files import FILES
from sewfmu.app.values import command_line, scenario_toml, short_run, value_of

_API = (sewfmu.run, sewfmu.sweep)     # the API loaded in the fork server, before any job
PROGRESS_EVERY = 0.15          # s between progress messages
MAX_POINTS = 1500              # samples of a revolution sent to the page for its plots
_PR_SET_PDEATHSIG = 1


def main(kind: str, job: dict, folder: str, conn) -> None:
    """A job's whole life in its process."""
    _lead_group()
    _do(kind, job, folder, conn)


def standby(warm: str | None, conn) -> None:
    """A run's process before its run: warmed on the scenario `warm`, then the job it is sent
    (kind, job, folder) done as main() does it; nothing if the app ends first."""
    _lead_group()
    try:
        _warm_up(warm)
        kind, job, folder = conn.recv()
    except BaseException:           # the app ended (or Cancel) before a job came: nothing to do
        conn.close()
        return
    _do(kind, job, folder, conn)


def _warm_up(source: str | None) -> None:
    """A short run of the scenario, nothing written: its FMUs loaded and initialized once, the
    unit registry built. A scenario that cannot run so (a study, a bad file) is left cold: its
    job says why."""
    if source is None:
        return
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            short = short_run(source)
            if short is not None:
                sewfmu.run(source, set=short)
    except Exception:
        pass


def _lead_group() -> None:
    os.setpgrp()
    signal.signal(signal.SIGINT, signal.SIG_IGN)    # the app decides; Ctrl-C reaches the group
    try:
        ctypes.CDLL(None).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    except (OSError, AttributeError):
        pass


def _do(kind: str, job: dict, folder: str, conn) -> None:
    try:
        {"run": _run, "sweep": _sweep, "report": _report}[kind](job, Path(folder), conn)
    except sewfmu.Error as err:
        conn.send(("error", " ".join(str(err).split())))
    except Exception as err:        # one line on the page, as the command line would say it
        conn.send(("error", f"unexpected {type(err).__name__}: {err}"))
    except BaseException:           # ended by the app (Cancel, its own end): nothing to tell
        pass
    finally:
        conn.close()


def _progress(conn):
    said = [0.0]

    def tell(done: int, total: int) -> None:
        now = time.monotonic()
        if now - said[0] >= PROGRESS_EVERY or done >= total:
            said[0] = now
            conn.send(("progress", done, total))
    return tell


def _run(job: dict, folder: Path, conn) -> None:
    values = {name: value_of(text) for name, text in job["changed"].items()}
    part = folder.with_name(folder.name + ".part")
    run = sewfmu.run(job["source"], set=values, out=part, progress=_progress(conn))
    (part / "command.txt").write_text(command_line(job["scenario"], job["changed"]) + "\n")
    if job.get("toml") is not None:
        (part / "scenario.toml").write_text(scenario_toml(job["toml"], job["changed"]))
    for name in os.listdir(part):          # only the files the page serves, and the pictures
        if name not in FILES or name == "report.html":
            _remove(part / name)
    os.replace(part, folder)
    conn.send(("done", {"variants": [_variant(label, r) for label, r in
                                     (run.runs.items() if run.runs else [("", run)])]}))


def _report(job: dict, folder: Path, conn) -> None:
    """report.html of a run, when it is first asked for: the run again with its pictures (the
    public API writes a report with a run), into the run's folder once it is whole."""
    values = {name: value_of(text) for name, text in job["changed"].items()}
    made = folder.with_name(folder.name + ".report")
    sewfmu.run(job["source"], set=values, out=made, report=True)
    os.replace(made / "report.html", folder / "report.html")
    shutil.rmtree(made, ignore_errors=True)
    conn.send(("done", {}))


def _variant(label: str, run) -> dict:
    """What the page shows of one run: key figures, the last revolution's series, the drawing
    (a study, computed rather than co-simulated: its figures alone)."""
    if run.series is None:
        return {"label": label, "figures": {k: _number(v) for k, v in run.figures.items()},
                "units": {k: run.units.get(k, "") for k in run.figures}, "series": {},
                "mechanism": None}
    turn = run.revolution(-1)
    every = max(1, math.ceil(len(turn) / MAX_POINTS))
    series = {name: _numbers(turn[name][::every]) for name in turn.dtype.names}
    try:
        drawing = run.mechanism()
    except sewfmu.Error:
        drawing = None                     # a mechanism without a drawing: plots only
    return {"label": label, "figures": {k: _number(v) for k, v in run.figures.items()},
            "units": {k: run.units.get(k, "") for k in [*run.figures, *series]},
            "series": series, "mechanism": drawing}


def _sweep(job: dict, folder: Path, conn) -> None:
    values = {name: value_of(text) for name, text in job["changed"].items()}
    sweep = sewfmu.sweep(job["source"], grid=job["grid"], set=values, workers=job.get("workers"),
                         scheduler=job.get("scheduler"), out=folder,
                         on_point=lambda row: conn.send(("point", _row(row))))
    conn.send(("done", {"rows": [_row(r) for r in sweep.rows], "swept": sweep.swept,
                        "units": sweep.units}))


def _row(row: dict) -> dict:
    return {k: _number(v) for k, v in row.items()}


def _number(value):
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


def _numbers(column) -> list:
    return [_number(v) for v in column.tolist()]


def _remove(path: Path) -> None:
    if path.is_dir():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)
