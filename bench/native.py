"""Native FMUs against Python FMUs (issue 46), side by side in one run, CPU time, the median of
alternated pairs (native, python, native, python, ...), so that a shared machine's load falls on
both sides alike:

1. PunchContact's step through fmpy, as sewfmu's master makes it (fmpy's ctypes functions of the
   loaded library: setReal of the three inputs, doStep, getReal of the outputs), fed the
   slider's motion recorded from a punch_drive run; doStep's own share is the whole step less
   the same loop without doStep. fmpy's call cost is in both sides;
2. the native FMU's own cost per step, with no Python around it (bench/native/step_cost.c, a C
   loop over the same calls), in CPU time and, with valgrind, in instructions;
3. a warm `sewfmu.run("punch_drive")` on native and on Python FMUs (as by default, with the
   accuracy estimate, and without it);
4. a 100-point sweep of punch_drive over the shaft speed (wall time, 2 workers);
5. what the master costs per step on native FMUs: the run's CPU per step less its FMUs' own,
   against the 0.14 µs of a compiled FMU's step.

    .venv/bin/python bench/native.py [--repeat N] [--no-callgrind]
"""
from __future__ import annotations

import argparse
import re
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave, fmi2Boolean, fmi2Real, fmi2ValueReference

import sewfmu
from sewfmu.scenarios.fmu_build.up_to_date import ensure_built

ROOT = Path(__file__).resolve().parent.parent
CLOCK = time.process_time
STEP = 2.5e-4                    # punch_drive's step


def _median_pairs(first, second, repeat):
    """(median of first, median of second), called alternately `repeat` times each."""
    a, b = [], []
    for _ in range(repeat):
        a.append(first())
        b.append(second())
    return statistics.median(a), statistics.median(b)


# --- 1. PunchContact's step through fmpy ---------------------------------------------------
class PunchInFmpy:
    """One PunchContact instance in fmpy, initialized, with the raw calls of a step bound."""

    def __init__(self, fmu: Path):
        md = read_model_description(str(fmu))
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)),
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName="p")
        variables = {v.name: v for v in md.modelVariables}
        inputs = [variables[n].valueReference for n in ("xi", "xi_dot", "xi_ddot")]
        reals = [v.valueReference for v in md.modelVariables
                 if v.causality == "output" and v.type == "Real"]
        self.in_vr = (fmi2ValueReference * 3)(*inputs)
        self.in_buf = (fmi2Real * 3)()
        self.out_vr = (fmi2ValueReference * len(reals))(*reals)
        self.out_buf = (fmi2Real * len(reals))()
        self.bool_vr = (fmi2ValueReference * 1)(variables["contact"].valueReference)
        self.bool_buf = (fmi2Boolean * 1)()
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.t = 0.0

    def steps(self, series: np.ndarray) -> tuple[float, float]:
        """(CPU seconds per step (set, doStep, get), seconds per doStep call) over the series
        (rows xi, xi_dot, xi_ddot). Each doStep is timed on its own with perf_counter (a vDSO
        read, ~50 ns), less the same pair of reads with nothing between them."""
        dll, c = self.fmu.dll, self.fmu.component
        set_real, do_step, get_real, get_bool = (dll.fmi2SetReal, dll.fmi2DoStep,
                                                 dll.fmi2GetReal, dll.fmi2GetBoolean)
        ivr, ibuf, ovr, obuf, n_out = self.in_vr, self.in_buf, self.out_vr, self.out_buf, \
            len(self.out_buf)
        bvr, bbuf = self.bool_vr, self.bool_buf
        t, h = self.t, STEP
        tick = time.perf_counter
        in_step = idle = 0.0
        started = CLOCK()
        for xi, xi_dot, xi_ddot in series:
            ibuf[0], ibuf[1], ibuf[2] = xi, xi_dot, xi_ddot
            set_real(c, ivr, 3, ibuf)
            before = tick()
            status = do_step(c, t, h, 1)
            after = tick()
            in_step += after - before
            before = tick()
            idle += tick() - before
            if status:
                raise RuntimeError(f"doStep failed at t = {t}")
            t += h
            get_real(c, ovr, n_out, obuf)
            get_bool(c, bvr, 1, bbuf)
        spent = CLOCK() - started
        self.t = t
        return spent / len(series), (in_step - idle) / len(series)


def call_floor(fmu: Path, calls: int = 100_000) -> float:
    """µs of one call through fmpy's ctypes function that does no work in the FMU (getReal of
    no values): what any doStep through fmpy costs at the least, native or not."""
    inst = PunchInFmpy(fmu)
    get_real, c, vr, buf = inst.fmu.dll.fmi2GetReal, inst.fmu.component, inst.out_vr, \
        inst.out_buf
    started = time.perf_counter()
    for _ in range(calls):
        get_real(c, vr, 0, buf)
    return (time.perf_counter() - started) / calls * 1e6


def slider_series() -> np.ndarray:
    """The linkage's xi, xi_dot, xi_ddot at every step of punch_drive (a Python FMU run)."""
    run = sewfmu.run("punch_drive", set={"experiment.accuracy": "off"})
    frame = run.to_pandas()
    return frame[["linkage.xi", "linkage.xi_dot", "linkage.xi_ddot"]].to_numpy()[1:]


def punch_step(fmus: dict[str, Path], series, repeat: int) -> dict[str, float]:
    """µs per step (set, doStep, get; CPU) and per doStep call, native and python, each the
    median over alternated pairs of fresh instances (the punch is where the series starts)."""
    found = {"native": [], "python": []}
    for _ in range(repeat):
        for kind in found:
            found[kind].append(PunchInFmpy(fmus[kind]).steps(series))
    out = {}
    for kind, rows in found.items():
        out[f"{kind}_step"] = statistics.median(r[0] for r in rows) * 1e6
        out[f"{kind}_doStep"] = statistics.median(r[1] for r in rows) * 1e6
    return out


# --- 2. the native FMU's own cost ------------------------------------------------------------
def own_cost(fmu: Path, folder: Path, callgrind: bool) -> dict[str, float]:
    """ns per step of PunchContact's set, doStep, get in a C loop; instructions with valgrind."""
    source = ROOT / "bench" / "native" / "step_cost.c"
    program = folder / "step_cost"
    compiler = shutil.which("gcc") or shutil.which("cc")
    subprocess.run([compiler, "-std=c99", "-O2", f"-I{ROOT / 'native' / 'runtime' / 'fmi2'}",
                    str(source), "-o", str(program), "-ldl", "-lm"], check=True)
    unzipped = Path(extract(str(fmu), str(folder / "punch")))
    md = read_model_description(str(fmu))
    binary = unzipped / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    variables = {v.name: v for v in md.modelVariables}
    ins = ",".join(str(variables[n].valueReference) for n in ("xi", "xi_dot", "xi_ddot"))
    outs = ",".join(str(v.valueReference) for v in md.modelVariables
                    if v.causality == "output" and v.type == "Real")

    def run(n, *wrap):
        done = subprocess.run([*wrap, str(program), str(binary), md.guid, str(n), str(STEP),
                               ins, outs], capture_output=True, text=True, check=True)
        return done

    n = 200_000
    found = {"ns_per_step": statistics.median(float(run(n).stdout) for _ in range(5))}
    if callgrind and shutil.which("valgrind"):
        counts = []
        for steps in (2_000, 4_000):
            log = folder / f"callgrind.{steps}"
            run(steps, "valgrind", "--tool=callgrind", f"--callgrind-out-file={log}.out",
                f"--log-file={log}")
            text = Path(f"{log}").read_text()
            counts.append(int(re.search(r"Collected : (\d+)", text).group(1)))
        found["instructions_per_step"] = (counts[1] - counts[0]) / 2_000
    return found


# --- 3. and 4. runs and sweeps -----------------------------------------------------------------
def warm_run(kind: str, accuracy: bool) -> float:
    settings = {"experiment.fmus": kind}
    if not accuracy:
        settings["experiment.accuracy"] = "off"
    started = CLOCK()
    sewfmu.run("punch_drive", set=settings)
    return CLOCK() - started


def sweep(kind: str, points: int, workers: int) -> float:
    """Wall seconds (the workers are a pool that outlives the sweep: their CPU time is not
    a waited child's, so wall time it is, the median of alternated pairs)."""
    started = time.perf_counter()
    sewfmu.sweep("punch_drive", grid={"shaft.omega0": list(np.linspace(80.0, 120.0, points))},
                 set={"experiment.fmus": kind}, workers=workers)
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--no-callgrind", action="store_true")
    parser.add_argument("--points", type=int, default=100)
    args = parser.parse_args()
    names = ["MainShaft", "PunchLinkage", "PunchContact"]
    fmus = {"python": ensure_built(names)["PunchContact"],
            "native": ensure_built(names, kind="native")["PunchContact"]}
    print(f"FMUs: {fmus['python']} and {fmus['native']}")
    series = slider_series()
    print(f"\n1. PunchContact's step through fmpy ({len(series)} steps of punch_drive's slider "
          f"motion, median of {args.repeat} alternated pairs, CPU µs per step)")
    punch = punch_step(fmus, series, args.repeat)
    for what, label in (("step", "set, doStep, get"), ("doStep", "doStep alone")):
        n, p = punch[f"native_{what}"], punch[f"python_{what}"]
        print(f"   {label:<18} native {n:8.2f}   python {p:8.2f}   python/native {p / n:6.1f}")
    floor = statistics.median(call_floor(fmus["native"]) for _ in range(args.repeat))
    print(f"   fmpy's ctypes call itself (a getReal of no values): {floor:.2f} µs, so through "
          f"fmpy doStep can be at most {punch['python_doStep'] / floor:.0f}× faster than the "
          f"Python FMU's;\n   without it: native {punch['native_doStep'] - floor:.2f}   python "
          f"{punch['python_doStep'] - floor:.2f}   python/native "
          f"{(punch['python_doStep'] - floor) / (punch['native_doStep'] - floor):6.1f}")
    with tempfile.TemporaryDirectory() as tmp:
        own = own_cost(fmus["native"], Path(tmp), not args.no_callgrind)
    print(f"\n2. the native PunchContact's own step (set, doStep, get in a C loop): "
          f"{own['ns_per_step'] / 1e3:.3f} µs CPU"
          + (f", {own['instructions_per_step']:,.0f} instructions"
             if "instructions_per_step" in own else ""))
    print(f"\n3. warm sewfmu.run('punch_drive'), CPU s, median of {args.repeat} alternated pairs")
    for accuracy in (True, False):
        warm_run("native", accuracy), warm_run("python", accuracy)       # warm both
        n, p = _median_pairs(lambda a=accuracy: warm_run("native", a),
                             lambda a=accuracy: warm_run("python", a), args.repeat)
        label = "as by default" if accuracy else "estimate off"
        print(f"   {label:<14} native {n:.4f}   python {p:.4f}   python/native {p / n:5.1f}")
        if not accuracy:
            bare_native = n
    workers = 2
    sweep("native", 4, workers), sweep("python", 4, workers)             # build, warm
    n, p = _median_pairs(lambda: sweep("native", args.points, workers),
                         lambda: sweep("python", args.points, workers), max(1, args.repeat // 2))
    print(f"\n4. a {args.points}-point sweep of punch_drive ({workers} workers), wall s, "
          f"median of alternated pairs\n   native {n:.3f}   python {p:.3f}   python/native {p / n:5.1f}")
    steps = round(2 * np.pi * 10 / 100.0 / STEP)
    per_step = bare_native / steps * 1e6
    fmu_own = 3 * own["ns_per_step"] / 1e3     # an upper bound: the shaft and linkage cost less
    print(f"\n5. the master on native FMUs: {per_step:.2f} µs CPU per step of punch_drive "
          f"({steps} steps, estimate off, load and summary included); its three FMUs' own\n"
          f"   work at most {fmu_own:.2f} µs; the rest, {per_step - fmu_own:.2f} µs, is the "
          f"master: {(per_step - fmu_own) / 0.14:.0f}× a compiled FMU's 0.14 µs step")


if __name__ == "__main__":
    main()
