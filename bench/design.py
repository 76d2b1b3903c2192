"""What an optimization's evaluation costs beside a plain run of the same point.

One Nelder-Mead optimization of punch_drive (two parameters, two targets, 3 revolutions) runs
into an empty folder; then a plain sequential loop of sewfmu.run over the very points it
evaluated, in the same process (sewfmu.run also estimates each run's coupling error with a run
at twice the step, and gathers provenance); then the floor: the run loop and the analysis alone
over the same points (what one evaluation runs); then `sewfmu run` as its own process for the
first few (what a script that calls the command line per point pays: start-up, files). The
in-process loops are alternated and the better of two kept; printed side by side.

    .venv/bin/python bench/design.py
"""
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import sewfmu

SET = {"experiment.revolutions": 3}
VARY = {"punch.F10": "15..40 N", "punch.c2": "2e4..1.5e5 N/m"}
# the figures at F10 = 30 N, c2 = 80 000 N/m: a point the optimization must find
TARGET = {"F2_weld_mean": "34.734 N", "contact_duration_deg": "145.555 deg"}
PROCESSES = 5                      # points run as `sewfmu run` processes
GLOBAL_POINTS = 80                 # the global method's budget (4 generations of 20)


def optimization() -> tuple[float, object]:
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        found = sewfmu.optimize("punch_drive", vary=VARY, target=TARGET, set=SET, out=out)
        return time.perf_counter() - start, found


def loop(points) -> float:
    start = time.perf_counter()
    for f10, c2 in points:
        sewfmu.run("punch_drive", set={**SET, "punch.F10": f10, "punch.c2": c2})
    return time.perf_counter() - start


def bare(points) -> float:
    """The floor: the run loop and the analysis alone, FMUs found once (what an evaluation is)."""
    from sewfmu.scenarios.cosim.master import run
    from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
    from sewfmu.scenarios.runs.runner import summarize

    base = sewfmu.load("punch_drive", set=SET)
    paths = fmus_for(base)
    start = time.perf_counter()
    for f10, c2 in points:
        sc = base.copy()
        sc.set_value("punch.F10", f10)
        sc.set_value("punch.c2", c2)
        summarize(run(sc, paths))
    return time.perf_counter() - start


def processes(points) -> float:
    command = [str(Path(sys.executable).with_name("sewfmu")), "run", "punch_drive"]
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as out:
        for f10, c2 in points:
            subprocess.run(command + ["--set", "experiment.revolutions=3", "--set",
                                      f"punch.F10={f10!r}", "--set", f"punch.c2={c2!r}",
                                      "--out", out], check=True, capture_output=True,
                           env={**os.environ, "PYTHONWARNINGS": "ignore"})
    return time.perf_counter() - start


def global_study(workers: int) -> tuple[float, object]:
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        found = sewfmu.optimize("punch_drive", vary=VARY, target=TARGET, set=SET, out=out,
                                method="global", workers=workers, max_evaluations=GLOBAL_POINTS)
        return time.perf_counter() - start, found


def sweep_of(points, workers: int) -> float:
    """A plain sweep of the same points on as many workers: what the study's batches are."""
    from sewfmu.scenarios.runs.sweep import Point, run_sweep

    scenario = sewfmu.load("punch_drive", set=SET)
    todo = [Point(i, (("punch.F10", a), ("punch.c2", b))) for i, (a, b) in enumerate(points)]
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        run_sweep(scenario, todo, Path(out), workers=workers, progress=False)
        return time.perf_counter() - start


def parallel() -> None:
    """The global method on one worker and on two, and a plain sweep of its points on two."""
    one, found = global_study(1)
    two, found2 = global_study(2)
    assert found.best == found2.best           # the answer does not depend on the workers
    points = [(float(a), float(b)) for a, b in zip(found.evaluations["punch.F10"],
                                                     found.evaluations["punch.c2"])]
    swept = sweep_of(points, 2)
    floor = bare(points)
    n = len(points)
    print(f"\nglobal method (differential evolution), {n} evaluations:")
    print("| what | wall [s] | evaluations/s |\n|---|---|---|")
    print(f"| 1 worker | {one:.2f} | {n / one:.2f} |")
    print(f"| 2 workers | {two:.2f} | {n / two:.2f} |")
    print(f"| a plain sweep of the same points, 2 workers | {swept:.2f} | {n / swept:.2f} |")
    print(f"| the run loop and analysis alone over them (floor, 1 process) | {floor:.2f} | "
          f"{n / floor:.2f} |")
    print(f"2 workers over 1: {one / two:.2f} x; the study on 1 worker over the floor: "
          f"{one / floor:.2f}, on 2 over the plain sweep: {two / swept:.2f} (1 = no overhead)")


def main():
    sewfmu.run("punch_drive", set=SET)        # FMUs built and loaded outside the timing
    walls, loops, floors = [], [], []
    for _ in range(2):
        wall, found = optimization()
        points = [(float(a), float(b)) for a, b in zip(found.evaluations["punch.F10"],
                                                         found.evaluations["punch.c2"])]
        walls.append(wall)
        loops.append(loop(points))
        floors.append(bare(points))
    n = len(points)
    wall, plain, floor = min(walls), min(loops), min(floors)
    own = processes(points[:PROCESSES]) / PROCESSES
    print(f"punch_drive, 3 revolutions; {found.algorithm}, {n} evaluations, "
          f"best {found.best}")
    print("| what | per point [s] | points/s |\n|---|---|---|")
    print(f"| sewfmu.optimize (whole study, {n} points) | {wall / n:.3f} | {n / wall:.2f} |")
    print(f"| sewfmu.run loop over the same points | {plain / n:.3f} | {n / plain:.2f} |")
    print(f"| the run loop and analysis alone (floor) | {floor / n:.3f} | {n / floor:.2f} |")
    print(f"| `sewfmu run` process per point (first {PROCESSES}) | {own:.3f} | {1 / own:.2f} |")
    print(f"optimization over the sewfmu.run loop: {wall / plain:.2f}; over the floor: "
          f"{wall / floor:.2f} (1 = no overhead); a process per point over an evaluation: "
          f"{own / (wall / n):.2f}")
    parallel()
    print(f"measured {time.strftime('%Y-%m-%d')} on {os.cpu_count()} CPUs, load "
          f"{os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
