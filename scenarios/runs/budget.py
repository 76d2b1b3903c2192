"""How many runs a sweep or a design study may make, counted before the first one.

A sweep's grid, a sensitivity analysis's samples, an optimizer's or a fit's evaluations are all
runs, each a co-simulation: a count typed one digit too long is days of work and a table that
grows in memory. Every one of them is counted from its settings alone (the grid's lengths, the
samples times the group, the budget of evaluations), before any point or sample is made, and
refused in one line over MAX_RUNS (DEFAULT_MAX_RUNS; the option --max-runs N, `max_runs=` from
Python, or the environment's SEWFMU_MAX_RUNS raise it); under it, the count and a time
estimate are said before the first run (`announce`).

The estimate is the runs' communication steps times a cost per FMU and step (STEP_COST,
measured: punch_drive 43 µs, take-up 45, carriage 30, feed 99 on this project's machine), plus
a start per run, over the workers: a guide to the order of magnitude, not a promise. The native
FMUs (experiment.fmus = "native") cost a hundredth of that where the compiled step loop runs them
(NATIVE_STEP_COST: the Jacobi master without experiment.step_timeout, cosim/stepper.py), a tenth
where the Python loop does (NATIVE_PYTHON_LOOP_STEP_COST). A sweep
counts each point's own steps (its step, its length, its shaft's speed: runs/sweep.py
seconds_of_points); a study scenario, computed rather than co-simulated, costs what its study
was measured to take (STUDY_SECONDS).
"""
from __future__ import annotations

import itertools
import math
import os
import sys

from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.value_lists import grid_values
from sewfmu.scenarios.format.values import ScenarioError, plain, short

SETTING = "SEWFMU_MAX_RUNS"
DEFAULT_MAX_RUNS = 10_000
RAISE_IT = f"--max-runs N, max_runs=N from Python, or {SETTING}=N"
STEP_COST = 50e-6           # seconds per FMU and communication step (module docstring)
START_COST = 0.05           # seconds per run: the FMUs instantiated and initialized
# the native FMUs, measured 2026-11-29 on this project's 2-core machine (load 1.7), a warm run
# in one process (FMUs built, loop compiled), CPU time per FMU and communication step: compiled
# loop punch_drive 0.50 µs (300 revolutions, 75,399 steps), carriage_startstop 0.37; the Python
# loop (SEWFMU_STEP_LOOP=python) punch_drive 6.1 µs, carriage_startstop 5.6; a run's start
# about 6 ms. Rounded up: a sweep point also writes its files.
NATIVE_STEP_COST = 0.6e-6
NATIVE_PYTHON_LOOP_STEP_COST = 6e-6
NATIVE_START_COST = 0.01
POOL_START = 2.0            # seconds: worker processes started, their FMUs first loaded
SAID_ALWAYS = 30.0          # an estimate beyond this is said even where no progress is shown
# seconds one computation of a study scenario takes (`sewfmu run NAME`, one sweep point),
# measured 2026-11-29 on this project's 2-core machine while other work held it (load 5):
# the order of magnitude; a study not listed costs the dearest
STUDY_SECONDS = {"carriage_resonance": 2.2, "feed_ratio": 3.6, "takeup_tolerance": 2.9}



def worker_count(workers, default: int | None = None) -> int | None:
    """The number of worker processes a user gave (--workers, workers=): a whole number >= 1,
    numpy's integers too; None gives `default`. The one check of it, for sweeps and studies."""
    if workers is None:
        return default
    value = plain(workers)
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ScenarioError(f"workers (--workers): a whole number >= 1, got {short(workers)}")
    return value

def max_runs(given=None) -> int:
    """The bound: `given` (the option, the argument), else SEWFMU_MAX_RUNS, else the default."""
    if given is None:
        text = os.environ.get(SETTING, "").strip()
        if not text:
            return DEFAULT_MAX_RUNS
        try:
            given = int(text.replace("_", ""))
        except ValueError:
            raise ScenarioError(f"{SETTING}={text!r}: expected a whole number of runs >= 1") \
                from None
        where = f"{SETTING}={text}"
    else:
        given, where = plain(given), "max_runs"
    if isinstance(given, bool) or not isinstance(given, int) or given < 1:
        raise ScenarioError(f"{where}: expected a whole number of runs >= 1, got {given!r}")
    return given


def seconds_per_run(scenario: Scenario) -> float | None:
    """About how long one run of the scenario takes (a study's computation: STUDY_SECONDS);
    None where its length is not known."""
    if scenario.study:
        return STUDY_SECONDS.get(scenario.study, max(STUDY_SECONDS.values()))
    try:
        steps = scenario.even_steps()[0]
    except ScenarioError:
        return None
    start, cost = costs_of(scenario)
    return start + steps * len(scenario.instances) * cost


def costs_of(scenario: Scenario) -> tuple[float, float]:
    """(seconds to start a run, seconds per FMU and communication step) of the scenario's build
    of the FMUs (experiment.fmus), and for native FMUs of the loop that will likely step them:
    the compiled one under the Jacobi master without experiment.step_timeout (cosim/stepper.py;
    a feedback loop keeps to the Python loop too, which this cheap guess does not see)."""
    if scenario.fmus != "native":
        return START_COST, STEP_COST
    compiled = scenario.master == "jacobi" and scenario.step_timeout is None
    return NATIVE_START_COST, NATIVE_STEP_COST if compiled else NATIVE_PYTHON_LOOP_STEP_COST


def mean_seconds(seconds: list[float | None]) -> float | None:
    """The mean of runs' estimates (runs * mean: their sum), None where one is not known."""
    if not seconds or any(s is None for s in seconds):
        return None
    return sum(seconds) / len(seconds)


def duration(seconds: float) -> str:
    """A time as a person says it: 40 s, 12 min, 3.5 h, 6 days."""
    if seconds < 90:
        return f"{max(seconds, 1):.0f} s"
    if seconds < 90 * 60:
        return f"{seconds / 60:.0f} min"
    if seconds < 48 * 3600:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:,.0f} days"


def estimate(runs: int, per_run: float | None, workers: int = 1) -> str:
    """", about 40 s on 2 workers", or nothing where a run's time is not known."""
    if per_run is None:
        return ""
    parallel = max(1, min(workers, runs))
    start = POOL_START if parallel > 1 else 0.0
    return f", about {duration(start + runs * per_run / parallel)}" + \
        (f" on {parallel} workers" if parallel > 1 else "")


def check(runs: int, what: str, limit: int, cause: str, per_run: float | None = None,
          workers: int = 1) -> None:
    """Refuse `runs` (what `cause` makes: "16777216 samples × 3") over the bound, in one line
    that names what makes the count and what raises the bound."""
    if runs <= limit:
        return
    raise ScenarioError(f"{what}: {runs:,} runs ({cause}){estimate(runs, per_run, workers)}; "
                        f"more than the {limit:,} a sweep or study may make: make it smaller, "
                        f"or raise the bound ({RAISE_IT})")


def announce(what: str, runs: int, per_run: float | None, workers: int = 1,
             shown: bool = True, most: bool = False) -> None:
    """The count and the estimate, one line on stderr, before the first run: where progress is
    shown, or where it will take long."""
    if not shown and (per_run is None or runs * per_run / max(1, min(workers, runs))
                      < SAID_ALWAYS):
        return
    count = f"{'at most ' if most else ''}{runs:,} run{'s' if runs != 1 else ''}"
    print(f"sewfmu: {what}: {count}{estimate(runs, per_run, workers)}", file=sys.stderr,
          flush=True)


def cpu_workers(workers: int | None) -> int:
    """The worker processes a sweep uses: those asked for, else one per core."""
    return workers or os.cpu_count() or 1


def counted(values, where: str, limit: int, what: str) -> tuple[int, object]:
    """(how many values a grid gives a parameter, the values): counted without a copy where
    they say their number; a generator or an iterator taken up to the bound on runs and one
    more, and refused past it without being listed whole (it may never end)."""
    if isinstance(values, str):
        return len(grid_values(values, where)), values      # a text list: as long as its text
    try:
        return len(values), values
    except TypeError:                                       # no len(): an iterator, one value
        pass
    try:
        iterator = None if hasattr(values, "keys") else iter(values)
    except TypeError:
        iterator = None
    if iterator is None:
        return len(grid_values(values, where)), values      # one value, or refused there
    taken = list(itertools.islice(iterator, limit + 1))
    if len(taken) > limit:
        raise ScenarioError(f"{what}: {where} gives more than {limit:,} values (an iterator, "
                            f"counted up to the bound); more than the {limit:,} runs a sweep "
                            f"or study may make: make it smaller, or raise the bound "
                            f"({RAISE_IT})")
    return len(taken), taken


def product(lengths) -> int:
    """The number of points of a grid from its axes' lengths (no grid made)."""
    return math.prod(lengths) if lengths else 0
