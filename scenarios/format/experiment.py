"""The experiment's keys, in one table: the scenario file's [experiment], `--set experiment.KEY`,
the provenance in summary.json, a sweep point's identity and sewfmu's SSP annotation all read
their keys here, so that a key added once is known everywhere (docs/scenarios.md lists them).

Each key is an attribute of the same name on a Scenario (scenarios/format/scenario.py).
"""
from __future__ import annotations

from dataclasses import dataclass

# which build of sewfmu's own FMUs a run uses (experiment.fmus): the Python FMUs (fmus/) or the
# compiled C ones of the same modelDescriptions (fmus/native/), which need no Python
FMU_KINDS = ("python", "native")


@dataclass(frozen=True)
class ExperimentKey:
    name: str
    meaning: str
    default: str            # as the documentation says it
    example: str            # a TOML value
    unit: str = ""          # a value may be given with a unit convertible to this one
    in_ssp: bool = False    # carried by sewfmu's SSP annotation (SSP 1.0 has no place for it)
    # decides the results (a sweep point's identity holds it); a key that only says how a run
    # is watched does not
    decides_results: bool = True


EXPERIMENT_KEYS: dict[str, ExperimentKey] = {key.name: key for key in (
    ExperimentKey("revolutions", "length of the run in turns of the shaft instance (exactly one "
                  "of revolutions and stop_time)", "none", "10", "rev"),
    ExperimentKey("stop_time", "length of the run (exactly one of revolutions and stop_time)",
                  "none", '0.5, or "500 ms"', "s"),
    ExperimentKey("shaft", "the MainShaft instance whose turns `revolutions` counts",
                  "the analysis's shaft, or the only MainShaft", '"shaft"'),
    ExperimentKey("step", "communication step; the run is a whole number of even steps no "
                  "longer than it (the adaptive master: its first step)", "required",
                  '2.5e-4, or "0.25 ms"', "s", in_ssp=True),
    ExperimentKey("master", "co-simulation algorithm: jacobi, gauss-seidel, iterative "
                  "(feedback loops, with rollback), adaptive (step size control)", '"jacobi"',
                  '"gauss-seidel"', in_ssp=True),
    ExperimentKey("tolerance", "iterative: relative agreement of the exchanged values; "
                  "adaptive: local error of the exchanged signals relative to their amplitude",
                  "iterative 1e-6, adaptive 1e-5", "1e-5", in_ssp=True),
    ExperimentKey("acceleration", "iterative master's acceleration of the passes: aitken, "
                  "iqn-ils, none", '"aitken"', '"iqn-ils"', in_ssp=True),
    ExperimentKey("record_every", "keep every n-th communication point (long runs); the last "
                  "revolution is always kept whole", "1", "10", in_ssp=True),
    ExperimentKey("fmi", "FMI version of sewfmu's FMUs the run uses: 2 or 3", "2", "3"),
    ExperimentKey("fmus", "which build of sewfmu's FMUs the run uses: python (fmus/) or "
                  "native (compiled C, fmus/native/: the same variables and numbers, no "
                  "Python needed)", '"python"', '"native"'),
    ExperimentKey("accuracy", "the coupling error a run's key figures may carry, relative to "
                  "each figure; estimated by the same run at twice the step (the adaptive "
                  "master: 8 times its tolerance); beyond it the run says so and fails; "
                  "\"off\": no estimate and no coarser run (half the work of a fixed-step run "
                  "less)", "0.05", '0.01, or "off"', in_ssp=True),
    ExperimentKey("accept_error", "true: a run beyond its accuracy succeeds all the same (its "
                  "estimate is still reported)", "false", "true", in_ssp=True),
    ExperimentKey("step_timeout", "the longest a communication step may take, in seconds of "
                  "wall time: a step still running after it (an FMU call that does not return) "
                  "stops the run with the instance, the FMI call and the time, and the record "
                  "so far is kept; \"off\": no limit", "none (off)", '30, or "2 min"', "s",
                  decides_results=False),
)}


def experiment_of(scenario) -> dict:
    """The value in this scenario (None where not given) of every experiment key that decides
    the results: what a run's provenance and a sweep point's identity hold (a limit on the wall
    time, which only stops a run, changes neither)."""
    return {name: getattr(scenario, name) for name, key in EXPERIMENT_KEYS.items()
            if key.decides_results}


def ssp_settings(scenario, step: float) -> dict:
    """What sewfmu's SSP annotation carries: the step, the master, the settings the master
    uses (a tolerance or an acceleration it ignores is left out), how the records are thinned
    and the accuracy the run's figures are held to."""
    used = {"step": step, "master": scenario.master, **scenario.master_settings(),
            "record_every": scenario.record_every, "accuracy": scenario.accuracy,
            "accept_error": scenario.accept_error}
    return {name: used[name] for name, key in EXPERIMENT_KEYS.items()
            if key.in_ssp and name in used}
