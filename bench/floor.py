"""sewfmu at the floor (issue 38): side by side in one run, on punch_drive (Jacobi, 3 FMUs, 9 FMI
calls a step), every variant checked to give the identical F2 series (np.array_equal):

1. warm, in one process: `sewfmu.run` (with its accuracy estimate switched off,
   experiment.accuracy = "off", like for like; and as by default, with the estimate: the
   coarser run is about +50 % of work the minimal loop does not do) against a minimal fmpy loop
   over the same FMU files (raw FMI calls through fmpy's ctypes functions, arrays prepared once,
   Jacobi in sewfmu's order, every output recorded): its whole run, load, initialize, step,
   free; and the master's step loop alone against the minimal loop's;
2. as whole processes: `sewfmu run punch_drive --out DIR` (with and without the estimate)
   against a minimal script that loads the same FMUs, steps them and writes the same CSV;
3. each FMU's cost per step in plain fmpy (set its inputs from a recorded series, doStep, get
   its outputs: the calls of the minimal loop), for the FMUs built from the code before issue
   38 (commit 190f0c1, `--before DIR`, built there if missing) and for today's;
4. a sweep point (a worker's seconds per point) against a standalone run of that point;
5. with --instructions (valgrind): the warm runs of 1. by instruction count, which a shared
   machine's load does not move.

    .venv/bin/python bench/floor.py [--repeat N] [--before DIR] [--instructions]
"""
from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

import sewfmu
from sewfmu.scenarios.cosim.master import Master
from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
from sewfmu.scenarios.format.loader import load

ROOT = Path(__file__).resolve().parent.parent
# CPU time, not wall time: this machine's 2 CPUs are shared with other work, which lengthens
# wall times at random; a process's own CPU time varies far less (whole processes: their
# user + system time, from the kernel's accounting of the finished child)
CLOCK = time.process_time
BEFORE_COMMIT = "190f0c1"
# as on a user's machine: Python keeps the bytecode it compiles; both sides alike
ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}

# The minimal loop: fmpy and numpy only, the same calls sewfmu's Jacobi master makes in the same
# order. Run in this process (warm) and, as the text of a script, as a whole process.
MINIMAL = r'''
import ctypes, sys, time
import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave, fmi2Real, fmi2Boolean, fmi2ValueReference


def prepare(paths, unzipped=None):
    """Extract and read each FMU once (sewfmu keeps its extracted FMUs between runs too; the
    whole-process script is given them extracted already, in `unzipped`, so that it pays no
    unzipping and keeps the bytecode of the FMUs' code, as sewfmu's cache does)."""
    return {name: (str(unzipped[name]) if unzipped else extract(str(path)),
                   read_model_description(str(path)))
            for name, path in paths.items()}


def minimal_run(prepared, n, h, stop, csv=None):
    """shaft -> linkage -> punch, Jacobi, every output recorded at every step; the records."""
    names = ("shaft", "linkage", "punch")
    fmus, comps, outs, bools = [], [], [], []
    for name in names:
        unzip, md = prepared[name]
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip,
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        fmus.append((fmu, md))
    out_vr, out_buf, bool_vr, bool_buf, in_vr, in_buf, header = [], [], [], [], [], [], []
    for fmu, md in fmus:
        real = [v for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
        boolean = [v for v in md.modelVariables if v.causality == "output"
                   and v.type == "Boolean"]
        inputs = [v for v in md.modelVariables if v.causality == "input"]
        out_vr.append((fmi2ValueReference * len(real))(*[v.valueReference for v in real]))
        out_buf.append((fmi2Real * len(real))())
        bool_vr.append((fmi2ValueReference * len(boolean))(*[v.valueReference for v in boolean]))
        bool_buf.append((fmi2Boolean * len(boolean))())
        in_vr.append((fmi2ValueReference * len(inputs))(*[v.valueReference for v in inputs]))
        in_buf.append((fmi2Real * len(inputs))())
        header.append((real, boolean))
    dll = [fmu.dll for fmu, _ in fmus]
    c = []
    for k, (fmu, md) in enumerate(fmus):
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0, stopTime=stop)
        fmu.enterInitializationMode()
        if k == 0:
            omega0 = next(v for v in md.modelVariables if v.name == "omega0")
            fmu.setReal([omega0.valueReference], [100.0])
        else:                       # the inputs from the source's outputs (in declared order)
            in_buf[k][:] = list(out_buf[k - 1])[:len(in_buf[k])]
            dll[k].fmi2SetReal(fmu.component, in_vr[k], len(in_buf[k]), in_buf[k])
        fmu.exitInitializationMode()
        dll[k].fmi2GetReal(fmu.component, out_vr[k], len(out_buf[k]), out_buf[k])
        if len(bool_buf[k]):
            dll[k].fmi2GetBoolean(fmu.component, bool_vr[k], len(bool_buf[k]), bool_buf[k])
        c.append(fmu.component)
    n_cols = sum(len(b) for b in out_buf) + sum(len(b) for b in bool_buf)
    records = np.empty((n + 1, 1 + n_cols))
    step0, step1, step2 = (d.fmi2DoStep for d in dll)
    set1, set2 = dll[1].fmi2SetReal, dll[2].fmi2SetReal
    get0, get1, get2 = (d.fmi2GetReal for d in dll)
    getb2 = dll[2].fmi2GetBoolean
    o0, o1, o2 = out_buf
    i1, i2 = in_buf[1], in_buf[2]
    b2 = bool_buf[2]
    args = [(c[k], out_vr[k], len(out_buf[k]), out_buf[k]) for k in range(3)]
    a0, a1, a2 = args
    s1 = (c[1], in_vr[1], 3, i1)
    s2 = (c[2], in_vr[2], 3, i2)
    g2 = (c[2], bool_vr[2], 1, b2)
    c0, c1, c2 = c

    def row(r, t):
        records[r] = (t, *o0, *o1, *o2[:7], b2[0], *o2[7:])

    row(0, 0.0)
    started = time.process_time()
    for k in range(1, n + 1):
        t = (k - 1) * h
        if step0(c0, t, h, 1) or step1(c1, t, h, 1) or step2(c2, t, h, 1):
            raise RuntimeError(f"doStep failed at t = {t}")
        get0(*a0)
        i1[0], i1[1], i1[2] = o0[0], o0[1], o0[2]
        set1(*s1)
        get1(*a1)
        i2[0], i2[1], i2[2] = o1[0], o1[1], o1[2]
        set2(*s2)
        get2(*a2)
        getb2(*g2)
        row(k, stop if k == n else k * h)
    loop = time.process_time() - started
    for fmu, _ in fmus:
        fmu.terminate()
        fmu.freeInstance()
    if csv:
        cols = [f"{p}.{v.name} [{v.unit}]" if v.unit else f"{p}.{v.name}"
                for p, (real, boolean) in zip(names, header) for v in (*real, *boolean)]
        # the punch's Boolean contact sits where sewfmu records it: after Delta
        cols = cols[:len(o0) + len(o1) + 7] + [cols[-1]] + cols[len(o0) + len(o1) + 7:-1]
        np.savetxt(csv, records, delimiter=",", header=",".join(["time [s]"] + cols),
                   comments="", fmt="%.17g")
    return records, loop
'''
_ns: dict = {}
exec(compile(MINIMAL, "minimal_loop", "exec"), _ns)
prepare, minimal_run = _ns["prepare"], _ns["minimal_run"]

SCRIPT = MINIMAL + r'''
from pathlib import Path
names = ("shaft", "linkage", "punch")
paths = dict(zip(names, map(Path, sys.argv[1:4])))
n, h, stop = int(sys.argv[4]), float(sys.argv[5]), float(sys.argv[6])
unzipped = dict(zip(names, sys.argv[8:11]))
minimal_run(prepare(paths, unzipped), n, h, stop, csv=Path(sys.argv[7]) / "results.csv")
'''


def _alternating(funcs, repeat: int) -> list[list[float]]:
    """The CPU times of each function over `repeat` alternated rounds (after one round to warm
    up): alternating spreads the drift of a shared machine's load over every function."""
    for f in funcs:
        f()
    times = [[] for _ in funcs]
    for _ in range(repeat):
        for k, f in enumerate(funcs):
            start = CLOCK()
            f()
            times[k].append(CLOCK() - start)
    return times


def _best_alternating(funcs, repeat: int) -> list[float]:
    """The best (shortest) CPU time of each function over `repeat` alternated rounds: on a
    shared machine the other processes' load only ever adds."""
    return [min(t) for t in _alternating(funcs, repeat)]


def _paired(times: list[list[float]], k: int) -> float:
    """The median over the rounds of function k's time over function 0's in the same round:
    each ratio of two runs made back to back, under the same load."""
    return statistics.median(t / t0 for t, t0 in zip(times[k], times[0]))


def _punch_drive():
    sc = load("punch_drive")
    paths = fmus_for(sc)
    n, h = sc.even_steps()
    by_instance = {name: paths[inst.fmu] for name, inst in sc.instances.items()}
    return sc, by_instance, n, h, sc.end_time()


def _f2(records) -> np.ndarray:
    return records[:, 12]           # time, shaft 3, linkage 4, punch y y_dot y_ddot F1 F2


def warm(repeat: int) -> dict:
    sc, paths, n, h, stop = _punch_drive()
    prepared = prepare(paths)
    records, _ = minimal_run(prepared, n, h, stop)
    off = sewfmu.run("punch_drive", {"experiment.accuracy": "off"})
    on = sewfmu.run("punch_drive")
    assert np.array_equal(off.series["punch.F2"], _f2(records)), "F2 differs (estimate off)"
    assert np.array_equal(on.series["punch.F2"], _f2(records)), "F2 differs (default run)"
    loops = {"minimal": [], "master": []}

    def minimal():
        loops["minimal"].append(minimal_run(prepared, n, h, stop)[1])

    def master_loop():
        with Master(load("punch_drive"), fmus_for(sc)) as m:
            start = CLOCK()
            m.steps(m.n_steps)          # the run's own loop, without progress reports
            loops["master"].append(CLOCK() - start)

    times = _alternating(
        [minimal, lambda: sewfmu.run("punch_drive", {"experiment.accuracy": "off"}),
         lambda: sewfmu.run("punch_drive"), master_loop], repeat)
    t_min, t_off, t_on, _ = (min(t) for t in times)
    loop_min = min(loops["minimal"]) / n * 1e6
    loop_master = min(loops["master"]) / n * 1e6
    print(f"1. warm, one process, punch_drive ({n} steps), identical F2 series; the best of "
          f"{repeat} alternated rounds, and the median of the rounds' own ratios:")
    print("| measure | seconds | × minimal loop: best / median of rounds | target |")
    print("|---|---|---|---|")
    print(f"| minimal fmpy loop, whole run (load, initialize, step, free) | {t_min:.3f} | 1.00 | |")
    print(f"| sewfmu.run, accuracy estimate off (experiment.accuracy = \"off\": like for like) "
          f"| {t_off:.3f} | **{t_off / t_min:.2f} / {_paired(times, 1):.2f}** | ≤ 1.05 |")
    print(f"| sewfmu.run as by default (with its accuracy estimate: a second, coarser run) "
          f"| {t_on:.3f} | {t_on / t_min:.2f} / {_paired(times, 2):.2f} | |")
    print(f"| step loop, µs per step: sewfmu's master {loop_master:.1f}, minimal loop "
          f"{loop_min:.1f} | | {loop_master / loop_min:.2f} / "
          f"{statistics.median(a / b for a, b in zip(loops['master'][1:], loops['minimal'][1:])):.2f} | |")
    return {"minimal": t_min, "off": t_off, "on": t_on}


def _wall(cmd, cwd=None) -> float:
    """The CPU time (user + system) of a whole process running `cmd` and of its children."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, check=True, capture_output=True, env=ENV, cwd=cwd)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def whole(repeat: int) -> None:
    sc, paths, n, h, stop = _punch_drive()
    with tempfile.TemporaryDirectory(prefix="sewfmu_floor_") as tmp:
        tmp = Path(tmp)
        script = tmp / "minimal.py"
        script.write_text(SCRIPT)
        for d in ("min", "off", "on"):
            (tmp / d).mkdir()
        unzipped = {}
        for k in ("shaft", "linkage", "punch"):
            unzipped[k] = tmp / "unzipped" / k
            with zipfile.ZipFile(paths[k]) as fmu:
                fmu.extractall(unzipped[k])
        commands = [
            [sys.executable, str(script), *(str(paths[k]) for k in ("shaft", "linkage", "punch")),
             str(n), repr(h), repr(stop), str(tmp / "min"),
             *(str(unzipped[k]) for k in ("shaft", "linkage", "punch"))],
            [sys.executable, "-m", "sewfmu", "run", "punch_drive", "--set",
             "experiment.accuracy=off", "--out", str(tmp / "off")],
            [sys.executable, "-m", "sewfmu", "run", "punch_drive", "--out", str(tmp / "on")],
        ]
        for cmd in commands:
            _wall(cmd)
        a = np.loadtxt(tmp / "min" / "results.csv", delimiter=",", skiprows=1)
        b = np.loadtxt(tmp / "off" / "results.csv", delimiter=",", skiprows=1)
        assert np.array_equal(a, b), "the minimal script's CSV differs from sewfmu's"
        times = [[] for _ in commands]
        for _ in range(repeat):
            for k, cmd in enumerate(commands):
                times[k].append(_wall(cmd))
        t_min, t_off, t_on = (min(t) for t in times)
    print("\n2. whole processes (the same CSV, identical numbers):")
    print("| process | seconds | × minimal script | target |")
    print("|---|---|---|---|")
    print(f"| minimal script: load the FMUs, step, write results.csv | {t_min:.3f} | 1.00 | |")
    print(f"| `sewfmu run punch_drive --set experiment.accuracy=off` (like for like) | "
          f"{t_off:.3f} | **{t_off / t_min:.2f}** | ≤ 1.1 |")
    print(f"| `sewfmu run punch_drive` as by default (with the estimate) | {t_on:.3f} | "
          f"{t_on / t_min:.2f} | |")


def _elapsed(cmd) -> float:
    """The wall time of a whole process (a sweep's workers are compared by their wall time)."""
    start = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, env=ENV)
    return time.perf_counter() - start


def _before_fmus(folder: Path) -> Path:
    """The FMUs built from the model code at BEFORE_COMMIT (its components/, checked out into a
    temp folder), by today's builder."""
    from sewfmu.scenarios.fmu_build.build import build_fmu  # only when building the old FMUs

    if all((folder / f"{name}.fmu").exists() for name in ("MainShaft", "PunchLinkage",
                                                           "PunchContact")):
        return folder
    with tempfile.TemporaryDirectory(prefix="sewfmu_before_") as src:
        subprocess.run(f"git -C {ROOT} archive {BEFORE_COMMIT} components | tar -x -C {src}",
                       shell=True, check=True)
        for name in ("MainShaft", "PunchLinkage", "PunchContact"):
            build_fmu(name, folder, source=Path(src) / "components")
    return folder


def per_fmu(repeat: int, before: Path) -> None:
    """Each FMU alone in plain fmpy, fed the inputs the coupled run gave it."""
    sc, paths, n, h, stop = _punch_drive()
    prepared_now = prepare(paths)
    records, _ = minimal_run(prepared_now, n, h, stop)
    old = {k: before / p.name for k, p in paths.items()}
    prepared_old = prepare(old)
    old_records, _ = minimal_run(prepared_old, n, h, stop)
    assert np.array_equal(old_records, records), "the FMUs before and after differ"
    feeds = {"shaft": None, "linkage": records[:, 1:4], "punch": records[:, 4:7]}
    print("\n3. each FMU's cost per step in plain fmpy (set inputs, doStep, get outputs), µs:")
    print("| FMU | before (190f0c1) | now | change | target |")
    print("|---|---|---|---|---|")
    total_old = total_new = 0.0
    for name in ("shaft", "linkage", "punch"):
        t_old, t_new = _best_alternating(
            [lambda p=prepared_old: _alone(p, name, feeds[name], n, h, stop),
             lambda p=prepared_now: _alone(p, name, feeds[name], n, h, stop)], repeat)
        t_old, t_new = t_old / n * 1e6, t_new / n * 1e6
        total_old += t_old
        total_new += t_new
        print(f"| {paths[name].stem} | {t_old:.1f} | {t_new:.1f} | "
              f"{100 * (t_new / t_old - 1):+.0f} % | ≤ −15 % |")
    print(f"| the three | {total_old:.1f} | {total_new:.1f} | "
          f"**{100 * (total_new / total_old - 1):+.0f} %** | ≤ −15 % |")


def _alone(prepared, name, feed, n, h, stop) -> None:
    from fmpy.fmi2 import FMU2Slave, fmi2Boolean, fmi2Real, fmi2ValueReference

    unzip, md = prepared[name]
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, instanceName=name,
                    modelIdentifier=md.coSimulation.modelIdentifier)
    real = [v.valueReference for v in md.modelVariables
            if v.causality == "output" and v.type == "Real"]
    boolean = [v.valueReference for v in md.modelVariables
               if v.causality == "output" and v.type == "Boolean"]
    inputs = [v.valueReference for v in md.modelVariables if v.causality == "input"]
    vr, buf = (fmi2ValueReference * len(real))(*real), (fmi2Real * len(real))()
    bvr, bbuf = (fmi2ValueReference * len(boolean))(*boolean), (fmi2Boolean * len(boolean))()
    ivr, ibuf = (fmi2ValueReference * len(inputs))(*inputs), (fmi2Real * len(inputs))()
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0, stopTime=stop)
    fmu.enterInitializationMode()
    if feed is not None:
        ibuf[:] = list(feed[0])
        fmu.dll.fmi2SetReal(fmu.component, ivr, len(inputs), ibuf)
    fmu.exitInitializationMode()
    c, dll = fmu.component, fmu.dll
    step, get, getb, set_ = dll.fmi2DoStep, dll.fmi2GetReal, dll.fmi2GetBoolean, dll.fmi2SetReal
    nr, nb, ni = len(real), len(boolean), len(inputs)
    for k in range(1, n + 1):
        if step(c, (k - 1) * h, h, 1):
            raise RuntimeError(f"{name}: doStep failed")
        if feed is not None:
            ibuf[0], ibuf[1], ibuf[2] = feed[k]
            set_(c, ivr, ni, ibuf)
        get(c, vr, nr, buf)
        if nb:
            getb(c, bvr, nb, bbuf)
    fmu.terminate()
    fmu.freeInstance()


def sweep_point(repeat: int) -> None:
    """A sweep point against a standalone run of one point: by wall time with 2 workers (as
    bench/speed.py), and by CPU time, the point as a worker runs it (run_point in a warm
    process) against the standalone process's CPU time (on a shared machine the wall time of
    2 workers measures the other work as much as the sweep)."""
    from sewfmu.scenarios.runs.sweep import grid_points, run_point, run_sweep

    sc = load("punch_drive")
    sc.set_value("experiment.revolutions", 2)
    grid = {"shaft.omega0": [80.0 + 240.0 * k / 11 for k in range(12)],
            "punch.F30": [10.0 * k / 9 for k in range(10)]}
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        rows = run_sweep(sc, grid_points(grid), Path(out), workers=2, progress=False)
        wall = time.perf_counter() - start
        assert all(r["status"] == "ok" for r in rows)
        per_point = 2 * wall / len(rows)
        cmd = [sys.executable, "-m", "sewfmu", "run", "punch_drive", "--set",
               "experiment.revolutions=2", "--set", "shaft.omega0=200", "--out", out]
        _elapsed(cmd)
        alone = min(_elapsed(cmd) for _ in range(repeat))
        alone_cpu = min(_wall(cmd) for _ in range(repeat))
    points = grid_points(grid)
    run_point(sc, points[0], "warm-up")
    start = CLOCK()
    for point in points:
        run_point(sc, point, "k")
    cpu_point = (CLOCK() - start) / len(points)
    print("\n4. a sweep point (120 points of 2 revolutions) against a standalone `sewfmu run` of "
          "one point (default, with its estimate):")
    print("| measure | sweep point | standalone | ratio | target |")
    print("|---|---|---|---|---|")
    print(f"| CPU time: the point in a warm worker / the whole process | {cpu_point:.4f} s | "
          f"{alone_cpu:.3f} s | **{cpu_point / alone_cpu:.3f}** | ≤ 0.15 |")
    print(f"| wall time: 2 workers' seconds per point / the whole process | {per_point:.4f} s | "
          f"{alone:.3f} s | {per_point / alone:.3f} | ≤ 0.15 |")


# The warm comparison by instruction count (valgrind's callgrind), which the load of a shared
# machine does not move: each side runs twice to warm up, then once inside qsort's comparison
# callback, so that --toggle-collect counts that run alone.
COUNTED = r'''
import ctypes, sys
sys.path.insert(0, sys.argv[2])
import floor, sewfmu
sc, paths, n, h, stop = floor._punch_drive()
prepared = floor.prepare(paths)
run = {"minimal": lambda: floor.minimal_run(prepared, n, h, stop),
       "sewfmu": lambda: sewfmu.run("punch_drive", {"experiment.accuracy": "off"})}[sys.argv[1]]
run(); run()
compare = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p)(
    lambda a, b: (run(), 0)[1])
ctypes.CDLL(None).qsort((ctypes.c_int * 2)(1, 2), 2, ctypes.sizeof(ctypes.c_int), compare)
'''


def instructions() -> None:
    """Instructions of one warm run of each side, counted by callgrind."""
    import re
    import shutil

    if not shutil.which("valgrind"):
        print("\n5. instructions: valgrind is not installed (apt install valgrind)")
        return
    counts = {}
    with tempfile.TemporaryDirectory(prefix="sewfmu_floor_") as tmp:
        script = Path(tmp) / "counted.py"
        script.write_text(COUNTED)
        for side in ("minimal", "sewfmu"):
            proc = subprocess.run(
                ["valgrind", "--tool=callgrind", "--collect-atstart=no",
                 "--toggle-collect=*qsort*", f"--callgrind-out-file={tmp}/{side}.out",
                 sys.executable, str(script), side, str(ROOT / "bench")],
                capture_output=True, text=True, env=ENV, check=True)
            counts[side] = int(re.search(r"Collected : (\d+)", proc.stderr).group(1))
    print("\n5. warm, by instruction count (callgrind; one run of each side after two):")
    print("| side | instructions | × minimal loop | target |")
    print("|---|---|---|---|")
    print(f"| minimal fmpy loop, whole run | {counts['minimal'] / 1e9:.3f} G | 1.000 | |")
    print(f"| sewfmu.run, accuracy estimate off | {counts['sewfmu'] / 1e9:.3f} G | "
          f"**{counts['sewfmu'] / counts['minimal']:.3f}** | ≤ 1.05 |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--before", default=str(Path(tempfile.gettempdir())
                                                 / "sewfmu_fmus_190f0c1"),
                        help="FMUs built from the code before issue 38 (built there if missing)")
    parser.add_argument("--only", choices=("warm", "whole", "fmus", "sweep", "instructions"))
    parser.add_argument("--instructions", action="store_true",
                        help="also count the warm runs' instructions under valgrind (2 minutes)")
    args = parser.parse_args()
    print(f"sewfmu floor benchmark, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
          f"{os.cpu_count()} CPUs, Python {sys.version.split()[0]}\n")
    # built first: the minimal loops instantiate FMUs without sewfmu's host, so the FMUs' own
    # copy of pythonfmu (without binaries) would be the one a build found afterwards
    before = _before_fmus(Path(args.before)) if args.only in (None, "fmus") else None
    if args.only in (None, "warm"):
        warm(args.repeat)
    if args.only in (None, "whole"):
        whole(args.repeat)
    if args.only in (None, "fmus"):
        per_fmu(args.repeat, before)
    if args.only in (None, "sweep"):
        sweep_point(args.repeat)
    if args.only == "instructions" or (args.only is None and args.instructions):
        instructions()


if __name__ == "__main__":
    main()
