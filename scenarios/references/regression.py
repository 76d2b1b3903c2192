"""Regression references for every FMU, in the layout of the FMI Cross-Check repository, shipped
with the package (scenarios/references/regression_references/):

    <Model>/<Model>_ref.csv   the outputs (time and one column per output)
    <Model>/<Model>_in.csv    the inputs, where the FMU has any
    <Model>/<Model>_ref.opt   StartTime, StopTime, StepSize, RelTol

Each is made with the FMU's default parameters, so that anyone can reproduce it (fmuCheck does,
with the reference's input, step and stop time). Not to be confused with the monolithic solution
of the punch drive (scenarios/mechanisms/punch.py), against which the physics is checked.

Each FMU runs alone in fmpy's simulate_fmu, its inputs from _in.csv; its case (stop time, step,
inputs) is declared by its mechanism's descriptor. The inputs are made from the
models of the upstream mechanisms (the shaft at constant speed; the punch driven by the six-bar's
excitation; the carriage by the start-stop drive), so every case exercises the FMU where it works
hard. `sewfmu references --regenerate` rewrites them, deliberately; `sewfmu references` (and the
test suite) checks every FMU against them.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from sewfmu.scenarios.mechanisms import mechanisms
from sewfmu.scenarios.mechanisms.base import RegressionCase
from sewfmu.scenarios.references import fmu_reference
from sewfmu.scenarios.references.fmu_reference import Experiment

REFERENCE_DIR = Path(__file__).resolve().parent / "regression_references"


def cases() -> dict[str, RegressionCase]:
    """Every FMU's regression case: the shared MainShaft's, and each mechanism's own (declared
    in its module, scenarios/mechanisms/)."""
    found = {"MainShaft": RegressionCase(0.2, 1e-3)}
    for mechanism in mechanisms().values():
        found.update(mechanism.regression)
    return found


def _grid(case: RegressionCase) -> np.ndarray:
    n = int(round(case.stop / case.step))
    return np.arange(n + 1) * case.step


def _input_table(case: RegressionCase):
    t = _grid(case)
    signals = case.inputs(t)
    table = np.zeros(len(t), dtype=[("time", float)] + [(k, float) for k in signals])
    table["time"] = t
    for k, v in signals.items():
        table[k] = v
    return table


def experiment_of(case: RegressionCase) -> Experiment:
    return Experiment(0.0, case.stop, case.step, _input_table(case) if case.inputs else None,
                      case.rel_tol)


def simulate_case(name: str, path: Path) -> dict:
    """The FMU (FMI 2.0 or 3.0) alone in fmpy's simulate_fmu with the case's inputs:
    {"time": ..., output: ...}."""
    return fmu_reference.simulate(Path(path), experiment_of(cases()[name]))


def regenerate(fmu_paths: dict[str, Path], folder: Path = REFERENCE_DIR) -> list[Path]:
    return [fmu_reference.record(Path(fmu_paths[name]), folder, experiment_of(case), model=name)
            for name, case in cases().items()]


def check(name: str, path: Path, folder: Path = REFERENCE_DIR, rtol: float | None = None,
          atol: float | None = None) -> list[str]:
    """Differences of the FMU from its reference, one line each; empty if it matches."""
    reference = fmu_reference.read_cross_check(folder, name)
    if reference is None:
        return [f"{name}: no reference in {folder}"]
    case = cases()[name]
    if (reference.experiment.stop, reference.experiment.step) != (case.stop, case.step):
        return [f"{name}: the reference was made for other run options; regenerate it"]
    atol = fmu_reference.DEFAULT_ATOL if atol is None else atol
    return [str(d) for d in fmu_reference.check(Path(path), reference, rtol, atol)]
