"""10⁶ communication steps of punch_drive in one run, with the resident memory size sampled every
10⁵ steps: it must stay flat (no growth per step).

    .venv/bin/python bench/long_run.py [--steps N]
"""
import argparse
import time
from pathlib import Path

from sewfmu.scenarios.cosim.master import Master
from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
from sewfmu.scenarios.format.loader import load


def rss_mib() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    raise RuntimeError("no VmRSS in /proc/self/status")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=1_000_000)
    args = parser.parse_args()
    sc = load("punch_drive")
    # enough revolutions for the steps; one recorded row per 1000 steps
    sc.set_value("experiment.revolutions", args.steps * sc.step * 100.0 / (2 * 3.141592653589793) + 1)
    sc.set_value("experiment.record_every", 1000)
    paths = fmus_for(sc)
    print("| steps | resident size [MiB] | wall [s] |\n|---|---|---|")
    start = time.perf_counter()
    with Master(sc, paths) as master:
        print(f"| 0 | {rss_mib():.1f} | 0 |")
        for k in range(1, args.steps + 1):
            master.step()
            if k % (args.steps // 10) == 0:
                print(f"| {k} | {rss_mib():.1f} | {time.perf_counter() - start:.0f} |", flush=True)


if __name__ == "__main__":
    main()
