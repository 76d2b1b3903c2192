"""Error of punch_drive against the monolithic solution, and wall time, per communication step.

    .venv/bin/python bench/punch_step_table.py [--master jacobi|gauss-seidel]

Prints, for each step h: the differences of the key figures from the reference (DOP853,
rtol 1e-10, switches located as events), the largest deviation of the punch height y at the
communication points, and the co-simulation's wall time beside the reference's.
"""
import argparse

import numpy as np

from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.mechanisms import punch
from sewfmu.scenarios.runs.compare import monolithic_summary
from sewfmu.scenarios.runs.runner import simulate, summarize

STEPS = (1e-3, 5e-4, 2.5e-4, 1e-4, 5e-5)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--master", default="jacobi")
    args = parser.parse_args()
    base = load("punch_drive")
    ref, ref_wall = monolithic_summary(base)
    t_end = base.end_time()
    print(f"punch_drive, {base.revolutions:g} revolutions, master {args.master}; reference "
          f"{ref_wall:.2f} s wall")
    print("| step [s] | onset [°] | loss [°] | duration [°] | F2_peak [N] | F2_weld_mean [N] "
          "| max abs(y - y_ref) [m] | wall [s] |")
    print("|---|---|---|---|---|---|---|---|")
    for h in STEPS:
        sc = load("punch_drive")
        sc.step, sc.master = h, args.master
        result = simulate(sc)
        fig = summarize(result)
        dense = punch.solve({"omega0": 100.0}, {}, {}, t_end, sample_step=h,
                                      sample_switches=False)
        n = len(result.time) - 1
        dy = np.max(np.abs(result["punch.y"][:n] - dense.y[:n]))
        d = {k: fig[k] - ref[k] for k in ("contact_onset_deg", "contact_loss_deg",
                                          "contact_duration_deg", "F2_peak", "F2_weld_mean")}
        print(f"| {h:g} | {d['contact_onset_deg']:+.4f} | {d['contact_loss_deg']:+.4f} | "
              f"{d['contact_duration_deg']:+.4f} | {d['F2_peak']:+.4f} | "
              f"{d['F2_weld_mean']:+.5f} | {dy:.2e} | {result.wall_time:.2f} |")


if __name__ == "__main__":
    main()
