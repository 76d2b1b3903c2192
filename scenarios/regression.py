"""Regression references for every FMU, in the layout of the FMI Cross-Check repository, shipped
with the package (scenarios/regression_references/):

    <Model>/<Model>_ref.csv   the outputs (time and one column per output)
    <Model>/<Model>_in.csv    the inputs, where the FMU has any
    <Model>/<Model>_ref.opt   StartTime, StopTime, StepSize, RelTol

Each is made with the FMU's default parameters, so that anyone can reproduce it (fmuCheck does,
with the reference's input, step and stop time). Not to be confused with the monolithic solution
of the punch drive (scenarios/punch_monolithic.py), against which the physics is checked.

Each FMU runs alone in fmpy's simulate_fmu, its inputs from _in.csv. The inputs are made from the
models of the upstream mechanisms (the shaft at constant speed; the punch driven by the six-bar's
excitation; the carriage by the start-stop drive), so every case exercises the FMU where it works
hard. `sewfmu references --regenerate` rewrites them, deliberately; `sewfmu references` (and the
test suite) checks every FMU against them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from .sampling import sampled

REFERENCE_DIR = Path(__file__).resolve().parent / "regression_references"


@dataclass(frozen=True)
class Case:
    stop: float
    step: float
    inputs: Callable[[np.ndarray], dict[str, np.ndarray]] | None = None
    rel_tol: float = 1e-9


def _shaft(omega: float):
    return lambda t: {"phi": omega * t, "omega": np.full_like(t, omega),
                      "epsilon": np.zeros_like(t)}


def _punch_inputs(t):
    from ..components.punch_linkage import PunchLinkage
    e = sampled(PunchLinkage().motion, 200.0 * t, 200.0, 0.0)
    return {"xi": e.xi, "xi_dot": e.xi_dot, "xi_ddot": e.xi_ddot}


def _body_inputs(t):
    """The six-bar's excitation at ω = 200 s⁻¹ and a fabric force pulse of 25 N (a half sine)
    in the middle of each revolution."""
    pulse = np.clip(np.sin(400.0 * t - 1.0), 0.0, None)
    rate = np.where(pulse > 0.0, 400.0 * np.cos(400.0 * t - 1.0), 0.0)
    return {**_punch_inputs(t), "F2": 25.0 * pulse, "F2_dot": 25.0 * rate}


def _fabric_inputs(t):
    """A punch oscillating 2 mm about 0.5 mm below the surface at 80 Hz: in and out of contact."""
    w = 2 * math.pi * 80.0
    return {"y": 2e-3 * np.cos(w * t) - 0.5e-3, "y_dot": -2e-3 * w * np.sin(w * t),
            "y_ddot": -2e-3 * w * w * np.cos(w * t)}


def _carriage_inputs(t):
    from ..components.carriage import CarriageDrive
    omega = 1600 * 2 * math.pi / 60
    _, _, a, jerk = sampled(CarriageDrive().motion, omega * t, omega, 0.0)
    return {"a_base": a, "a_base_dot": jerk}


CASES: dict[str, Case] = {
    "MainShaft": Case(0.2, 1e-3),
    "PunchLinkage": Case(2 * math.pi / 100, 2.5e-4, _shaft(100.0)),
    "PunchContact": Case(4 * math.pi / 200, 2.5e-4, _punch_inputs),
    "PunchBody": Case(4 * math.pi / 200, 2.5e-4, _body_inputs),
    "Fabric": Case(0.025, 1e-4, _fabric_inputs),
    "TakeupLinkage": Case(2 * math.pi / 523.5987755982989, 2e-5, _shaft(523.5987755982989)),
    "FeedLinkage": Case(2 * math.pi / 303.5, 5e-5, _shaft(303.5)),
    "CarriageDrive": Case(2 * math.pi / 167.55160819145564, 1e-4, _shaft(167.55160819145564)),
    "CarriageModal": Case(3 * 60 / 1600, 1e-4, _carriage_inputs),
}


def _grid(case: Case) -> np.ndarray:
    n = int(round(case.stop / case.step))
    return np.arange(n + 1) * case.step


def _input_table(case: Case):
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

    from .master import FmuInstance, LogCollector, extracted_fmu

    case = CASES[name]
    unzip_dir, md = extracted_fmu(Path(path))
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    inputs = _input_table(case) if case.inputs else None
    unit = FmuInstance.for_fmu(name, unzip_dir, md, LogCollector())
    unit.prepare()
    unit.instantiate()
    try:
        return simulate_fmu(str(path), start_time=0.0, stop_time=case.stop,
                            output_interval=case.step, input=inputs, output=outputs,
                            validate=False, fmu_instance=unit.fmu, terminate=False)
    finally:
        unit.release()


def _write_csv(path: Path, table) -> None:
    names = table.dtype.names
    data = np.column_stack([table[n].astype(float) for n in names])
    np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.17g")


def regenerate(fmu_paths: dict[str, Path], folder: Path = REFERENCE_DIR) -> list[Path]:
    written = []
    for name, case in CASES.items():
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
    case = CASES[name]
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
