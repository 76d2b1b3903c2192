"""Error of every summary figure against a tight monolithic solution, against wall time: the
masters on punch_drive (one-way) and punch_split (two-way, across the fabric) at several steps or
tolerances, beside the monolithic solver at several tolerances; and the stability limit of plain
Jacobi on punch_split.

    .venv/bin/python bench/coupling.py [--plot docs/coupling_accuracy.png]

Wall times are the co-simulation's run (FMUs loaded, initialized, stepped, freed; the first run
of each scenario is repeated so that no run pays for extracting the FMUs) and the monolithic
solve, measured in this one process.
"""
import argparse
import math

import numpy as np

from sewfmu.scenarios.cosim.divergence import Diverged
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.runs.compare import monolithic_summary
from sewfmu.scenarios.runs.runner import simulate, summarize

FIGURES = ("contact_onset_deg", "contact_loss_deg", "F2_peak", "F2_weld_mean")
RUNS = [("punch_drive", "jacobi", h) for h in (1e-3, 5e-4, 2.5e-4, 1e-4)] + \
       [("punch_drive", "gauss-seidel", h) for h in (5e-4, 2.5e-4)] + \
       [("punch_split", "jacobi", h) for h in (1e-3, 5e-4, 2.5e-4, 1e-4)] + \
       [("punch_split", f"iterative/{acc}", h) for acc in ("aitken", "iqn-ils")
        for h in (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4)] + \
       [("punch_split", "iterative/none", h) for h in (1e-3, 2.5e-4)] + \
       [("punch_drive", f"adaptive/{tol:g}", 2.5e-4) for tol in (1e-4, 1e-5, 1e-6)] + \
       [("punch_split", f"adaptive/{tol:g}", 2.5e-4) for tol in (1e-2, 3e-3, 1e-3, 1e-4)]
RTOLS = (1e-3, 1e-4, 1e-5, 1e-6)


def run(name: str, master: str, h: float):
    sc = load(name)
    sc.master, _, option = master.partition("/")
    if option and sc.master == "adaptive":
        sc.tolerance = float(option)
    elif option:
        sc.acceleration = option
    sc.step = h
    result = simulate(sc)
    return summarize(result), result


def errors(figures: dict, tight: dict) -> dict:
    return {k: abs(figures[k] - tight[k]) for k in FIGURES}


def stable(h: float) -> bool:
    """Whether plain Jacobi on punch_split stays bounded at step h (F2 below 1 kN). The master
    stops a diverging coupling with Diverged (a value left its declared range or grew without
    bound): that run is unstable. Any other error (a CosimError: an FMU failed) says nothing
    about stability and stops the bench."""
    try:
        _, result = run("punch_split", "jacobi", h)
    except Diverged:
        return False
    return bool(np.all(np.isfinite(result["fabric.F2"])) and result["fabric.F2"].max() < 1e3)


def step_of(h: float) -> float:
    """The step a run asked for h takes: whole, even steps to its end (end / n, not above h)."""
    sc = load("punch_split")
    sc.step = h
    return sc.even_steps()[1]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--plot", help="write the error-against-wall-time plot here")
    args = parser.parse_args()
    tight, _ = monolithic_summary(load("punch_drive"))
    for name in ("punch_drive", "punch_split"):        # extract and load the FMUs once
        run(name, "jacobi", 1e-3)
    rows = []
    for name, master, h in RUNS:
        figures, result = run(name, master, h)
        extra = ""
        if "iterations_per_step" in result.coupling:
            extra = (f"{result.coupling['iterations_per_step']:.2f} passes/step, "
                     f"{result.coupling['unconverged_steps']} unconverged")
        elif result.coupling:
            extra = (f"{result.coupling['steps']} steps, "
                     f"{result.coupling['rejected_steps']} rejected")
        rows.append((name, master, f"{h:g}", result.wall_time, errors(figures, tight), extra))
    for rtol in RTOLS:
        figures, wall = monolithic_summary(load("punch_drive"), rtol)
        rows.append(("monolithic", f"DOP853 rtol {rtol:g}", "", wall, errors(figures, tight), ""))
    print("errors against the monolithic solution at rtol 1e-10 (10 revolutions, ω = 100 s⁻¹)")
    print("| scenario | master | step [s] | wall [s] | onset [°] | loss [°] | F2_peak [N] "
          "| F2_weld_mean [N] | coupling |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, master, h, wall, err, extra in rows:
        print(f"| {name} | {master} | {h} | {wall:.3f} | " + " | ".join(
            f"{err[k]:.2g}" if math.isfinite(err[k]) and err[k] < 1e6 else "diverged"
            for k in FIGURES) + f" | {extra} |")
    print("\ntargets (medians of 5 alternating runs):")
    walls = {key: [] for key in ("drive", "split", "adaptive")}
    for _ in range(5):
        walls["drive"].append(run("punch_drive", "jacobi", 2.5e-4)[1].wall_time)
        walls["split"].append(simulate(load("punch_split")).wall_time)       # its own master
        walls["adaptive"].append(run("punch_drive", "adaptive/1e-05", 2.5e-4)[1].wall_time)
    loose = [monolithic_summary(load("punch_drive"), 1e-4)[1] for _ in range(3)]
    median = {key: float(np.median(v)) for key, v in walls.items()}
    own = load("punch_split")
    split_errors = errors(summarize(simulate(own)), tight)
    print(f"- punch_split with its own master ({own.master}, tolerance "
          f"{own.settings().tolerance:g}): {median['split']:.3f} s, "
          f"{median['split'] / median['drive']:.2f} x punch_drive with jacobi "
          f"({median['drive']:.3f} s; goal <= 2); errors "
          + ", ".join(f"{k} {v:.2g}" for k, v in split_errors.items())
          + " (goals 0.1°, 0.01 N)")
    at300 = load("punch_split")
    at300.set_value("shaft.omega0", 300.0)
    tight300, _ = monolithic_summary(at300)
    print("- the same at ω = 300 s⁻¹: errors " + ", ".join(
        f"{k} {v:.2g}" for k, v in errors(summarize(simulate(at300)), tight300).items()))
    print(f"- punch_drive with the adaptive master (tolerance 1e-5): {median['adaptive']:.3f} s, "
          f"{median['adaptive'] / float(np.median(loose)):.2f} x the monolithic solver at rtol "
          f"1e-4 ({float(np.median(loose)):.3f} s); goal <= 1")
    lo, hi = 1e-3, 4e-3
    while hi - lo > 2e-5:                # bisection on the stability of plain Jacobi
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    print(f"\nplain Jacobi on punch_split is stable up to a step of {lo * 1e3:.2f} ms and diverges "
          f"from {hi * 1e3:.2f} ms, the steps asked for; the runs' whole, even steps "
          f"{step_of(lo) * 1e3:.3f} ms and {step_of(hi) * 1e3:.3f} ms (2·m/b2 = "
          f"{2 * 0.063 / 97.64 * 1e3:.2f} ms)")
    if args.plot:
        plot(rows, args.plot)


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    series = {}
    for name, master, _, wall, err, _ in rows:
        series.setdefault(f"{name}, {master}" if name != "monolithic" else "monolithic DOP853",
                          []).append((wall, err))
    for k, (label, points) in enumerate(sorted(series.items())):
        points = [(w, e) for w, e in points if all(math.isfinite(v) and v < 1e6
                                                   for v in e.values())]
        if not points:
            continue
        walls = [w for w, _ in points]
        for ax, figure in zip(axes, ("F2_weld_mean", "contact_onset_deg")):
            ax.loglog(walls, [max(e[figure], 1e-7) for _, e in points], "o-", ms=4,
                      label=label, color=f"C{k}")
    for ax, (figure, unit) in zip(axes, (("F2_weld_mean", "N"), ("contact_onset_deg", "°"))):
        ax.set(xlabel="wall time [s]", ylabel=f"|error of {figure}| [{unit}]")
        ax.grid(alpha=0.3, which="both")
    axes[0].legend(fontsize=7)
    fig.suptitle("Error against a tight monolithic solution, against wall time "
                 "(punch drive, 10 revolutions)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)


if __name__ == "__main__":
    main()
