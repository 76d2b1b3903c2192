"""Speed where users feel it, measured side by side in one run on this machine:

1. whole process at equal accuracy: `sewfmu run punch_drive --set experiment.master="adaptive"`
   against a plain script that solves the same physics with scipy at rtol 1e-4 (the project's
   monolithic solver, sampled where the figures are read); both checked against the tight
   monolithic solution (rtol 1e-10): medians of alternating runs;
2. the same two in one warm process;
3. µs per communication step and FMU: the master stepping punch_drive (Jacobi) against the model
   code alone (the same three models called directly for the same steps);
4. a sweep point (a worker's seconds per point, 120 points on 2 workers) against a standalone run
   of that point (a whole process);
5. a worker's resident memory growth per point over 240 points;
6. the speed-up of 2 workers over 1 at 27 and 400 points;
7. Dask (a local cluster of 2 worker processes) against the local pool: throughput per worker.

    .venv/bin/python bench/speed.py [--repeat N]
"""
from __future__ import annotations

import argparse
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from sewfmu.components.registry import FMUS
from sewfmu.scenarios.cosim.master import Master, run
from sewfmu.scenarios.fmu_build.up_to_date import ensure_built, fmus_for
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.runs.compare import monolithic_summary
from sewfmu.scenarios.runs.runner import summarize
from sewfmu.scenarios.runs.sweep import grid_points, run_sweep

ONSET_WITHIN, FORCE_WITHIN = 0.002, 0.002          # ° and N from the tight solution

MONOLITHIC_SCRIPT = """
import math
from sewfmu.scenarios.mechanisms import punch
t_end = 10 * 2 * math.pi / 100.0
solution = punch.solve({}, {}, {}, t_end, sample_step=2.5e-4,
                                  sample_from=t_end - 2.2 * math.pi / 100.0, rtol=1e-4,
                                  atol=1e-7)
print(punch.summary_of_monolithic(solution))
"""


# as on a user's machine: Python keeps the bytecode it compiles (this machine's environment says
# not to); both sides of every comparison run with the same setting
ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def _wall(cmd: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, env=ENV)
    return time.perf_counter() - start


def _alternating(commands: list[list[str]], repeat: int) -> list[float]:
    """Median wall time of each command, the commands alternated so that load drifts hit all."""
    for cmd in commands:
        _wall(cmd)                                   # warm the file cache and the FMU cache
    times = [[] for _ in commands]
    for _ in range(repeat):
        for k, cmd in enumerate(commands):
            times[k].append(_wall(cmd))
    return [statistics.median(t) for t in times]


def _errors(figures: dict, tight: dict) -> tuple[float, float]:
    return (abs(figures["contact_onset_deg"] - tight["contact_onset_deg"]),
            abs(figures["F2_weld_mean"] - tight["F2_weld_mean"]))


def _monolithic_in_process():
    from sewfmu.scenarios.mechanisms import punch
    t_end = 10 * 2 * math.pi / 100.0
    solution = punch.solve({}, {}, {}, t_end, sample_step=2.5e-4,
                                      sample_from=t_end - 2.2 * math.pi / 100.0, rtol=1e-4,
                                      atol=1e-7)
    return punch.summary_of_monolithic(solution)


def whole_process_and_warm(repeat: int) -> None:
    adaptive = load("punch_drive")
    adaptive.set_value("experiment.master", "adaptive")
    tight, _ = monolithic_summary(load("punch_drive"))
    cosim_err = _errors(summarize(run(adaptive, fmus_for(adaptive))), tight)
    mono_err = _errors(_monolithic_in_process(), tight)
    equal = (max(cosim_err[0], mono_err[0]) <= ONSET_WITHIN
             and max(cosim_err[1], mono_err[1]) <= FORCE_WITHIN)
    print(f"accuracy against the tight monolithic solution: co-simulation (adaptive) "
          f"{cosim_err[0]:.4f}° {cosim_err[1]:.4f} N; monolithic rtol 1e-4 {mono_err[0]:.4f}° "
          f"{mono_err[1]:.4f} N (both within {ONSET_WITHIN}° and {FORCE_WITHIN} N: {equal})")
    out = tempfile.mkdtemp(prefix="sewfmu_bench_")
    cosim = [sys.executable, "-m", "sewfmu", "run", "punch_drive", "--set",
             'experiment.master="adaptive"', "--out", out]
    a, b = _alternating([cosim, [sys.executable, "-c", MONOLITHIC_SCRIPT]], repeat)
    print(f"1. whole process, medians of {repeat}: sewfmu run (adaptive) {a:.3f} s, monolithic "
          f"script {b:.3f} s: ratio **{a / b:.2f}** (target <= 0.5)")
    paths = fmus_for(adaptive)
    warm_cosim = statistics.median(run(adaptive, paths).wall_time for _ in range(repeat))
    warm_mono = []
    for _ in range(repeat):
        start = time.perf_counter()
        _monolithic_in_process()
        warm_mono.append(time.perf_counter() - start)
    print(f"2. one warm process, medians of {repeat}: adaptive run {warm_cosim:.3f} s, monolithic "
          f"solve {statistics.median(warm_mono):.3f} s: ratio "
          f"**{warm_cosim / statistics.median(warm_mono):.2f}**")


def _model_only(steps: int, h: float) -> float:
    """The three models of punch_drive for `steps` steps of h, as the FMUs step them."""
    from sewfmu.components.punch_contact import PunchContact, PunchContactParams
    from sewfmu.components.punch_linkage import PunchLinkage
    from sewfmu.components.shaft import MainShaft, ShaftParams
    shaft, linkage = MainShaft(ShaftParams()), PunchLinkage()
    contact = PunchContact(PunchContactParams())
    e = linkage.motion(*shaft.state(0.0))
    state = contact.initial_state(e.xi, e.xi_dot, e.xi_ddot)
    start = time.perf_counter()
    for k in range(steps):
        state = contact.step(state, e.xi, e.xi_dot, 0.5 * e.xi_ddot, h)
        e = linkage.motion(*shaft.state((k + 1) * h))
        contact.outputs(state, e.xi, e.xi_dot, e.xi_ddot)
    return time.perf_counter() - start


def per_step(repeat: int) -> None:
    sc = load("punch_drive")
    paths = fmus_for(sc)
    master_times, model_times = [], []
    for _ in range(repeat):
        with Master(sc, paths) as master:
            start = time.perf_counter()
            while not master.finished():
                master.step()
            master_times.append(time.perf_counter() - start)
            steps, h = master.n_steps, master.h
        model_times.append(_model_only(steps, h))
    fmus = len(sc.instances)
    a = statistics.median(master_times) / steps / fmus * 1e6
    b = statistics.median(model_times) / steps / fmus * 1e6
    call = _fmi_call_cost(sc, paths)
    print(f"3. per communication step and FMU (punch_drive, {steps} steps, {fmus} FMUs): master "
          f"{a:.1f} µs, model code alone {b:.1f} µs: ratio **{a / b:.2f}** (target <= 1.5); "
          f"what stands in the way: one call through pythonfmu's binary costs {call:.1f} µs "
          f"(a getReal of values already computed), and an FMU takes at least three a step "
          f"(set inputs, doStep, get outputs): a floor of {(b + 3 * call) / b:.2f} before any "
          f"bookkeeping")


def _fmi_call_cost(sc, paths) -> float:
    """µs of one getReal round trip into an FMU's Python code whose outputs are computed."""
    with Master(sc, paths) as master:
        master.step()
        inst = master.instances[-1]
        n = 20000
        start = time.perf_counter()
        for _ in range(n):
            inst._get_reals()
        return (time.perf_counter() - start) / n * 1e6


def _sweep_wall(name: str, grid: dict, workers: int, revolutions: float | None = 2) -> float:
    sc = load(name)
    if revolutions:
        sc.set_value("experiment.revolutions", revolutions)
    points = grid_points(grid)
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        rows = run_sweep(sc, points, Path(out), workers=workers, progress=False)
        wall = time.perf_counter() - start
    assert all(r["status"] == "ok" for r in rows), [r for r in rows if r["status"] != "ok"][:1]
    return wall


def _grid(n_speed: int, n_preload: int) -> dict:
    return {"shaft.omega0": [80.0 + 240.0 * k / max(1, n_speed - 1) for k in range(n_speed)],
            "punch.F30": [10.0 * k / max(1, n_preload - 1) for k in range(n_preload)]}


def sweeps(repeat: int) -> None:
    wall = _sweep_wall("punch_drive", _grid(12, 10), workers=2)
    per_point = 2 * wall / 120
    out = tempfile.mkdtemp(prefix="sewfmu_bench_")
    alone = _alternating([[sys.executable, "-m", "sewfmu", "run", "punch_drive", "--set",
                           "experiment.revolutions=2", "--set", "shaft.omega0=200", "--out",
                           out]], repeat)[0]
    print(f"4. a sweep point (120 points of 2 revolutions on 2 workers): {per_point:.3f} "
          f"worker-seconds, a standalone run of one point {alone:.3f} s: ratio "
          f"**{per_point / alone:.2f}** (target <= 0.15)")
    growth = subprocess.run([sys.executable, "-c", _WORKER_MEMORY], capture_output=True,
                            text=True, check=True, env=ENV).stdout.strip()
    print(f"5. a worker's resident memory over 240 points: **{growth} KiB per point** "
          f"(target <= 10)")
    for name, grid in (("punch_grid", None), ("punch_drive", _grid(20, 20))):
        if grid is None:
            one = _sweep_wall(name, load(name).sweep["grid"], 1, None)
            two = _sweep_wall(name, load(name).sweep["grid"], 2, None)
            n = math.prod(len(v) for v in load(name).sweep["grid"].values())
        else:
            one, two = _sweep_wall(name, grid, 1), _sweep_wall(name, grid, 2)
            n = 400
        print(f"6. {n} points ({name}): 1 worker {one:.2f} s, 2 workers {two:.2f} s: speed-up "
              f"**{one / two:.2f}**")


_WORKER_MEMORY = """
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.runs.sweep import Point, run_point
def rss():
    return next(int(line.split()[1]) for line in open("/proc/self/status")
                if line.startswith("VmRSS"))
sc = load("punch_drive")
sc.set_value("experiment.revolutions", 2)
points = [Point(k, (("shaft.omega0", 80.0 + k),)) for k in range(260)]
for p in points[:20]:
    run_point(sc, p, str(p.index))
before = rss()
for p in points[20:]:
    assert run_point(sc, p, str(p.index))["status"] == "ok"
print(f"{(rss() - before) / 240:.1f}")
"""


def dask_against_local() -> None:
    try:
        from distributed import LocalCluster
    except ImportError:
        print("7. Dask: not installed (pip install 'sewfmu[dask]')")
        return
    sc = load("punch_drive")
    sc.set_value("experiment.revolutions", 2)
    points = grid_points(_grid(12, 10))
    local = _sweep_wall("punch_drive", _grid(12, 10), workers=2)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, tempfile.TemporaryDirectory() as out:
        run_sweep(sc, points[:4], Path(out) / "warm", scheduler=cluster.scheduler_address,
                  progress=False)                    # the workers import sewfmu once
        start = time.perf_counter()
        rows = run_sweep(sc, points, Path(out) / "run", scheduler=cluster.scheduler_address,
                         progress=False)
        dask = time.perf_counter() - start
    assert all(r["status"] == "ok" for r in rows)
    print(f"7. 120 points on 2 workers: local pool {local:.2f} s, Dask LocalCluster {dask:.2f} s: "
          f"Dask throughput per worker **{local / dask:.2f}** of the local pool's (target >= 0.9)")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    ensure_built(sorted(FMUS))
    print(f"sewfmu speed, {os.cpu_count()} cores, {time.strftime('%Y-%m-%d')}\n")
    whole_process_and_warm(args.repeat)
    per_step(args.repeat)
    sweeps(args.repeat)
    dask_against_local()


if __name__ == "__main__":
    main()
