"""Bounded work per doStep: the wall time of one doStep of PunchContact (the one FMU whose work
grows with the step: its switch search) against the step size, through fmpy, from 0.1 ms to
10^6 s, and the same for the other FMUs at a short and a huge step. A step is either taken, in a
time proportional to what it simulates, or refused at once (fmi2Discard, with the reason).

    .venv/bin/python bench/step_work.py
"""
from __future__ import annotations

import time
from pathlib import Path

from fmpy.fmi1 import FMICallException

from sewfmu.components.registry import FMUS
from sewfmu.scenarios.cosim.fmi_calls import LogCollector
from sewfmu.scenarios.cosim.instances import open_instance
from sewfmu.scenarios.fmu_build.up_to_date import ensure_built


def one_step(path: Path, name: str, h: float, **values) -> tuple[str, float, str]:
    """A fresh instance, `values` set during initialization, one doStep(0, h), timed."""
    log = LogCollector()
    instance = open_instance(name, path, log)
    instance.prepare()
    instance.instantiate()
    fmu = instance.fmu
    instance.enter_initialization(stop=h)
    for key, value in values.items():
        instance.set_parameter(instance.variables[key], value)
    instance.exit_initialization()
    started = time.perf_counter()
    try:
        fmu.doStep(0.0, h)
        status = "OK"
    except FMICallException:
        status = "Discard"
    wall = time.perf_counter() - started
    reason = log.lines[-1].split(": ", 1)[-1] if status != "OK" else ""
    instance.release()
    return status, wall, reason


def main() -> None:
    paths = ensure_built(FMUS)
    rest = {"xi": 4.5e-3, "xi_dot": 0.0, "xi_ddot": 0.0}
    print("1. PunchContact, one doStep from rest on a still slider (default parameters)")
    print("| step [s] | status | wall [ms] | wall per simulated second [ms/s] |")
    print("|---|---|---|---|")
    for h in (1e-4, 1e-3, 1e-2, 1e-1, 1.0, 2.0, 1e3, 1e6):
        status, wall, reason = one_step(paths["PunchContact"], "punch", h, **rest)
        print(f"| {h:g} | {status} | {wall * 1e3:.2f} | {wall * 1e3 / h:.3g} |")
        if reason:
            print(f"|  | reason: {reason} | | |")
    print()
    print("2. extreme but valid parameters (m = 1e-9 kg, c3 = 1e9 N/m) at the default step")
    status, wall, reason = one_step(paths["PunchContact"], "punch", 2.5e-4, m=1e-9, c3=1e9, **rest)
    print(f"   {status} in {wall * 1e3:.2f} ms: {reason}")
    print()
    print("3. every other FMU: one step of 1e-4 s and of 1e6 s")
    print("| FMU | 1e-4 s: status, wall [ms] | 1e6 s: status, wall [ms] |")
    print("|---|---|---|")
    for name in FMUS:
        if name == "PunchContact":
            continue
        cells = []
        for h in (1e-4, 1e6):
            status, wall, _ = one_step(paths[name], name, h)
            cells.append(f"{status}, {wall * 1e3:.2f}")
        print(f"| {name} | {cells[0]} | {cells[1]} |")


if __name__ == "__main__":
    main()
