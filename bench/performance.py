"""sewfmu's speed, measured side by side in one run. Prints three tables:

1. punch_drive (default settings) as a whole process, `sewfmu run punch_drive`, against the whole
   process of the monolithic scipy solution of the same model (DOP853 with event location,
   rtol 1e-8, as a user of the paper's ode45 approach would run it); medians of alternating runs.
2. the master's cost per communication step and per FMU against a bare fmpy loop (setReal,
   doStep, getReal with value references resolved beforehand) on the same trivial FMUs.
3. time to accuracy: the error of F2_weld_mean and of the contact duration against the wall time
   as the communication step changes, Jacobi and Gauss–Seidel (also drawn: bench/time_to_accuracy.png).
4. the FMI 3.0 FMUs against the FMI 2.0 ones: the same runs (same numbers), wall time of the run.

    .venv/bin/python bench/performance.py [--repeat N]
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from sewfmu.components.registry import FMUS
from sewfmu.scenarios.cosim.master import run
from sewfmu.scenarios.fmu_build.up_to_date import ensure_built
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.format.scenario import Connection, Instance, Scenario
from sewfmu.scenarios.runs.compare import monolithic_summary
from sewfmu.scenarios.runs.runner import simulate, summarize

HERE = Path(__file__).resolve().parent
MONOLITHIC = """
import math
from sewfmu.scenarios.mechanisms import punch
t_end = 10 * 2 * math.pi / 100.0
ref = punch.solve({"omega0": 100.0}, {}, {}, t_end, sample_step=2.5e-4,
                            sample_from=t_end - 2.2 * math.pi / 100.0, rtol=1e-8, atol=1e-11)
print(punch.summary_of_monolithic(ref))
"""


def _wall(cmd) -> float:
    start = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    return time.perf_counter() - start


def whole_process(repeat: int) -> None:
    ensure_built(sorted(FMUS))                       # built once, outside the timing
    out = tempfile.mkdtemp(prefix="sewfmu_bench_")
    cosim = [sys.executable, "-m", "sewfmu", "run", "punch_drive", "--out", out]
    mono = [sys.executable, "-c", MONOLITHIC]
    _wall(cosim), _wall(mono)                        # warm the file cache
    t_cosim, t_mono = [], []
    for _ in range(repeat):                          # alternate, so that load drifts hit both
        t_cosim.append(_wall(cosim))
        t_mono.append(_wall(mono))
    a, b = statistics.median(t_cosim), statistics.median(t_mono)
    fig = summarize(simulate(load("punch_drive")))
    ref, _ = monolithic_summary(load("punch_drive"))
    print("1. punch_drive, whole process (median of", repeat, "alternating runs)")
    print("| process | wall [s] |\n|---|---|")
    print(f"| sewfmu run punch_drive (co-simulation, 3 FMUs, step 2.5e-4 s) | {a:.3f} |")
    print(f"| monolithic scipy DOP853 rtol 1e-8 with event location | {b:.3f} |")
    print(f"ratio co-simulation / monolithic: **{a / b:.2f}** (goal <= 0.5)")
    worst_angle = max(abs(fig[k] - ref[k]) for k in ("contact_onset_deg", "contact_loss_deg",
                                                      "contact_duration_deg"))
    worst_force = max(abs(fig[k] - ref[k]) for k in ("F2_peak", "F2_weld_mean"))
    print(f"accuracy at these settings: {worst_angle:.3f}° and {worst_force:.4f} N from the "
          f"reference (required: 0.75° and 0.15 N)\n")


# --- 2. master overhead on trivial FMUs ---------------------------------------------------------
TRIVIAL = '''
import ctypes

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class Trivial(Fmi2Slave):
    """One input copied to one output: the cheapest possible FMU."""

    def __init__(self, **kwargs):
        # pythonfmu 0.7.0 releases one reference to this namespace per instance: take it back
        ctypes.pythonapi.Py_IncRef(ctypes.py_object(globals()))
        super().__init__(**kwargs)
        self.u = 0.0
        self.y = 0.0
        self.register_variable(Real("u", causality=Fmi2Causality.input,
                                    variability=Fmi2Variability.continuous, start=0.0))
        self.register_variable(Real("y", causality=Fmi2Causality.output,
                                    variability=Fmi2Variability.continuous))

    def do_step(self, t, h):
        self.y = self.u + 1.0
        return True
'''


def _trivial_fmu(folder: Path) -> Path:
    from pythonfmu.builder import FmuBuilder
    script = folder / "Trivial.py"
    script.write_text(TRIVIAL)
    return Path(FmuBuilder.build_FMU(script, dest=folder))


def _bare_loop(path: Path, n_fmus: int, steps: int) -> float:
    """setReal, doStep, getReal per FMU per step through fmpy, references resolved once."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    md = read_model_description(str(path))
    unzip = extract(str(path))
    fmus = []
    for k in range(n_fmus):
        f = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier="Trivial",
                      instanceName=f"t{k}")
        f.instantiate()
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        f.exitInitializationMode()
        fmus.append(f)
    vr_u, vr_y = [0], [1]
    values = [0.0] * n_fmus
    start = time.perf_counter()
    for s in range(steps):
        t = s * 1e-3
        for k, f in enumerate(fmus):
            f.setReal(vr_u, [values[k - 1]])
            f.doStep(t, 1e-3)
            values[k] = f.getReal(vr_y)[0]
    return (time.perf_counter() - start) / steps / n_fmus


def _master_loop(path: Path, n_fmus: int, steps: int) -> float:
    names = [f"t{k}" for k in range(n_fmus)]
    sc = Scenario(name="trivial_chain", source="bench", description="", analysis=None,
                  instances={n: Instance(n, "Trivial") for n in names},
                  connections=[Connection(names[k - 1], "y", names[k], "u")
                               for k in range(1, n_fmus)],
                  record=None, step=1e-3, master="jacobi", stop_time=steps * 1e-3,
                  revolutions=None, shaft=None, compare=None)
    run(sc, {"Trivial": path})                       # warm up: extraction, imports
    start = time.perf_counter()
    result = run(sc, {"Trivial": path})
    elapsed = time.perf_counter() - start
    assert result["t1.y"][-1] == 2.0                 # the chain worked: t0.y = 1, t1.y = 2
    return elapsed / steps / n_fmus


def master_overhead(steps: int = 20000, n_fmus: int = 3) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = _trivial_fmu(Path(tmp))
        bare = _bare_loop(path, n_fmus, steps)
        master = _master_loop(path, n_fmus, steps)
    print(f"2. cost per communication step and per FMU, {n_fmus} trivial FMUs in a chain, "
          f"{steps} steps")
    print("| loop | µs per step per FMU |\n|---|---|")
    print(f"| bare fmpy loop (setReal, doStep, getReal) | {bare * 1e6:.1f} |")
    print(f"| sewfmu master (Jacobi, with recording) | {master * 1e6:.1f} |")
    print(f"ratio master / bare loop: **{master / bare:.2f}** (goal <= 1.3)\n")


# --- 3. time to accuracy ----------------------------------------------------------------------
STEPS = (2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4)


def time_to_accuracy() -> None:
    ref, _ = monolithic_summary(load("punch_drive"))
    rows = []
    print("3. time to accuracy, punch_drive (10 revolutions), against the reference")
    print("| master | step [s] | wall [s] | error F2_weld_mean [N] | error contact duration [°] |")
    print("|---|---|---|---|---|")
    for master in ("jacobi", "gauss-seidel"):
        for h in STEPS:
            sc = load("punch_drive")
            sc.step, sc.master = h, master
            result = simulate(sc)
            fig = summarize(result)
            e_f = abs(fig["F2_weld_mean"] - ref["F2_weld_mean"])
            e_d = abs(fig["contact_duration_deg"] - ref["contact_duration_deg"])
            rows.append((master, h, result.wall_time, e_f, e_d))
            print(f"| {master} | {h:g} | {result.wall_time:.3f} | {e_f:.2e} | {e_d:.2e} |")
    _plot(rows)


def _plot(rows) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for master, marker in (("jacobi", "o-"), ("gauss-seidel", "x--")):
        sel = [r for r in rows if r[0] == master]
        for ax, col, label in ((axes[0], 3, "F2_weld_mean [N]"), (axes[1], 4, "contact duration [°]")):
            ax.loglog([r[2] for r in sel], [r[col] for r in sel], marker, label=master)
            ax.set(xlabel="wall time [s]", ylabel=f"error of {label}")
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
        ax.legend()
    fig.suptitle("punch_drive: error against wall time (steps 2e-3 … 1e-4 s)")
    fig.tight_layout()
    fig.savefig(HERE / "time_to_accuracy.png", dpi=100)
    plt.close(fig)


def fmi_versions(repeat: int) -> None:
    """The same scenarios with the FMI 2.0 and the FMI 3.0 FMUs, alternating; medians."""
    print("4. FMI 2.0 against FMI 3.0 FMUs (same model code, same numbers), wall time of the run")
    print("| scenario | FMI 2.0 [s] | FMI 3.0 [s] | ratio 3.0 / 2.0 |\n|---|---|---|---|")
    for name in ("punch_drive", "punch_split"):
        runs = {2: [], 3: []}
        for fmi in (2, 3):                           # built and loaded outside the timing
            scenario = load(name)
            scenario.set_value("experiment.fmi", fmi)
            simulate(scenario)
        for _ in range(repeat):
            for fmi in (2, 3):
                scenario = load(name)
                scenario.set_value("experiment.fmi", fmi)
                runs[fmi].append(simulate(scenario).wall_time)
        a, b = statistics.median(runs[2]), statistics.median(runs[3])
        print(f"| {name} | {a:.3f} | {b:.3f} | {b / a:.2f} |")
    print()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    whole_process(args.repeat)
    master_overhead()
    time_to_accuracy()
    fmi_versions(args.repeat)


if __name__ == "__main__":
    main()
