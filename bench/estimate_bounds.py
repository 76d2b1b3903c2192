"""The printed ± of every run against its true error: the tables of docs/running.md that show the
bound holding, and the scans that set scenarios/runs/accuracy.py's SAFETY and ORDER.

    .venv/bin/python bench/estimate_bounds.py           # the table of runs (a few minutes)
    .venv/bin/python bench/estimate_bounds.py --scan    # also the scans (a quarter of an hour)
    .venv/bin/python bench/estimate_bounds.py --check   # compute the table, compare, change nothing

Each run is `sewfmu.run` with accept_error (its ± as the console prints it); its true error is
against a converged run of the same physics: the punch's monolithic solution (DOP853, rtol 1e-10,
switches as events), the same for punch_split; the carriage co-simulated at 1e-5 s (its
last-stitch peak 0.008 µm from the continuous solution of tests/independent/carriage.py). It
rewrites docs/running.md's blocks `<!-- figures: estimate-table-punch -->`, `-carriage`, and with
--scan `estimate-scan` and `estimate-noise`, each up to its `<!-- /figures -->` (docs/tools/doc_figures.py
writes the page's other blocks and leaves these alone). A row of the table whose ± falls below
its true error is printed and the script exits 1: the factor must be measured again.

The scan (--scan) runs every step of each configuration, 8 to an octave, from where the error
is tiny to where the coupling breaks down, accepted or not; for each figure it fits the order of
the error against the step (the tolerance) and finds the smallest ± / true error: where it falls
below 1 the bound falls short. Then 40 runs of punch_split's adaptive master at one tolerance,
each changed by a millionth, show how often the bound falls short where the figures are chaotic
in the tolerance. scenarios/runs/accuracy.py's docstring says how SAFETY and ORDER follow.
"""
from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import re
import sys
from pathlib import Path

import numpy as np

import sewfmu
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.runs import accuracy
from sewfmu.scenarios.runs.compare import monolithic_summary
from sewfmu.scenarios.runs.runner import simulate, summarize

REPO = Path(__file__).resolve().parent.parent
PAGE = REPO / "docs" / "running.md"
MARKER = re.compile(r"<!-- figures: (estimate-[\w-]+) -->(.*?)<!-- /figures -->", re.S)
PUNCH = {"contact_onset_deg": "onset [°]", "contact_loss_deg": "loss [°]",
         "contact_duration_deg": "duration [°]", "F2_peak": "F2_peak [N]",
         "F2_weld_mean": "F2_weld_mean [N]"}
CARRIAGE = {"peak_abs_U2_last_stitch_um": "last stitch's peak \\|U2\\| [µm]",
            "peak_abs_U2_um": "peak \\|U2\\| [µm]"}
CARRIAGE_REFERENCE_STEP = 1e-5
ACCURACY = 0.05                     # experiment.accuracy's default: which runs are accepted


class Config:
    """A scenario under one master: `settings` the --set values besides the step or tolerance,
    `swept` experiment.step or experiment.tolerance."""

    def __init__(self, scenario: str, master: str, swept: str = "experiment.step", **settings):
        self.scenario, self.master, self.swept = scenario, master, swept
        self.settings = {"experiment.master": master,
                         **{f"experiment.{k}": v for k, v in settings.items()}}

    @property
    def label(self) -> str:
        extra = "/".join(str(v) for k, v in self.settings.items() if k != "experiment.master")
        return f"{self.scenario}, {self.master}" + (f" ({extra})" if extra else "")

    def figures(self) -> dict:
        return CARRIAGE if self.scenario.startswith("carriage") else PUNCH


CARRIAGE_JACOBI = Config("carriage_startstop", "jacobi")
DRIVE = {m: Config("punch_drive", m) for m in ("jacobi", "gauss-seidel", "iterative")}
DRIVE_ADAPTIVE = Config("punch_drive", "adaptive", "experiment.tolerance")
SPLIT = {"jacobi": Config("punch_split", "jacobi"),
         "iterative": Config("punch_split", "iterative", acceleration="aitken"),
         "iqn-ils": Config("punch_split", "iterative", acceleration="iqn-ils")}
SPLIT_ADAPTIVE = Config("punch_split", "adaptive", "experiment.tolerance")

# the table of docs/running.md: (configuration, values of its swept key)
TABLE = [(CARRIAGE_JACOBI, (5e-4, 1e-3, 2e-3)),
         (DRIVE["jacobi"], (1e-4, 2.5e-4, 5e-4, 1e-3)),
         (DRIVE["gauss-seidel"], (2.5e-4, 1e-3)),
         (DRIVE["iterative"], (2.5e-4, 1e-3)),
         (DRIVE_ADAPTIVE, (1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3)),
         (SPLIT["jacobi"], (1e-4, 2.5e-4, 5e-4, 1e-3)),
         (SPLIT["iterative"], (2.5e-4, 1e-3, 2e-3)),
         (SPLIT["iqn-ils"], (1e-3,)),
         (SPLIT_ADAPTIVE, (1e-4, 1e-3, 3e-3, 5e-3))]
# the scans: (configuration, lowest, highest value), 8 values an octave
SCANS = [(CARRIAGE_JACOBI, 6.25e-5, 4e-3),
         (DRIVE["jacobi"], 3.125e-5, 2e-3),
         (DRIVE["gauss-seidel"], 6.25e-5, 2e-3),
         (DRIVE["iterative"], 6.25e-5, 2e-3),
         (DRIVE_ADAPTIVE, 1.25e-5, 5e-3),
         (SPLIT["jacobi"], 3.125e-5, 1.4e-3),
         (SPLIT["iterative"], 3.125e-5, 4e-3),
         (SPLIT_ADAPTIVE, 1.25e-5, 5e-3)]


# --- one run and its truth ------------------------------------------------------------------
class Truth:
    """The converged figures of each scenario, computed once."""

    def __init__(self):
        self._found: dict[str, dict] = {}

    def __call__(self, scenario: str) -> dict:
        if scenario not in self._found:
            if scenario.startswith("carriage"):
                sc = load(scenario)
                sc.set_value("experiment.step", CARRIAGE_REFERENCE_STEP)
                self._found[scenario] = summarize(simulate(sc))
            else:                     # punch_split is punch_drive cut at the fabric
                self._found[scenario] = monolithic_summary(load("punch_drive"))[0]
        return self._found[scenario]


def measure(config: Config, value: float, truth: Truth) -> dict:
    """One run as `sewfmu run` makes it: {"±": {figure: bound}, "untrusted", "failed", "true":
    {figure: |error|}, "accepted": within ACCURACY, "diverged": the run itself}."""
    given = {**config.settings, config.swept: value, "experiment.accept_error": True}
    try:
        run = sewfmu.run(config.scenario, set=given)
    except sewfmu.Diverged:
        return {"diverged": True}
    found = run.summary["coupling_error"]
    exact = truth(config.scenario)
    return {"±": found.get("figures", {}), "untrusted": found.get("untrusted", {}),
            "failed": found.get("failed") or found.get("none"),
            "true": {k: abs(run.summary[k] - exact[k]) for k in config.figures()},
            "accepted": not accuracy.beyond(run.summary, ACCURACY), "diverged": False}


def broken(row: dict) -> list[str]:
    """The figures whose printed ± lies below the true error."""
    return [k for k, bound in row.get("±", {}).items()
            if k in row["true"] and bound < row["true"][k]]


# --- the table ------------------------------------------------------------------------------
def value_text(config: Config, value: float) -> str:
    return f"{value * 1e3:g} ms" if config.swept == "experiment.step" else f"tol {value:g}"


def cell(row: dict, key: str) -> str:
    if row.get("diverged"):
        return "diverged"
    true = g2(row["true"][key])
    if key in row["±"]:
        return f"{g2(row['±'][key])} / {true}"
    return f"none / {true}"


def g2(x: float) -> str:
    return f"{x:.2g}"


def verdict(row: dict) -> str:
    if row.get("diverged"):
        return "the run diverges"
    if row["failed"]:           # its first words: what failed ("the run at twice the step ...")
        return "no ± (" + row["failed"].split(":")[0] + ")"
    if row["untrusted"]:
        return f"no ± for {', '.join(row['untrusted'])}"
    return "accepted" if row["accepted"] else "beyond 5 %"


def table(truth: Truth, failures: list[str]) -> dict[str, str]:
    """The two blocks of the table (punch, carriage): markdown, each row printed as computed."""
    out = {}
    for name, figures in (("estimate-table-carriage", CARRIAGE), ("estimate-table-punch", PUNCH)):
        lines = ["", "| configuration | step or tolerance | " + " | ".join(figures.values())
                 + " | at experiment.accuracy 5 % |",
                 "|---|---|" + "---|" * len(figures) + "---|"]
        for config, values in TABLE:
            if config.figures() is not figures:
                continue
            for value in values:
                row = measure(config, value, truth)
                print(f"{config.label:40s} {value_text(config, value):12s} "
                      + "  ".join(cell(row, k) for k in figures) + f"  {verdict(row)}", flush=True)
                if not row.get("diverged"):
                    failures += [f"{config.label} at {value_text(config, value)}: {k} ± "
                                 f"{row['±'][k]:.3g} below its true error {row['true'][k]:.3g}"
                                 for k in broken(row)]
                lines.append(f"| {config.label} | {value_text(config, value)} | "
                             + " | ".join(cell(row, k) for k in figures) + f" | {verdict(row)} |")
        lines += ["", f"*± / true error, by `bench/estimate_bounds.py`, {machine()}.*", ""]
        out[name] = "\n".join(lines)
    return out


# --- the scans ------------------------------------------------------------------------------
def scan(truth: Truth) -> str:
    """The block of the scans: per configuration and figure, the order of its error against the
    step (tolerance) and the smallest ± / true error, among the runs accepted at 5 % and among
    all; below 1 the bound falls short."""
    lines = ["", "| configuration | range | figure | order of the error | smallest ± / true error, "
             "accepted runs | the same, every run |", "|---|---|---|---|---|---|"]
    tightest = (math.inf, "")
    for config, low, high in SCANS:
        values = [low * 2 ** (k / 8) for k in range(int(8 * math.log2(high / low) + 1e-9) + 1)]
        rows = [(v, measure(config, v, truth)) for v in values]
        print(f"{config.label}: {len(rows)} runs", flush=True)
        for key in config.figures():
            errors = [(v, r["true"][key]) for v, r in rows
                      if not r.get("diverged") and r["true"][key] > 0]
            order = np.polyfit(np.log([v for v, _ in errors]), np.log([e for _, e in errors]), 1)[0]
            least = {"accepted": (math.inf, None), "all": (math.inf, None)}
            for v, r in rows:
                if r.get("diverged") or key not in r["±"] or r["true"][key] == 0:
                    continue
                ratio = r["±"][key] / r["true"][key]
                for which in ("all", "accepted") if r["accepted"] else ("all",):
                    if ratio < least[which][0]:
                        least[which] = (ratio, v)
            if least["accepted"][0] < tightest[0]:
                tightest = (least["accepted"][0], f"{config.label}, {key}, "
                                                  f"{value_text(config, least['accepted'][1])}")
            lines.append(f"| {config.label} | {value_text(config, low)} to "
                         f"{value_text(config, high)} | {key} | {order:.2f} | "
                         + " | ".join(f"{least[w][0]:.2f} at {value_text(config, least[w][1])}"
                                      if least[w][1] is not None else "–"
                                      for w in ("accepted", "all")) + " |")
    lines += ["", f"*The tightest accepted run: ± {tightest[0]:.2f} times its error ({tightest[1]}); "
              f"SAFETY = {accuracy.SAFETY:g}, SAMPLING = {accuracy.SAMPLING:g}, ORDER = "
              f"{accuracy.ORDER}. By `bench/estimate_bounds.py --scan`, {machine()}.*", ""]
    print(f"tightest accepted run: {tightest[0]:.2f} ({tightest[1]})")
    return "\n".join(lines)


# the adaptive master's figures are chaotic in its tolerance (a change of 1e-16 moves
# punch_split's contact onset by 0.001°): runs at one tolerance changed by a millionth apiece
NOISE = (SPLIT_ADAPTIVE, 4e-4, 40)


def noise(truth: Truth) -> str:
    """The block of the perturbed runs: how often, and by how much, the ± fell short."""
    config, value, count = NOISE
    rows = [measure(config, value * (1 + k * 1e-6), truth) for k in range(count)]
    lines = ["", f"| {config.label}, tolerance {value:g} × (1 + k·10⁻⁶), k < {count} | smallest "
             "± / true error | runs whose ± falls short |", "|---|---|---|"]
    for key in config.figures():
        ratios = [r["±"][key] / r["true"][key] for r in rows if key in r["±"] and r["true"][key]]
        lines.append(f"| {key} | {min(ratios):.2f} | {sum(x < 1 for x in ratios)} of "
                     f"{len(ratios)} |")
    lines += ["", f"*By `bench/estimate_bounds.py --scan`, {machine()}.*", ""]
    return "\n".join(lines)


def machine() -> str:
    return (f"{datetime.date.today().isoformat()} on {platform.system()} {platform.machine()}, "
            f"{os.cpu_count()} CPUs, Python {platform.python_version()}")


def rewrite(blocks: dict[str, str]) -> None:
    text = PAGE.read_text(encoding="utf-8")
    found = {m.group(1): m for m in MARKER.finditer(text)}
    for name, body in blocks.items():
        if name not in found:
            raise SystemExit(f"{PAGE}: no block <!-- figures: {name} --> to write into")
        text = text.replace(found[name].group(0), f"<!-- figures: {name} -->{body}<!-- /figures -->")
    PAGE.write_text(text, encoding="utf-8")


def stripped(body: str) -> str:
    """A block without its stamp line (the date moves; the numbers must not)."""
    return "\n".join(line for line in body.splitlines() if not line.startswith("*"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scan", action="store_true", help="also the scans behind SAFETY")
    parser.add_argument("--check", action="store_true", help="compare the table, change nothing")
    args = parser.parse_args()
    truth, failures = Truth(), []
    blocks = table(truth, failures)
    if args.scan:
        blocks["estimate-scan"] = scan(truth)
        blocks["estimate-noise"] = noise(truth)
    for line in failures:
        print(f"BROKEN: {line}")
    if args.check:
        found = {m.group(1): m.group(2) for m in MARKER.finditer(PAGE.read_text(encoding="utf-8"))}
        stale = [n for n, b in blocks.items() if stripped(found.get(n, "")) != stripped(b)]
        print("\n".join(f"{PAGE.name}: block {n} differs from the computed one" for n in stale)
              or "the page's tables hold")
        sys.exit(1 if stale or failures else 0)
    rewrite(blocks)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
