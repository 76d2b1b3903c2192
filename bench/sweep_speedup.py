"""Speed-up of the 27-point punch sweep (ω × F30 × c3) with 2 local worker processes over 1,
measured side by side in one run: each timing includes forking its workers; the fork server
(which imports sewfmu once per session) is started before either, and the two are alternated.

    .venv/bin/python bench/sweep_speedup.py
"""
import tempfile
import time
from pathlib import Path

from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.runs.sweep import points_of, run_sweep


def timed(workers: int) -> float:
    scenario = load("punch_grid")
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        rows = run_sweep(scenario, points_of(scenario), Path(out), workers=workers,
                         progress=False)
        elapsed = time.perf_counter() - start
    assert all(r["status"] == "ok" for r in rows) and len(rows) == 27
    return elapsed


def main():
    scenario = load("punch_grid")
    fmus_for(scenario)                    # build outside the timing
    with tempfile.TemporaryDirectory() as out:          # start the fork server
        run_sweep(scenario, points_of(scenario)[:1], Path(out), workers=1, progress=False)
    ones, twos = [], []
    for _ in range(2):
        ones.append(timed(1))
        twos.append(timed(2))
    one, two = min(ones), min(twos)
    print("| workers | wall [s] for 27 points (best of 2) |\n|---|---|")
    print(f"| 1 | {one:.2f} |\n| 2 | {two:.2f} |")
    print(f"speed-up 2 workers over 1: **{one / two:.2f}** (goal >= 1.8)")


if __name__ == "__main__":
    main()
