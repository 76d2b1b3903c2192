"""Regression references for every FMU, in the layout of the FMI Cross-Check repository, shipped
with the package (scenarios/regression_references/):

    <Model>/<Model>_ref.csv   the outputs (time and one column per output)
    <Model>/<Model>_in.csv    the inputs, where the FMU has any
    <Model>/<Model>_ref.opt   StartTime, StopTime, StepSize, RelTol

Each is made with the FMU's default parameters, so that anyone can reproduce it (fmuCheck does,
with the reference's input, step and stop time). Not to be confused with the monolithic solution
of the punch drive (scenarios/punch_monolithic.py), against which the physics is checked.

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

from .analyses import RegressionCase, mechanisms

REFERENCE_DIR = Path(__file__).resolve().parent / "regression_references"


def cases() -> dict[str, RegressionCase]:
    """Every FMU's regression case: the shared MainShaft's, and each mechanism's own (declared
    in its descriptor, scenarios/analyses/)."""
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


def simulate_case(name: str, path: Path):
    """The FMU (FMI 2.0 or 3.0) alone in fmpy's simulate_fmu with the case's inputs: a
    structured array (time, outputs). The instance is made and freed here, so that fmpy does not
    unload the library."""
    from fmpy import simulate_fmu

    from .fmi_calls import LogCollector
    from .instances import open_instance

    case = cases()[name]
    instance = open_instance(name, Path(path), LogCollector())
    outputs = [v.name for v in instance.md.modelVariables if v.causality == "output"]
    inputs = _input_table(case) if case.inputs else None
    instance.prepare()
    instance.instantiate()
    try:
        return simulate_fmu(str(path), start_time=0.0, stop_time=case.stop,
                            output_interval=case.step, input=inputs, output=outputs,
                            validate=False, fmu_instance=instance.fmu, terminate=False)
    finally:
        instance.release()


def _write_csv(path: Path, table) -> None:
    names = table.dtype.names
    data = np.column_stack([table[n].astype(float) for n in names])
    np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.17g")


def regenerate(fmu_paths: dict[str, Path], folder: Path = REFERENCE_DIR) -> list[Path]:
    written = []
    for name, case in cases().items():
        target = folder / name
        target.mkdir(parents=True, exist_ok=True)
        _write_csv(target / f"{name}_ref.csv", simulate_case(name, fmu_paths[name]))
        if case.inputs:
            _write_csv(target / f"{name}_in.csv", _input_table(case))
        (target / f"{name}_ref.opt").write_text(
            f"StartTime, 0.0\nStopTime, {case.stop!r}\nStepSize, {case.step!r}\n"
            f"RelTol, {case.rel_tol!r}\n")
        written.append(target)
    return written


def read_options(path: Path) -> dict[str, float]:
    return {k.strip(): float(v) for k, v in (line.split(",") for line in
                                             path.read_text().splitlines() if line.strip())}


def check(name: str, path: Path, folder: Path = REFERENCE_DIR) -> list[str]:
    """Differences of the FMU from its reference, one line each; empty if it matches."""
    target = folder / name
    options = read_options(target / f"{name}_ref.opt")
    ref = np.genfromtxt(target / f"{name}_ref.csv", delimiter=",", names=True)
    case = cases()[name]
    if (options["StopTime"], options["StepSize"]) != (case.stop, case.step):
        return [f"{name}: the reference was made for other run options; regenerate it"]
    got = simulate_case(name, path)
    problems = []
    for column in ref.dtype.names:
        if column not in got.dtype.names:
            problems.append(f"{name}: output {column} is gone")
            continue
        a, b = got[column].astype(float), ref[column]
        if a.shape != b.shape:
            problems.append(f"{name}: {column} has {len(a)} points, the reference {len(b)}")
            continue
        scale = max(np.abs(b).max(), 1e-300)
        worst = np.abs(a - b).max()
        if worst > options["RelTol"] * scale:
            k = int(np.argmax(np.abs(a - b)))
            problems.append(f"{name}: {column} differs by {worst:.3g} (at t = {got['time'][k]:g} "
                            f"s; allowed {options['RelTol']:g} of {scale:.3g})")
    return problems
