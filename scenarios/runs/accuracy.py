"""A run's coupling error on its key figures: a bound from the same run made coarser and from its
own samples read every other one.

What is computed. A master that steps at a fixed communication step (Jacobi, Gauss-Seidel,
iterative) runs again at twice its step; the adaptive master at eight times its tolerance (at
most its loosest, 1e-2). The run's own record is read twice more, every other sample each way
(`thinnings`; no run). For each figure f:

    Δf    = |f of the coarser run − f of the run read on the coarser run's samples| / (r**ORDER − 1)
            (r the ratio of the steps or tolerances; under the adaptive master, whose samples fall
            elsewhere, f of the run itself)
    σf    = the larger |f − f of a thinning|
    own f = SAFETY · Δf + SAMPLING · σf
    ± f   = the largest own g / |g| of the figures g of f's unit, times |f| (f's own among them)

Why so, measured against converged runs (the punch's monolithic solution at rtol 1e-10, the
carriage at 1e-5 s; bench/estimate_bounds.py, its tables in docs/running.md). The error of a
figure read from samples does not shrink evenly with the step: a contact angle interpolated
between two samples, a peak read at one, a landing inside a step move with where the samples
fall, so two runs can agree while both are off. Twice the difference alone (the estimate before
this one) fell short in a scan of every step by up to 350 times (punch_drive's contact onset
under the adaptive master at tolerance 6.5e-5), 200 times on the carriage (0.545 ms), and in the
two cases reported: the carriage at 0.5 ms (± 8.75 µm, 9.03 µm off), the adaptive master at
tolerance 2e-3 (F2_peak ± 0.085 N, 0.093 N off).

- Sampling and coupling apart: under a fixed step the coarser run's samples are every other one
  of the run's, so read there the two runs differ by their coupling alone, and σ says what the
  samples do. Mixed, a run whose coarser run samples badly was bounded by that (punch_drive at
  300 s⁻¹: the loss 1.75° apart, 0.15° off; nearly all of it the samples).
- SAMPLING = 1: for a crossing interpolated linearly between samples σ is at least twice the
  error at the run's own step, wherever the samples fall.
- The unit: figures of one unit are read from the same signals (the angles from the punch's height
  and force, the forces from F2, the peaks from U2), so a difference that vanishes by chance for
  one is made up by the others, each in proportion to its size.
- ORDER, the lowest order of the error measured, rounded down: against the step 1.6 to 2.6 for
  every figure, so 1; against the adaptive master's tolerance 0.55 (punch_split's contact angles,
  whose errors its step sets as much as its tolerance) to 1.3, so 0.5: r**ORDER − 1 = 1.83 at
  eight times the tolerance, not the 7 of an error proportional to it.
- SAFETY = 7: the least that keeps the scans' hardest bounded run bounded (punch_split, Jacobi,
  F2_peak at 0.4585 ms: its ± 1.02 times its error; every other accepted run of the scans 1.8
  times or more); more would refuse runs whose figures are a thousandth off (punch_drive at
  200 s⁻¹ and its default step comes to ± 4.4 % of a figure at 7, 5 %, accuracy's default, at 8).

Where it still falls short, measured (docs/running.md): punch_split under the iterative master at
about 0.1 ms, F2_peak 0.0048 N off, its ± 0.69 of that; punch_split under the adaptive master at
tolerances near 4e-4, where its contact angles' error grows as the tolerance tightens and is
chaotic in it (a millionth changes it): 2 runs of 40 fall short, by up to 2.3 times, on errors
of 0.02°. Two runs cannot see an error that does not shrink between them.

Where no difference can measure the error, there is no ± and the run counts as beyond its
accuracy: a coarser run that diverges or fails (the step near the coupling's stability limit); a
count (n_contacts) that differs between the runs or the thinnings (they see other events); a
figure whose coarser value is further from it than it is from zero (outside every scan).

The cost is the coarser run (half of the run for a fixed-step master) and two readings of the
record. Sweep points are not estimated (their table compares them with each other), nor
kinematic mechanisms (the feed, the take-up: their FMUs give exact positions at every
communication point; what their figures owe to the step is sampling, which their analyses state).
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from sewfmu.errors import Error
from sewfmu.scenarios.cosim.algorithms import ALGORITHMS
from sewfmu.scenarios.cosim.divergence import Diverged
from sewfmu.scenarios.cosim.master import RunResult
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.runs.runner import simulate, summarize

TOLERANCE_FACTOR = 8          # the adaptive master's coarser run: its tolerance times this
SAFETY = 7.0                  # on the coupling's difference (docstring: measured need 6.83)
SAMPLING = 1.0                # on the thinnings' spread, which is twice the sampling error or more
# the lowest measured order of the figures' error, rounded down: against the step, against the
# adaptive master's tolerance
ORDER = {"step": 1.0, "tolerance": 0.5}
# a column whose name ends so holds the largest value within each step (the F2_max of PunchContact
# and Fabric, which catches the impact at a landing between two samples)
HOLD_SUFFIX = "_max"


def coarser(scenario: Scenario) -> tuple[Scenario, float, str, str] | None:
    """The coarser run, its ratio to the run (step or tolerance), which of the two ORDER applies
    to, and how it was made; None where there is none (a run of under 4 steps, or the adaptive
    master within a factor 2 of its loosest tolerance)."""
    coarse = scenario.copy()
    origin = "accuracy estimate"
    if ALGORITHMS[scenario.master].variable_step:
        settings = scenario.settings()
        high = type(settings).TOLERANCES[1]
        tolerance = min(settings.tolerance * TOLERANCE_FACTOR, high)
        if tolerance < 2 * settings.tolerance:
            return None
        coarse.set_value("experiment.tolerance", tolerance, origin=origin)
        return (coarse, tolerance / settings.tolerance, "tolerance",
                f"the run at tolerance {tolerance:g}")
    n, h = scenario.even_steps()
    if n < 4:
        return None
    coarse.set_value("experiment.step", 2 * h, origin=origin)
    ratio = coarse.even_steps()[1] / h
    return coarse, ratio, "step", f"the run at twice the step ({2 * h:.4g} s)"


def thinnings(result: RunResult) -> list[RunResult]:
    """The run's record read every other sample, each way (the even samples, the odd ones), both
    with the first and the last (where the last revolution ends). A column that holds the largest
    value within each step keeps, at each sample left, the largest of the steps it now ends: the
    impact at a landing stays in every reading, as it would in a run at twice the step."""
    n = len(result.time)
    if n < 5:
        return []
    out = []
    for first in (0, 1):
        kept = np.unique(np.concatenate(([0], np.arange(first, n, 2), [n - 1])))
        starts = np.concatenate(([kept[0]], kept[:-1] + 1))      # the steps each sample ends
        columns = {name: (np.maximum.reduceat(values, starts) if name.endswith(HOLD_SUFFIX)
                          and values.dtype.kind == "f" else values[kept])
                   for name, values in result.columns.items()}
        out.append(dataclasses.replace(result, time=result.time[kept], columns=columns))
    return out


def bound(run: dict, coarse: dict, thinned: list[dict], units: dict[str, str], ratio: float,
          kind: str) -> dict[str, float]:
    """The ± of the docstring's formula for each figure of `units` (figure -> unit) that the run,
    the coarser run and every thinning give as numbers. Under a fixed step the coarser run's
    samples are every other one of the run's (the first thinning): compared there, the two
    differ by their coupling alone."""
    names = [k for k in units if all(isinstance(s.get(k), (int, float))
                                     for s in (run, coarse, *thinned))]
    same_samples = kind == "step" and bool(thinned)
    base = thinned[0] if same_samples else run
    divisor = ratio ** ORDER[kind] - 1.0
    own = {k: SAFETY * abs(base[k] - coarse[k]) / divisor
           + SAMPLING * max([abs(run[k] - t[k]) for t in thinned], default=0.0) for k in names}
    out = {}
    for k in names:             # at least its unit's largest, relative to each figure's size
        peers = [own[g] / abs(run[g]) for g in names if units[g] == units[k] and run[g] != 0]
        out[k] = max([own[k]] + [abs(run[k]) * r for r in peers])
    return out


def distrust(run: dict, coarse: dict, thinned: list[dict], units: dict[str, str]
             ) -> tuple[str | None, dict[str, str]]:
    """Why no difference measures the error: for the whole run (a count the runs disagree on),
    or figure by figure (figure -> why)."""
    for k in units:
        counts = [s.get(k) for s in (run, coarse, *thinned)]
        if all(isinstance(c, int) and not isinstance(c, bool) for c in counts) \
                and len(set(counts)) > 1:
            return (f"the runs count {k} differently ({run[k]} here, {coarse[k]} in the coarser "
                    f"run, {', '.join(str(t[k]) for t in thinned)} every other sample): they "
                    f"see other events, so their difference is not an error"), {}
    why = {}
    for k in units:
        a, b = run.get(k), coarse.get(k)
        if isinstance(a, (int, float)) and isinstance(b, (int, float)) and abs(a - b) > abs(a):
            why[k] = (f"the coarser run gives {b:.6g}, further from {a:.6g} than it is from "
                      f"zero: far outside the steps where the bound was measured")
    return None, why


def estimate(scenario: Scenario, result: RunResult, summary: dict,
             fmu_dir: Path | None = None) -> dict | None:
    """{"method", "figures": {figure: bound}, "untrusted": {figure: why}} (in the figures'
    units), or with "failed": the reason there is no bound, or "none": why none was sought;
    None for a scenario without key figures."""
    if not scenario.analysis:
        return None
    if scenario.accuracy == "off":
        return {"method": None, "figures": {},
                "none": "experiment.accuracy = \"off\""}
    if scenario.mechanism.kinematic:
        return {"method": None, "figures": {},
                "none": "kinematic: the FMUs give exact positions at every communication point"}
    units = {k: u for k, u in scenario.mechanism.figures.items()
             if isinstance(summary.get(k), (int, float))}
    if not units:                         # no figures (a narrowed record): nothing to estimate
        return None
    made = coarser(scenario)
    if made is None:
        return {"method": None, "figures": {},
                "none": "no coarser run to compare with (a run of under 4 steps, or the "
                        "adaptive master within a factor 2 of its loosest tolerance)"}
    coarse_scenario, ratio, kind, how = made
    try:
        coarse = summarize(simulate(coarse_scenario, fmu_dir))
    except Diverged:
        return {"method": how, "figures": {},
                "failed": f"{how} diverged: this step is near the coupling's stability limit"}
    except Error as err:
        return {"method": how, "figures": {}, "failed": f"{how} failed: {_line(err)}"}
    try:
        thinned = [summarize(t) for t in thinnings(result)]
    except Error as err:        # too few samples left in the last revolution, say
        return {"method": how, "figures": {},
                "failed": f"the run's samples, every other one, give no figures: {_line(err)}"}
    whole, untrusted = distrust(summary, coarse, thinned, units)
    if whole:
        return {"method": how, "figures": {}, "failed": whole}
    found = bound(summary, coarse, thinned, units, ratio, kind)
    out = {"method": f"{how} and its samples thinned",
           "figures": {k: b for k, b in found.items() if k not in untrusted}}
    if untrusted:
        out["untrusted"] = untrusted
    return out


def _line(err: Exception) -> str:
    return " ".join(str(err).split())


def beyond(summary: dict, accuracy: float) -> list[str]:
    """The figures whose bound exceeds `accuracy` (relative to the figure), those without a
    bound and why, or the reason there is none; [] where the run is within it or was not
    estimated."""
    found = summary.get("coupling_error")
    if not found or found.get("none"):
        return []
    if found.get("failed"):
        return [f"no estimate: {found['failed']}"]
    out = [f"{name}: no bound ({why})" for name, why in found.get("untrusted", {}).items()]
    for name, error in found["figures"].items():
        value = abs(summary[name])
        if error > accuracy * value or (value == 0.0 and error > 0.0):
            out.append(f"{name} = {summary[name]:.6g} ± {error:.3g} "
                       f"({100 * error / value if value else float('inf'):.2g} %)")
    return out
