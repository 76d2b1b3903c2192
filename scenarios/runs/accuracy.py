"""A run's coupling error on its key figures, estimated by the same run made coarser.

A master that steps at a fixed communication step (Jacobi, Gauss-Seidel, iterative) runs again
at twice its step; the adaptive master at eight times its tolerance. The coupling error of a
figure shrinks with the step (with the tolerance): for a first-order error the difference
between the two runs equals the finer run's error, for a higher order it exceeds it. Figures
read from samples (a contact angle interpolated between steps) do not shrink evenly, so the
estimate is twice the difference (for the adaptive master, whose error is proportional to its
tolerance, twice the difference over 7): on the punch drive it lies above the error against an
independent solution for every figure (tests/test_accuracy.py). A coarser run that diverges or
fails says the step sits near the coupling's stability limit: no estimate, and the run counts
as beyond its accuracy.

The cost is the coarser run: half of the run for a fixed-step master. Sweep points are not
estimated (their table compares them with each other), nor kinematic mechanisms (the feed, the
take-up: their FMUs give exact positions at every communication point; what their figures owe
to the step is sampling, which their analyses state).
"""
from __future__ import annotations

from pathlib import Path

from sewfmu.errors import Error
from sewfmu.scenarios.cosim.algorithms import ALGORITHMS
from sewfmu.scenarios.cosim.divergence import Diverged
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.runs.runner import simulate, summarize

TOLERANCE_FACTOR = 8          # the adaptive master's coarser run: its tolerance times this
SAFETY = 2.0                  # the estimate: this times the difference, divided as coarser() says


def coarser(scenario: Scenario) -> tuple[Scenario, float, str] | None:
    """The coarser run, the divisor that turns the difference into the estimate, and how it was
    made; None where there is none (a run of one step)."""
    coarse = scenario.copy()
    origin = "accuracy estimate"
    if ALGORITHMS[scenario.master].variable_step:
        settings = scenario.settings()
        high = type(settings).TOLERANCES[1]
        tolerance = min(settings.tolerance * TOLERANCE_FACTOR, high)
        if tolerance <= settings.tolerance:
            return None
        coarse.set_value("experiment.tolerance", tolerance, origin=origin)
        return coarse, tolerance / settings.tolerance - 1.0, f"the run at tolerance {tolerance:g}"
    n, h = scenario.even_steps()
    if n < 4:
        return None
    coarse.set_value("experiment.step", 2 * h, origin=origin)
    return coarse, 1.0, f"the run at twice the step ({2 * h:.4g} s)"


def estimate(scenario: Scenario, summary: dict, fmu_dir: Path | None = None) -> dict | None:
    """{"method", "figures": {figure: estimated error}} (in the figures' units), or with
    "failed": the reason the coarser run gave none; None for a scenario without key figures."""
    if not scenario.analysis:
        return None
    if scenario.accuracy == "off":
        return {"method": None, "figures": {},
                "none": "experiment.accuracy = \"off\""}
    if scenario.mechanism.kinematic:
        return {"method": None, "figures": {},
                "none": "kinematic: the FMUs give exact positions at every communication point"}
    names = [k for k in scenario.mechanism.figures
             if isinstance(summary.get(k), (int, float))]
    if not names:                         # no figures (a narrowed record): nothing to estimate
        return None
    made = coarser(scenario)
    if made is None:
        return {"method": None, "figures": {},
                "none": "no coarser run to compare with (a run of under 4 steps, or the "
                        "adaptive master already at its loosest tolerance)"}
    coarse, divisor, how = made
    try:
        other = summarize(simulate(coarse, fmu_dir))
    except Diverged:
        return {"method": how, "figures": {},
                "failed": "it diverged: this step is near the coupling's stability limit"}
    except Error as err:
        return {"method": how, "figures": {}, "failed": " ".join(str(err).split())}
    return {"method": how,
            "figures": {k: SAFETY * abs(summary[k] - other[k]) / divisor for k in names
                        if isinstance(other.get(k), (int, float))}}


def beyond(summary: dict, accuracy: float) -> list[str]:
    """The figures whose estimated error exceeds `accuracy` (relative to the figure), or the
    reason there is no estimate; [] where the run is within it or was not estimated."""
    found = summary.get("coupling_error")
    if not found or found.get("none"):
        return []
    if found.get("failed"):
        return [f"no estimate: {found['method']} failed ({found['failed']})"]
    out = []
    for name, error in found["figures"].items():
        value = abs(summary[name])
        if error > accuracy * value or (value == 0.0 and error > 0.0):
            out.append(f"{name} = {summary[name]:.6g} ± {error:.3g} "
                       f"({100 * error / value if value else float('inf'):.2g} %)")
    return out
