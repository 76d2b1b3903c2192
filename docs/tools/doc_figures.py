"""Every accuracy figure that README.md and docs/ quote, computed from the code and written into
them, so that a quoted figure cannot go stale unnoticed (tests/docs/test_doc_figures.py recomputes them).

    .venv/bin/python docs/tools/doc_figures.py            # compute, rewrite the figures in the docs
    .venv/bin/python docs/tools/doc_figures.py --check    # compute, compare, change nothing
    .venv/bin/python docs/tools/doc_figures.py --timings  # also measure the wall times again

The docs hold the figures between markers, a table or a piece of prose:

    <!-- figures: NAME -->…<!-- /figures -->

BLOCKS below gives each block's text as a template: literal text and fields in braces,
`{KIND KEYS FORMAT}`, a key being `figure@run` (RUNS says what each run is) and KEYS one key or
several separated by commas (the largest value counts). The kinds:

    fig      a measured figure, printed at FORMAT
    within   a measured figure quoted as a bound ("within 0.0034°"): rounded up at FORMAT
    bound    a promise a writer chose ("within 0.05°"): kept while it holds; broken, it is
             loosened to the figure rounded up to one digit, and said so
    verdict  a run that diverges ("diverges") or not ("stable")
    wall     a wall time: a measurement of a day, kept as written unless --timings
    stamp    the date and machine of the figures (`stamp figures`) or the timings
             (`stamp timings`)

The same template parses a block back (whitespace aside: prose may be rewrapped):
tests/docs/test_doc_figures.py recomputes the README's figures in the fast loop and every block in a
slow test; a block not in its template's layout is an error. Accuracy figures are deterministic on
one machine, timings are not: hence the two stamps, and wall times left alone by default.

A new figure: its run in RUNS (or a new kind of run: a class with `compute(figs) -> dict`), a
field in a template of BLOCKS, the markers in the page, then run this script. An inline block
must not begin a line (a line that starts with `<!--` would end the paragraph in Markdown).
"""
from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sewfmu.scenarios.cosim.divergence import Diverged
from sewfmu.scenarios.cosim.master import run
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.mechanisms import punch
from sewfmu.scenarios.runs.compare import monolithic_summary
from sewfmu.scenarios.runs.runner import simulate, summarize

REPO = Path(__file__).resolve().parents[2]
# the short names of the punch's key figures in the templates
PUNCH_FIGURES = {"onset": "contact_onset_deg", "loss": "contact_loss_deg",
                 "duration": "contact_duration_deg", "peak": "F2_peak", "weld": "F2_weld_mean"}
NAN = float("nan")


# --- the runs --------------------------------------------------------------------------------
@dataclass(frozen=True)
class Cosim:
    """A co-simulation against the tight monolithic solution at its speed. Figures: each of
    PUNCH_FIGURES as the absolute error and, prefixed d_, the signed difference; `diverged`;
    the master's `passes` and `unconverged` steps; `wall`; `y_err`, the largest deviation of the
    punch's height at the communication points (computed when asked: it costs a dense solve)."""
    scenario: str
    master: str | None = None         # None: the scenario's own
    step: float | None = None         # None: the scenario's own
    option: str | None = None         # the adaptive tolerance or the iterative acceleration
    omega: float | None = None        # shaft speed; None: the scenario's (100 s⁻¹)

    def load(self):
        sc = load(self.scenario)
        sc.master = self.master or sc.master
        if self.option and sc.master == "adaptive":
            sc.tolerance = float(self.option)
        elif self.option:
            sc.acceleration = self.option
        if self.step:
            sc.step = self.step
        if self.omega:
            sc.set_value("shaft.omega0", self.omega)
        return sc

    def compute(self, figs: Figures) -> dict:
        sc = self.load()
        try:
            result = figs.run(sc)
        except Diverged:                  # the master's own verdict: the coupling is unstable
            return {"diverged": True} | {k: NAN for k in ("wall", "passes", "unconverged", "y_err")} \
                | {k: NAN for s in PUNCH_FIGURES for k in (s, f"d_{s}")}
        out = {"diverged": unbounded(result), "wall": result.wall_time,
               "passes": result.coupling.get("iterations_per_step", NAN),
               "unconverged": result.coupling.get("unconverged_steps", NAN),
               "y_err": lambda: trajectory_error(sc, result)}
        summary, tight = summarize(result), figs.tight(self.omega or 100.0)
        for short, key in PUNCH_FIGURES.items():
            out[f"d_{short}"] = summary[key] - tight[key]
            out[short] = abs(out[f"d_{short}"])
        return out


@dataclass(frozen=True)
class Monolithic:
    """The monolithic solver at a looser tolerance (`sewfmu compare --rtol`), against the tight."""
    rtol: float

    def compute(self, figs: Figures) -> dict:
        summary, wall = monolithic_summary(load("punch_drive"), self.rtol)
        tight = figs.tight(100.0)
        return {"wall": wall} | {s: abs(summary[k] - tight[k]) for s, k in PUNCH_FIGURES.items()}


@dataclass(frozen=True)
class Script:
    """bench/speed.py's plain scipy script (rtol 1e-4, sampled where the figures are read)."""
    rtol: float

    def compute(self, figs: Figures) -> dict:
        t_end = 10 * 2 * math.pi / 100.0
        solution = punch.solve({}, {}, {}, t_end, sample_step=2.5e-4,
                                          sample_from=t_end - 2.2 * math.pi / 100.0,
                                          rtol=self.rtol, atol=self.rtol * 1e-3)
        summary, tight = punch.summary_of_monolithic(solution), figs.tight(100.0)
        return {s: abs(summary[k] - tight[k]) for s, k in PUNCH_FIGURES.items()}


@dataclass(frozen=True)
class StabilityLimit:
    """Plain Jacobi on punch_split: the longest step that stays bounded (`stable_ms`) and the
    shortest that diverges (`diverges_ms`), in ms. A run is whole, even steps (end / n), so the
    bisection is on n: exact, where one on the step asked for stops at some resolution."""
    lo_ms: float = 1.0                # stable
    hi_ms: float = 4.0                # divergent

    def compute(self, figs: Figures) -> dict:
        end = load("punch_split").end_time()

        def diverges(n: int) -> bool:
            return Cosim("punch_split", "jacobi", end / n).compute(figs)["diverged"]

        stable_n, unstable_n = math.ceil(end / (self.lo_ms * 1e-3)), math.ceil(end / (self.hi_ms * 1e-3))
        if diverges(stable_n) or not diverges(unstable_n):      # else the bisection would lie
            raise RuntimeError(f"plain Jacobi on punch_split is not stable at {self.lo_ms} ms and "
                               f"divergent at {self.hi_ms} ms: widen StabilityLimit's bracket")
        while stable_n - unstable_n > 1:
            n = (stable_n + unstable_n) // 2
            stable_n, unstable_n = (stable_n, n) if diverges(n) else (n, unstable_n)
        return {"stable_ms": end / stable_n * 1e3, "diverges_ms": end / unstable_n * 1e3}


@dataclass(frozen=True)
class HeldOnStop:
    """punch_drive with a compression-only spring 11 preloaded to 30 N at the default step, over
    so many revolutions: the share of the run the monolithic punch rides on the stop, and the
    co-simulation's largest deviation of the punch height (y_err, m) and of spring 11's force
    (F3_err, N)."""
    revolutions: int

    def compute(self, figs: Figures) -> dict:
        sc = load("punch_drive")
        sc.revolutions = self.revolutions
        values = {"compression_only": 1, "F30": 30.0}
        for name, value in values.items():
            sc.set_value(f"punch.{name}", value)
        result = figs.run(sc)
        mono = punch.solve({"omega0": 100.0}, {}, values, result.time[-1],
                                      sample_step=sc.even_steps()[1], sample_switches=False)
        n = len(result.time) - 1
        return {"held_pct": 100.0 * float(np.mean(mono.held[:n])),
                "y_err": float(np.max(np.abs(result["punch.y"][:n] - mono.y[:n]))),
                "F3_err": float(np.max(np.abs(result["punch.F3"][:n] - mono.F3[:n])))}


# the figures of the pure linkages read from samples: those in degrees, those in millimetres
LINKAGE_FIGURES = {"feed": {"deg": ("phi3_swing_deg", "phi5_swing_deg", "phi7_swing_deg",
                                    "min_transmission_angle_C_deg", "min_transmission_angle_N_deg",
                                    "min_transmission_angle_F_deg"),
                            "mm": ("M_path_width_mm", "M_path_height_mm")},
                   "takeup": {"deg": (), "mm": ("path_extent_z_mm", "path_extent_x_mm", "stroke_mm")}}


@dataclass(frozen=True)
class AdaptiveLinkages:
    """The adaptive master on feed and takeup against their own fixed step: the largest
    difference of an angle (`deg`) and of a length (`mm`) among their figures."""

    def compute(self, figs: Figures) -> dict:
        worst = {"deg": 0.0, "mm": 0.0}
        for name, groups in LINKAGE_FIGURES.items():
            fixed = summarize(figs.run(load(name)))
            adaptive = load(name)
            adaptive.master = "adaptive"
            variable = summarize(figs.run(adaptive))
            for unit, keys in groups.items():
                worst[unit] = max([worst[unit]] + [abs(variable[k] - fixed[k]) for k in keys])
        return worst


@dataclass(frozen=True)
class Order:
    """The observed order of the trajectory error: the slope of log y_err over log step, fitted
    over the runs named."""
    runs: tuple[str, ...]

    def compute(self, figs: Figures) -> dict:
        steps = [RUNS[r].load().even_steps()[1] for r in self.runs]
        errors = [figs.value(f"y_err@{r}") for r in self.runs]
        return {"order": float(np.polyfit(np.log(steps), np.log(errors), 1)[0])}


def unbounded(result) -> bool:
    """A run of punch_split that ended but whose fabric force ran away (the check before the
    master watched for divergence; kept as a second opinion)."""
    if "fabric.F2" not in result.columns:
        return False
    force = result["fabric.F2"]
    return not bool(np.all(np.isfinite(force)) and force.max() < 1e3)


def trajectory_error(sc, result) -> float:
    """Largest |y − y_ref| at the communication points, against a dense monolithic solution on
    the run's own grid (its whole, even steps)."""
    omega = sc.instances["shaft"].parameters.get("omega0", 100.0)
    mono = punch.solve({"omega0": omega}, {}, {}, result.time[-1],
                                  sample_step=sc.even_steps()[1], sample_switches=False)
    n = len(result.time) - 1              # the last step may be shorter: compare the grid
    assert np.allclose(mono.time[:n], result.time[:n], rtol=0, atol=1e-12)
    return float(np.max(np.abs(result["punch.y"][:n] - mono.y[:n])))


def _runs() -> dict:
    runs = {}
    for h in ("1e-3", "5e-4", "2.5e-4", "1e-4", "5e-5", "2e-3"):
        runs[f"drive-jacobi-{h}"] = Cosim("punch_drive", "jacobi", float(h))
    for h in ("5e-4", "2.5e-4"):
        runs[f"drive-gs-{h}"] = Cosim("punch_drive", "gauss-seidel", float(h))
    for h in ("2e-3", "1e-3", "5e-4", "2.5e-4", "1e-4"):
        runs[f"split-jacobi-{h}"] = Cosim("punch_split", "jacobi", float(h))
    for acc, short in (("aitken", "aitken"), ("iqn-ils", "iqn"), ("none", "none")):
        for h in ("4e-3", "2e-3", "1e-3", "5e-4", "2.5e-4"):
            runs[f"split-{short}-{h}"] = Cosim("punch_split", "iterative", float(h), acc)
    for tol in ("1e-4", "1e-5", "1e-6"):
        runs[f"drive-adaptive-{tol}"] = Cosim("punch_drive", "adaptive", 2.5e-4, tol)
    for tol in ("1e-2", "3e-3", "1e-3", "1e-4"):
        runs[f"split-adaptive-{tol}"] = Cosim("punch_split", "adaptive", 2.5e-4, tol)
    for rtol in ("1e-3", "1e-4", "1e-5", "1e-6"):
        runs[f"mono-{rtol}"] = Monolithic(float(rtol))
    runs |= {"split-own": Cosim("punch_split"), "split-own-300": Cosim("punch_split", omega=300.0),
             "split-jacobi-2.5e-4-300": Cosim("punch_split", "jacobi", 2.5e-4, omega=300.0),
             "drive-jacobi-2.5e-4-300": Cosim("punch_drive", "jacobi", 2.5e-4, omega=300.0),
             "script-1e-4": Script(1e-4), "split-limit": StabilityLimit(),
             "held": HeldOnStop(3), "held-10": HeldOnStop(10), "linkages": AdaptiveLinkages(),
             "drive-order": Order(tuple(f"drive-jacobi-{h}"
                                        for h in ("1e-3", "5e-4", "2.5e-4", "1e-4", "5e-5")))}
    return runs


RUNS = _runs()


class Figures:
    """The figures of the runs, each run computed once, when a figure of it is first asked for.
    `fmus` (FMU name -> file) runs given FMUs (the tests' build), else those of fmus/."""

    def __init__(self, fmus: dict | None = None):
        self.fmus = fmus
        self._runs: dict[str, dict] = {}
        self._tight: dict[float, dict] = {}

    def run(self, sc):
        return run(sc, self.fmus) if self.fmus is not None else simulate(sc)

    def tight(self, omega: float) -> dict:
        """The monolithic solution at rtol 1e-10 (the reference of every error) at that speed."""
        if omega not in self._tight:
            sc = load("punch_drive")
            sc.set_value("shaft.omega0", omega)
            self._tight[omega] = monolithic_summary(sc)[0]
        return self._tight[omega]

    def value(self, key: str):
        figure, _, run_id = key.partition("@")
        if run_id not in self._runs:
            self._runs[run_id] = RUNS[run_id].compute(self)
        figures = self._runs[run_id]
        if callable(figures[figure]):             # a figure computed only when asked
            figures[figure] = figures[figure]()
        return figures[figure]

    def warm(self) -> None:
        """Extract and load the FMUs once, so that no timed run pays for it."""
        for name in ("punch_drive", "punch_split"):
            self.run(load(name))


# --- printing and reading numbers ------------------------------------------------------------
SUPERSCRIPT = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")
PLAIN = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻", "0123456789-")


def fmt(x: float, spec: str) -> str:
    """x printed at spec: gN (Python's g, N significant digits), sN (signed, fixed point, N
    significant digits, the typographic minus), eN ("3.5e-7"), uN ("1.8·10⁻⁸"), fN (N
    decimals), d (an integer)."""
    if isinstance(x, float) and math.isnan(x):
        return "diverged"
    kind, digits = spec[0], int(spec[1:] or 0)
    if kind == "g":
        return f"{x:.{digits}g}"
    if kind == "f":
        return f"{x:.{digits}f}"
    if kind == "d":
        return f"{round(x):d}"
    if kind == "s":
        decimals = max(0, digits - 1 - _exponent(x))
        return f"{x:+.{decimals}f}".replace("-", "−")
    mantissa, exponent = f"{x:.{digits - 1}e}".split("e")
    if kind == "e":
        return f"{mantissa}e{int(exponent)}"
    if kind == "u":
        return f"{mantissa}·10{str(int(exponent)).translate(SUPERSCRIPT)}"
    raise ValueError(f"unknown format {spec!r}")


def _exponent(x: float) -> int:
    return math.floor(math.log10(abs(x))) if x else 0


def parse_number(text: str) -> float:
    """A number as fmt prints it (the typographic minus, ·10⁻⁸ too)."""
    text = text.strip().replace("−", "-")
    if "·10" in text:
        mantissa, exponent = text.split("·10")
        return float(mantissa) * 10.0 ** int(exponent.translate(PLAIN))
    return float(text)


def last_digit(text: str) -> float:
    """The value of one unit in the last printed digit: 0.0012 -> 1e-4, 9.6e-05 -> 1e-6."""
    text = text.strip().replace("−", "-").lstrip("+-")
    mantissa, exponent = text, 0
    for mark in ("·10", "e"):
        if mark in text:
            mantissa, tail = text.split(mark)
            exponent = int(tail.translate(PLAIN))
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    return 10.0 ** (exponent - decimals)


def round_up(x: float, spec: str) -> str:
    """x printed at spec, rounded up in its last digit: a bound that holds."""
    if math.isnan(x) or x <= 0:
        return fmt(x, spec)
    kind, digits = spec[0], int(spec[1:] or 0)
    quantum = 10.0 ** -digits if kind == "f" else 1.0 if kind == "d" else \
        10.0 ** (_exponent(x) - digits + 1)
    text = fmt(math.ceil(x / quantum * (1 - 1e-12)) * quantum, spec)
    return text if parse_number(text) >= x else fmt(parse_number(text) + quantum, spec)


# --- the blocks in the docs ------------------------------------------------------------------
ERRORS = "{fig onset@R g2} | {fig loss@R g2} | {fig peak@R g2} | {fig weld@R g2}"


def keyed(row: str, run_id: str) -> str:
    """A row written with R for its run, for that run."""
    return row.replace("@R ", f"@{run_id} ").replace("{wall R ", f"{{wall {run_id} ")
STAMP = ("*Errors by `docs/tools/doc_figures.py`, {stamp figures};\n"
         "wall times measured {stamp timings}: a measurement of that day.*")


def table(header: str, rows: list[str]) -> str:
    """A table block: a line of its own after the opening marker, the stamp under the table."""
    columns = header.count("|") - 1
    return "\n".join(["", header, "|---" * columns + "|", *rows, "", STAMP, ""])


def coupling_table(rows) -> str:
    """The two-way coupling table from (first cell, step cell, run) rows; a run written "!R":
    a row that only says that run diverges."""
    lines = []
    for first, step, run_id in rows:
        if run_id.startswith("!"):
            lines.append(f"| {first} | {step} | {{verdict diverged@{run_id[1:]}}} | | | | |")
        else:
            lines.append(keyed(f"| {first} | {step} | {{wall R f3}} | {ERRORS} |", run_id))
    return table("| scenario, master | step or tolerance | wall [s] | onset [°] | loss [°] "
                 "| F2_peak [N] | F2_weld_mean [N] |", lines)


README_TABLE = coupling_table([
    ("punch_drive, jacobi", "2.5e-4 s", "drive-jacobi-2.5e-4"),
    ("punch_drive, adaptive", "1e-5", "drive-adaptive-1e-5"),
    ("punch_split, adaptive (its own)", "3e-3", "split-own"),
    ("punch_split, jacobi", "2.5e-4 s", "split-jacobi-2.5e-4"),
    ("punch_split, jacobi", "2e-3 s", "!split-jacobi-2e-3"),
    ("punch_split, iterative (Aitken)", "2e-3 s", "split-aitken-2e-3"),
    ("monolithic DOP853", "rtol 1e-4", "mono-1e-4")])

ITERATIVE_STEPS = ("4e-3", "2e-3", "1e-3", "5e-4", "2.5e-4")
RUNNING_TABLE = coupling_table(
    [("punch_drive, jacobi", f"{float(h):g} s", f"drive-jacobi-{h}")
     for h in ("1e-3", "5e-4", "2.5e-4", "1e-4")]
    + [("punch_drive, gauss-seidel", f"{float(h):g} s", f"drive-gs-{h}") for h in ("5e-4", "2.5e-4")]
    + [("punch_split, jacobi", f"{float(h):g} s", f"split-jacobi-{h}")
       for h in ("1e-3", "5e-4", "2.5e-4", "1e-4")]
    + [(f"punch_split, iterative/{acc}", f"{float(h):g} s", f"split-{short}-{h}")
       for acc, short in (("aitken", "aitken"), ("iqn-ils", "iqn")) for h in ITERATIVE_STEPS]
    + [("punch_split, iterative/none", f"{float(h):g} s", f"split-none-{h}") for h in ("1e-3", "2.5e-4")]
    + [("punch_drive, adaptive", f"{float(t):g}", f"drive-adaptive-{t}") for t in ("1e-4", "1e-5", "1e-6")]
    + [("punch_split, adaptive (its own)" if t == "3e-3" else "punch_split, adaptive", f"{float(t):g}",
        "split-own" if t == "3e-3" else f"split-adaptive-{t}") for t in ("1e-2", "3e-3", "1e-3", "1e-4")]
    + [("monolithic DOP853", f"rtol {float(r):g}", f"mono-{r}") for r in ("1e-3", "1e-4", "1e-5", "1e-6")])

STEP_TABLE = table(
    "| step [s] | onset [°] | loss [°] | F2_peak [N] | F2_weld_mean [N] | max abs(y − y_ref) [m] "
    "| co-sim wall [s] |",
    [keyed(f"| {label} | {{fig d_onset@R s2}} | {{fig d_loss@R s2}} | {{fig d_peak@R s2}} "
           "| {fig d_weld@R s2} | {fig y_err@R e2} | {wall R f2} |", f"drive-jacobi-{h}")
     for label, h in (("1e-3", "1e-3"), ("5e-4", "5e-4"), ("**2.5e-4 (default)**", "2.5e-4"),
                      ("1e-4", "1e-4"), ("5e-5", "5e-5"))])

TIME_TO_ACCURACY = table(
    "| step [s] | wall [s] | error F2_weld_mean [N] | error contact duration [°] |",
    [keyed(f"| {label} | {{wall R f3}} | {{fig weld@R g2}} | {{fig duration@R g2}} |", f"drive-jacobi-{h}")
     for label, h in (("2e-3", "2e-3"), ("1e-3", "1e-3"), ("5e-4", "5e-4"), ("**2.5e-4**", "2.5e-4"),
                      ("1e-4", "1e-4"))])


# the prose: the same figures in several places
def of(figures: str, run_id: str) -> str:
    """The keys of several figures of one run: of("onset,loss", R) -> "onset@R,loss@R"."""
    return ",".join(f"{f}@{run_id}" for f in figures.split(","))


OWN, OWN300, ADAPTIVE = "split-own", "split-own-300", "drive-adaptive-1e-5"
JACOBI, JACOBI300 = "split-jacobi-2.5e-4", "split-jacobi-2.5e-4-300"
DEFAULT, DEFAULT300 = "drive-jacobi-2.5e-4", "drive-jacobi-2.5e-4-300"
ANGLES, FORCES = "onset,loss,duration", "peak,weld"
LIMIT = "diverges from a step of {fig diverges_ms@split-limit f3} ms"

BLOCKS = {
    "README.md": {
        "coupling-table": README_TABLE,
        "split-own": (
            f"within {{within {of('onset,loss', OWN)} g2}}° and {{within {of(FORCES, OWN)} g2}} N of the\n"
            f"monolithic figures (at ω = 300 s⁻¹: the angles within {{within {of('onset,loss', OWN300)} g2}}°"
            f" and F2_weld_mean within\n{{within weld@{OWN300} g2}} N, the landing's F2_peak "
            f"{{fig peak@{OWN300} g2}} N off; Jacobi at 2.5e-4 s is {{fig weld@{JACOBI300} g2}} N\noff in "
            "F2_weld_mean there)"),
        "split-limit": LIMIT,
        "speed-accuracy": (
            f"onset\nwithin {{bound onset@{ADAPTIVE},onset@script-1e-4}}° and F2_weld_mean within "
            f"{{bound weld@{ADAPTIVE},weld@script-1e-4}} N of the tight solution"),
    },
    "docs/running.md": {
        "linkages": "within {within deg@linkages g2}° and {within mm@linkages g2} mm here",
        "coupling-table": RUNNING_TABLE,
        "targets-split": (
            f"within {{within onset@{OWN} g2}}° (onset),\n  {{within loss@{OWN} g2}}° (loss) and "
            f"{{within weld@{OWN} g2}} N (F2_weld_mean) of the monolithic figures (goal 0.1°, 0.01 N); "
            f"at\n  ω = 300 s⁻¹ within {{within onset@{OWN300} g2}}°, {{within loss@{OWN300} g2}}° and "
            f"{{within weld@{OWN300} g2}} N (F2_peak {{fig peak@{OWN300} g2}} N). Jacobi at 2.5e-4 s is as"
            f"\n  good at ω = 100 s⁻¹ ({{fig onset@{JACOBI} g2}}°, {{fig loss@{JACOBI} g2}}°, "
            f"{{fig weld@{JACOBI} g2}} N) but not at 300 s⁻¹\n  ({{fig weld@{JACOBI300} g2}} N)"),
        "targets-adaptive": (
            f"onset and loss within {{within {of('onset,loss', ADAPTIVE)} g1}}°, F2_peak within "
            f"{{within peak@{ADAPTIVE} g1}} N,\n  F2_weld_mean within {{within weld@{ADAPTIVE} g1}} N"),
        "stability": ("stable up to a step of {fig stable_ms@split-limit f3} ms, divergent from\n  "
                      "{fig diverges_ms@split-limit f3} ms"),
        "iterative": ("less accurate than Jacobi\n  in the contact angles at the small steps (onset "
                      f"{{fig onset@split-aitken-2.5e-4 g2}}° against {{fig onset@{JACOBI} g2}}° at\n  "
                      "2.5e-4 s)"),
        "passes": ("{fig passes@split-aitken-1e-3 f1} and {fig passes@split-iqn-1e-3 f1} against "
                   "{fig passes@split-none-1e-3 f1} per step at\n  1 ms, where the plain iteration "
                   "fails to converge in {fig unconverged@split-none-1e-3 d} steps"),
    },
    "docs/punch_drive.md": {
        "held": ("rides on the stop\n  {fig held_pct@held f0} % of the time and the co-simulation "
                 "follows the monolithic solution, which implements the\n  same rule independently "
                 "(scipy events), to {fig y_err@held u2} m (y) and {fig F3_err@held g1} N (F3) over "
                 "three\n  revolutions at the default step ({fig y_err@held-10 u2} m and "
                 "{fig F3_err@held-10 g1} N over ten)"),
        "split-limit": LIMIT,
        "split-own": (
            f"within {{bound {of('onset,loss', OWN)}}}° and {{bound {of(FORCES, OWN)}}} N (at ω = 300 s⁻¹ "
            f"the\nangles within {{bound {of('onset,loss', OWN300)}}}° and F2_weld_mean within "
            f"{{bound weld@{OWN300}}} N; the landing's F2_peak is {{fig peak@{OWN300} g1}} N\noff)"),
        "step-table": STEP_TABLE,
        "step-prose": (
            "observed order of\nabout {fig order@drive-order f1} (the body is integrated exactly; what "
            "remains is the Taylor extrapolation of ξ within\na step). The default step 2.5e-4 s keeps "
            f"every figure within {{bound {of(ANGLES, DEFAULT)}}}° and {{bound {of(FORCES, DEFAULT)}}} N "
            f"at ω = 100 s⁻¹\nand within {{bound {of(ANGLES, DEFAULT300)}}}° and "
            f"{{bound {of(FORCES, DEFAULT300)}}} N at ω = 300 s⁻¹; at 1e-3 s the contact angles are "
            "already {fig onset@drive-jacobi-1e-3,loss@drive-jacobi-1e-3 g1}°\noff, because the "
            "figures are read from the samples"),
    },
    "docs/performance.md": {
        "speed-accuracy": (
            f"onset {{fig onset@{ADAPTIVE} f4}}°, F2_weld_mean {{fig weld@{ADAPTIVE} f4}} N from the "
            "tight solution; the script {fig onset@script-1e-4 f4}° and {fig weld@script-1e-4 f4} N"),
        "default-accuracy": (
            f"figures within {{within {of(ANGLES, DEFAULT)} g2}}° and {{within {of(FORCES, DEFAULT)} g2}} "
            "N of the monolithic solution"),
        "time-to-accuracy": TIME_TO_ACCURACY,
    },
}

# The blocks of the pages that another script writes and checks (its markers alike): page -> names
WRITTEN_ELSEWHERE = {"docs/running.md": ("estimate-table-punch", "estimate-table-carriage",
                                         "estimate-scan", "estimate-noise")}   # estimate_bounds.py

# The "within <number>" in the docs that are not accuracy figures against the monolithic solution,
# and why they are left to others; every other one must lie in a block (tests/docs/test_doc_figures.py).
WITHIN_ELSEWHERE = {
    "within 0.06° and 0.0001 N": "sewfmu against another FMI host (ecos's command-line tool): "
                                  "`sewfmu crosscheck --host ecos-cli`; tests/hosts/test_interop.py",
    "within 0.06°, its CSV": "the same, in docs/fmi.md's list of hosts",
    "within 1e-4° and 1e-5 N": "libcosim against sewfmu: tests/hosts/test_interop.py (2e-4°, 1e-5 N)",
    "within 0.001 N (F2_weld_mean) of sewfmu's adaptive run": "OMSimulator, a host built by hand",
    "within 0.2 µm of the exact bouncing": "the held punch against its exact bouncing: "
                                           "tests/components/test_punch_contact.py",
    "within 4 % of its μ*": "Morris's μ* against one-at-a-time runs: "
                            "tests/design/test_design_examples.py (20 %)",
    # times of the way out of a stuck FMU (scenarios/cosim/watchdog.py, guardian.py): settings of
    # the code, held by the tests that send the signals
    "within 50 ms of a": "the SIGTERM after a SIGINT that still decides: "
                         "tests/cosim/test_interruptions.py",
    "within 1.1 s, or a": "the guardian's grace: tests/cosim/test_gil_held.py",
    "within 1.5 s while it": "the waiter's grace for an FMU that ignores a signal: "
                             "tests/cosim/test_signals_ignored.py",
}

FIELD = re.compile(r"\{(fig|within|bound|verdict|wall|stamp) ([^ }]+)(?: ([^ }]+))?\}")
MARKER = re.compile(r"<!-- figures: ([\w-]+) -->(.*?)<!-- /figures -->", re.S)


@dataclass(frozen=True)
class Field:
    kind: str
    keys: tuple[str, ...]         # figure@run; a wall time's run; a stamp's "figures"/"timings"
    spec: str | None


def parts(template: str) -> list:
    """The template as literal strings and Fields, alternating (a string first and last)."""
    pieces = FIELD.split(template)
    out = [pieces[0]]
    for k in range(1, len(pieces), 4):
        out += [Field(pieces[k], tuple(pieces[k + 1].split(",")), pieces[k + 2]), pieces[k + 3]]
    return out


def parse(template: str, text: str) -> list[str] | None:
    """The printed text of each field of a block written from this template, None if the
    block's text does not follow the template."""
    pattern = "".join(_loose(p) if isinstance(p, str) else "(.*?)" for p in parts(template))
    match = re.fullmatch(pattern, text, re.S)
    return list(match.groups()) if match else None


def _loose(literal: str) -> str:
    """A literal as a pattern in which any whitespace matches any whitespace: prose rewrapped by
    hand still parses (the next write wraps it as the template does)."""
    return "".join(r"\s+" if piece.isspace() else re.escape(piece)
                   for piece in re.split(r"(\s+)", literal) if piece)


def machine() -> str:
    return (f"{datetime.date.today().isoformat()} on {platform.system()} {platform.machine()}, "
            f"{os.cpu_count()} CPUs, Python {platform.python_version()}")


def field_text(field: Field, printed: str | None, figs: Figures, timings: bool,
               notices: list[str], where: str) -> str:
    """One field's text from the figures (a stamp's is render's)."""
    if field.kind == "wall":
        return fmt(figs.value(f"wall@{field.keys[0]}"), field.spec) if timings else printed or "?"
    values = [figs.value(key) for key in field.keys]
    if field.kind == "verdict":
        return "diverges" if all(values) else "stable"
    value = max(values)
    if field.kind == "fig":
        return fmt(value, field.spec)
    if field.kind == "within":
        return round_up(value, field.spec)
    if printed and holds(printed, value):                       # a bound: kept while it holds
        return printed
    loosened = round_up(value, "g1")
    notices.append(f"{where}: the promise 'within {printed}' does not hold ({value:.3g}): "
                   f"now 'within {loosened}'")
    return loosened


def render(template: str, figs: Figures, old: list[str] | None, timings: bool,
           notices: list[str], where: str) -> str:
    """The block's text from the figures; wall times and the stamps from `old` (the block as
    written) unless measured anew; a bound kept while it holds."""
    pieces = parts(template)
    fields = [p for p in pieces if isinstance(p, Field)]
    old = old or [None] * len(fields)
    texts = [None if f.kind == "stamp" else field_text(f, printed, figs, timings, notices, where)
             for f, printed in zip(fields, old)]

    def assemble(new_figures: bool) -> str:
        new = {"figures": new_figures, "timings": timings}
        filled = iter([text if text is not None else machine() if new[f.keys[0]]
                       else printed or "(not measured)" for f, text, printed in zip(fields, texts, old)])
        return "".join(p if isinstance(p, str) else next(filled) for p in pieces)

    same_stamp = assemble(False)                 # the stamp moves only when a figure did
    return same_stamp if parse(template, same_stamp) == old else assemble(True)


def holds(printed: str, value: float) -> bool:
    """A bound holds: the computed value is not above the printed one."""
    try:
        return value <= parse_number(printed) * (1 + 1e-12)
    except ValueError:
        return False


def close(printed: str, value) -> bool:
    """A figure agrees with its computed value: within 2 % or one unit of its last printed
    digit, whichever is larger (accuracy figures are deterministic on one machine)."""
    if isinstance(value, float) and math.isnan(value):
        return printed == "diverged"
    try:
        number = parse_number(printed)
    except ValueError:
        return False
    return abs(number - value) <= max(0.02 * abs(value), last_digit(printed)) * (1 + 1e-9)


def check_block(template: str, text: str, figs: Figures) -> list[str]:
    """What in one block no longer holds, one line each (none: all true)."""
    printed = parse(template, text)
    if printed is None:
        return ["its text does not follow the script's template: run docs/tools/doc_figures.py"]
    failures = []
    fields = [p for p in parts(template) if isinstance(p, Field)]
    for field, shown in zip(fields, printed):
        if field.kind in ("wall", "stamp"):
            continue
        values = [figs.value(key) for key in field.keys]
        if field.kind == "verdict":
            ok = shown == ("diverges" if all(values) else "stable")
        elif field.kind == "fig":
            ok = close(shown, max(values))
        elif field.kind == "within":
            ok = holds(shown, max(values)) and close(shown, max(values))
        else:
            ok = holds(shown, max(values))
        if not ok:
            failures.append(f"{field.kind} {','.join(field.keys)}: printed {shown!r}, computed "
                            f"{max(values) if field.kind != 'verdict' else values}")
    return failures


def blocks_of(text: str) -> dict[str, tuple[re.Match, str]]:
    return {m.group(1): (m, m.group(2)) for m in MARKER.finditer(text)}


def check(figs: Figures, files=None, names=None) -> list[str]:
    """Every failure in the blocks of these files (default: all), one line each."""
    failures = []
    for doc, blocks in BLOCKS.items():
        if files and doc not in files:
            continue
        found = blocks_of((REPO / doc).read_text(encoding="utf-8"))
        for name, template in blocks.items():
            if names and name not in names:
                continue
            if name not in found:
                failures.append(f"{doc}: no block '{name}'")
                continue
            failures += [f"{doc} [{name}] {line}" for line in check_block(template, found[name][1], figs)]
    return failures


def write(figs: Figures, timings: bool) -> list[str]:
    """Rewrite every block; what changed and every loosened promise, one line each."""
    notices = []
    for blocks in BLOCKS.values():           # the minutes of computing before any file is read:
        for template in blocks.values():     # others may be editing the docs meanwhile
            for field in parts(template)[1::2]:
                if field.kind not in ("stamp", "wall"):
                    [figs.value(key) for key in field.keys]
                elif field.kind == "wall" and timings:
                    figs.value(f"wall@{field.keys[0]}")
    for doc, blocks in BLOCKS.items():
        path = REPO / doc
        text = path.read_text(encoding="utf-8")
        found = blocks_of(text)
        for name, template in blocks.items():
            if name not in found:
                raise SystemExit(f"{doc}: no block <!-- figures: {name} --> to write into")
            old_text = found[name][1]
            new_text = render(template, figs, parse(template, old_text), timings, notices,
                              f"{doc} [{name}]")
            if new_text != old_text:
                notices.append(f"{doc} [{name}] rewritten")
                text = text.replace(found[name][0].group(0),
                                    f"<!-- figures: {name} -->{new_text}<!-- /figures -->")
        path.write_text(text, encoding="utf-8")
    return notices


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true", help="compare only, change nothing")
    parser.add_argument("--timings", action="store_true", help="measure the wall times again")
    args = parser.parse_args()
    figs = Figures()
    if args.timings:
        figs.warm()
    if args.check:
        failures = check(figs)
        print("\n".join(failures) or "every figure holds")
        sys.exit(1 if failures else 0)
    print("\n".join(write(figs, args.timings)) or "nothing changed")


if __name__ == "__main__":
    main()
