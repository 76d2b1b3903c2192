"""Run an exported scenario (.ssp) in another FMI host: libcosim (libcosimpy) or ecos (ecospy).

Each host runs in a child process, which writes the recorded columns as CSV and leaves with
os._exit: those hosts free and unload the FMU libraries as they shut down, which pythonfmu's
binary does not survive inside a Python process (see README). The parent reads the CSV back as a
RunResult, so `sewfmu crosscheck` summarizes it exactly like sewfmu's own run.

    python -m scenarios.hosts libcosim|ecos SSP STEP STOP RECORD_JSON OUT_CSV
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HOSTS = ("libcosim", "ecos")


class HostError(RuntimeError):
    """The other host could not run the scenario."""


def _run_libcosim(ssp: str, step: float, stop: float, record: list[str]):
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)
    step_ns = round(step * 1e9)            # libcosim counts time in whole nanoseconds
    execution = CosimExecution.from_ssp_file(ssp, step_size=step_ns)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    readers = []
    for column in record:
        inst, var = column.split(".", 1)
        index = execution.slave_index_from_instance_name(inst)
        variables = {_text(v.name): v for v in execution.slave_variables(index)}
        v = variables[var]
        boolean = v.type == CosimVariableType.BOOLEAN.value
        readers.append((index, v.reference, boolean))
    n_steps = int(np.ceil(stop / step - 1e-9))
    rows = []
    for k in range(n_steps):
        execution.step()
        row = [(k + 1) * step_ns * 1e-9]
        for index, ref, boolean in readers:
            if boolean:
                row.append(float(observer.last_boolean_values(index, [ref])[0]))
            else:
                row.append(observer.last_real_values(index, [ref])[0])
        rows.append(row)
    return rows


def _run_ecos(ssp: str, step: float, stop: float, record: list[str]):
    from ecospy import EcosSimulation, EcosSimulationStructure  # noqa: F401 (import check)
    raise HostError("ecos: not supported yet")


def _text(value) -> str:
    return value.decode() if isinstance(value, bytes) else str(value)


def child_main(argv: list[str]) -> None:
    host, ssp, step, stop, record, out = argv
    record_list = json.loads(record)
    try:
        rows = {"libcosim": _run_libcosim, "ecos": _run_ecos}[host](ssp, float(step), float(stop),
                                                                    record_list)
        header = ",".join(["time"] + record_list)
        np.savetxt(out, np.array(rows), delimiter=",", header=header, comments="", fmt="%.17g")
        code = 0
    except Exception as err:                  # reported by the parent in one line
        Path(out + ".error").write_text(f"{type(err).__name__}: {err}")
        code = 3
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)                            # no host teardown: see the module docstring


def run_in_host(host: str, ssp: Path, scenario, record: list[str], out_csv: Path,
                timeout: float = 600.0):
    """Run the .ssp in the other host (child process); return (time, columns, wall)."""
    from .master import stop_time

    if host not in HOSTS:
        raise HostError(f"unknown host {host!r} (hosts: {', '.join(HOSTS)})")
    out_csv = Path(out_csv)
    out_csv.parent.mkdir(parents=True, exist_ok=True)
    error_file = Path(str(out_csv) + ".error")
    error_file.unlink(missing_ok=True)
    started = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "scenarios.hosts", host, str(ssp),
                           repr(scenario.step), repr(stop_time(scenario)), json.dumps(record),
                           str(out_csv)], capture_output=True, text=True, timeout=timeout)
    wall = time.perf_counter() - started
    if error_file.exists():
        raise HostError(f"{host}: {error_file.read_text().strip()}")
    if proc.returncode != 0:
        tail = " ".join((proc.stderr or proc.stdout).strip().splitlines()[-2:])
        raise HostError(f"{host} exited with status {proc.returncode}: {tail or 'no message'}")
    data = np.loadtxt(out_csv, delimiter=",", skiprows=1, ndmin=2)
    return data[:, 0], {name: data[:, j + 1] for j, name in enumerate(record)}, wall


if __name__ == "__main__":
    child_main(sys.argv[1:])
