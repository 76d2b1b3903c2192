"""Run an exported scenario (.ssp) in another FMI host: libcosim (libcosimpy) or ecos (ecospy).

Each host runs in a child process, which writes the recorded columns as CSV and leaves with
os._exit: those hosts free and unload the FMU libraries as they shut down, which pythonfmu's
binary does not survive inside a Python process (see README). The parent reads the CSV back as a
RunResult, so `sewfmu crosscheck` summarizes it exactly like sewfmu's own run.

    python -m sewfmu.scenarios.interop.hosts libcosim|ecos SSP STEP STOP RECORD_JSON OUT_CSV
"""
from __future__ import annotations

import ctypes
import importlib.util
import json
import os
import re
import subprocess
import sys
import sysconfig
import time
from pathlib import Path

import numpy as np

from sewfmu.errors import Error
from sewfmu.extras import require
from sewfmu.processes import python_command
from sewfmu.scenarios.interop.ssp_export import PARAMETER_SET

HOSTS = ("libcosim", "ecos", "ecos-cli")


class HostError(Error, RuntimeError):
    """The other host could not run the scenario."""


def _run_libcosim(ssp: str, step: float, stop: float, record: list[str]):
    require("libcosimpy", "a run in libcosim")        # or one line naming the extra
    from libcosimpy.CosimEnums import CosimVariableType  # optional extra (interop)
    from libcosimpy.CosimExecution import CosimExecution  # optional extra (interop)
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level  # optional extra (interop)
    from libcosimpy.CosimObserver import CosimObserver  # optional extra (interop)

    log_output_level(CosimLogLevel.WARNING)
    step_ns = round(step * 1e9)            # libcosim counts time in whole nanoseconds
    try:
        execution = CosimExecution.from_ssp_file(ssp, step_size=step_ns)
    except AssertionError:          # libcosimpy asserts; libcosim's own message says why
        from libcosimpy._internal import get_last_error_message  # optional extra (interop)
        raise HostError(f"libcosim could not load the system: {get_last_error_message()}") \
            from None
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
        if not execution.step():
            raise HostError(f"libcosim could not take the step to t = {(k + 1) * step_ns * 1e-9:g} "
                            f"s: an FMU refused it (fmi2Discard or fmi2Error)")
        row = [(k + 1) * step_ns * 1e-9]
        for index, ref, boolean in readers:
            if boolean:
                row.append(float(observer.last_boolean_values(index, [ref])[0]))
            else:
                row.append(observer.last_real_values(index, [ref])[0])
        _refuse_non_finite(row, record, "libcosim")
        rows.append(row)
    return rows


def _refuse_non_finite(row: list[float], record: list[str], host: str) -> None:
    """A host that goes on after an FMU refused its step (ecos does) records NaN: stop there."""
    bad = [name for name, value in zip(record, row[1:]) if not np.isfinite(value)]
    if bad:
        raise HostError(f"{host}: {bad[0]} is {row[1 + record.index(bad[0])]} at t = {row[0]:g} "
                        f"s (the FMU refused its step or could not compute it: see its log)")


def _load_tbb() -> None:
    """ecospy's library needs libtbb.so.12: the `tbb` wheel (interop extra) puts it in the
    environment's lib/, which is not on the loader's path; load it globally first."""
    tbb = Path(sys.prefix) / "lib" / "libtbb.so.12"
    if not tbb.exists():
        raise HostError(f"ecos needs libtbb.so.12; not found at {tbb}: pip install -e '.[interop]'")
    ctypes.CDLL(str(tbb), mode=ctypes.RTLD_GLOBAL)


def _run_ecos(ssp: str, step: float, stop: float, record: list[str]):

    _load_tbb()                                       # before ecospy: its library needs it
    require("ecospy", "a run in ecos")                # or one line naming the extra
    from ecospy import EcosSimulation  # optional extra (interop)

    sim = EcosSimulation(step_size=step, ssp_path=ssp)
    sim.init(parameter_set=PARAMETER_SET)     # ecos applies a parameter set only when named
    getters = []
    for column in record:
        inst, var = column.split(".", 1)
        identifier = f"{inst}::{var}"
        getters.append((sim.get_bool if var == "contact" else sim.get_real, identifier))
    n_steps = int(np.ceil(stop / step - 1e-9))
    rows = []
    for k in range(n_steps):
        sim.step()
        rows.append([sim.get_time()] + [float(get(identifier)) for get, identifier in getters])
        _refuse_non_finite(rows[-1], record, "ecos")
    return rows


# --- ecos out of process: the `ecos` command-line tool, a host that is not Python ------------
def ecos_binary(name: str = "ecos") -> Path:
    """ecospy's `ecos` or `proxyfmu` binary, with its run bit set (the wheel ships it without)."""
    spec = importlib.util.find_spec("ecospy")
    if spec is None or not spec.submodule_search_locations:
        raise HostError("ecospy is not installed: pip install -e '.[interop]'")
    path = Path(list(spec.submodule_search_locations)[0]) / "binaries" / name
    if not path.exists():
        raise HostError(f"ecospy has no {name} binary for this platform ({path})")
    if not os.access(path, os.X_OK):
        path.chmod(path.stat().st_mode | 0o111)
    return path


def host_environment() -> dict[str, str]:
    """What a host that is not a Python process needs to run sewfmu's FMUs: pythonfmu's binary
    is not linked to libpython, so the Python library must be preloaded, and the embedded
    interpreter must find its standard library (PYTHONHOME); the FMUs import nothing else (they
    carry their own code and pythonfmu's). LD_LIBRARY_PATH lets ecos find libtbb.so.12."""
    libdir, library = sysconfig.get_config_var("LIBDIR"), sysconfig.get_config_var("LDLIBRARY")
    return {"LD_PRELOAD": os.path.join(libdir or "", library or ""),
            "PYTHONHOME": sys.base_prefix,
            "LD_LIBRARY_PATH": str(Path(sys.prefix) / "lib")}


# the Python versions whose home and libpython the FMUs run with (pythonfmu's binary uses the
# stable parts of the C API; tried with each)
HOST_PYTHONS = ("3.10", "3.11", "3.12", "3.13")


def check_host_environment(env: dict[str, str]) -> list[str]:
    """What is missing from `env` for a non-Python host; empty if it is complete. Any Python of
    HOST_PYTHONS will do, if the preloaded libpython and the home are the same version."""
    problems = []
    preload = env.get("LD_PRELOAD", "")
    libs = [p for p in preload.replace(":", " ").split() if "libpython" in Path(p).name]
    lib_version = None
    if not libs:
        problems.append("LD_PRELOAD does not name libpython3.x.so (the FMUs' binary needs the "
                        "Python symbols; without it the host dies with a segmentation fault)")
    elif not all(Path(p).exists() for p in libs):
        problems.append(f"LD_PRELOAD names {libs[0]}, which does not exist (a Python built "
                        f"without --enable-shared has no libpython to preload)")
    else:
        found = re.search(r"libpython(3\.\d+)", Path(libs[0]).name)
        lib_version = found.group(1) if found else None
        if lib_version not in HOST_PYTHONS:
            problems.append(f"LD_PRELOAD names {Path(libs[0]).name}: the FMUs run with Python "
                            f"{', '.join(HOST_PYTHONS)}")
    home = env.get("PYTHONHOME")
    homes = [v for v in HOST_PYTHONS if home and (Path(home) / "lib" / f"python{v}" /
                                                  "os.py").exists()]
    if not homes:
        problems.append(f"PYTHONHOME is not set to a Python installation ({', '.join(HOST_PYTHONS)})"
                        f" whose lib/python3.x holds the standard library the embedded "
                        f"interpreter needs")
    elif lib_version in HOST_PYTHONS and lib_version not in homes:
        problems.append(f"PYTHONHOME {home} holds Python {homes[0]}'s standard library, "
                        f"LD_PRELOAD Python {lib_version}'s library: give both of one version")
    return problems


def run_ecos_cli(ssp: Path, scenario, record: list[str], out_dir: Path, timeout: float = 600.0):
    """Run the .ssp with the `ecos` command-line tool; return (time, columns, wall)."""

    env = {**os.environ, **host_environment()}
    problems = check_host_environment(env)
    if problems:
        raise HostError("ecos-cli cannot host the FMUs: " + "; ".join(problems))
    out_dir = Path(out_dir)
    work = out_dir / "ecos-cli"
    work.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    proc = subprocess.run([str(ecos_binary()), "simulate", "--path", str(Path(ssp).resolve()),
                           "--stepSize", repr(scenario.even_steps()[1]),
                           # one step beyond: the caller cuts the record at the stop time exactly
                           "--stopTime", repr(scenario.end_time() + scenario.even_steps()[1]),
                           "--parameterSet", PARAMETER_SET, "--noParallel", "-l", "warn"],
                          cwd=work, env=env, capture_output=True, text=True, timeout=timeout)
    wall = time.perf_counter() - started
    csvs = sorted(work.glob("*.csv"))
    if proc.returncode != 0 or not csvs:
        tail = " ".join((proc.stderr or proc.stdout).strip().splitlines()[-2:])
        raise HostError(f"ecos-cli exited with status {proc.returncode}: {tail or 'no message'}")
    return (*_read_ecos_csv(csvs[-1], record), wall)


def _read_ecos_csv(path: Path, record: list[str]):
    """ecos's CSV: `iterations, time, inst::var[TYPE], ...`; values as written (6 decimals)."""
    with open(path) as f:
        header = [h.strip() for h in f.readline().split(",")]
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    index = {h.split("[")[0].replace("::", "."): j for j, h in enumerate(header)}
    missing = [c for c in record if c not in index]
    if missing:
        raise HostError(f"ecos-cli wrote no column for {', '.join(missing)}")
    return data[:, header.index("time")], {c: data[:, index[c]] for c in record}


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

    if host not in HOSTS:
        raise HostError(f"unknown host {host!r} (hosts: {', '.join(HOSTS)})")
    if host == "ecos-cli":
        return run_ecos_cli(ssp, scenario, record, Path(out_csv).parent, timeout)
    out_csv = Path(out_csv)
    out_csv.parent.mkdir(parents=True, exist_ok=True)
    error_file = Path(str(out_csv) + ".error")
    error_file.unlink(missing_ok=True)
    started = time.perf_counter()
    # -P: python -m would put the current folder first on sys.path (sewfmu/processes.py)
    proc = subprocess.run(python_command("-m", "sewfmu.scenarios.interop.hosts", host, str(ssp),
                                         repr(scenario.even_steps()[1]),
                                         repr(scenario.end_time()), json.dumps(record),
                                         str(out_csv)),
                          capture_output=True, text=True, timeout=timeout)
    wall = time.perf_counter() - started
    if error_file.exists():
        # the FMU's own words, as the host logged them (libcosim: "... logStatusError] text")
        said = [line.rsplit("] ", 1)[-1] for line in proc.stderr.splitlines()
                if "logStatusError" in line]
        cause = f"; the FMU said: {said[0]}" if said else ""
        raise HostError(f"{host}: {error_file.read_text().strip()}{cause}")
    if proc.returncode != 0:
        tail = " ".join((proc.stderr or proc.stdout).strip().splitlines()[-2:])
        raise HostError(f"{host} exited with status {proc.returncode}: {tail or 'no message'}")
    data = np.loadtxt(out_csv, delimiter=",", skiprows=1, ndmin=2)
    return data[:, 0], {name: data[:, j + 1] for j, name in enumerate(record)}, wall


if __name__ == "__main__":
    child_main(sys.argv[1:])
