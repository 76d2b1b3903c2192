"""`sewfmu export-fmu`: a scenario as one co-simulation FMU (fmpy's container FMU), run in fmpy
(FMI 2.0 and 3.0) and in fmuCheck (a host written in C), its punch figures against sewfmu's own
run of the scenario."""
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from sewfmu.scenarios.cosim.master import RunResult, run
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.interop.hosts import host_environment
from sewfmu.scenarios.runs.runner import summarize

pytestmark = pytest.mark.slow
FIGURES = ("contact_onset_deg", "contact_loss_deg", "F2_peak", "F2_weld_mean")


def _export(tmp_path: Path, *args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sewfmu", "export-fmu", *map(str, args)],
                          capture_output=True, text=True, timeout=300, cwd=tmp_path)


def _figures(columns: dict, time) -> dict:
    scenario = load("punch_drive")
    cols = {n: np.asarray(v, dtype=float) for n, v in columns.items() if n != "time"}
    return summarize(RunResult(scenario, np.asarray(time, dtype=float), cols, 0.0))


@pytest.fixture(scope="module")
def own_figures(fmu_paths, fmu3_paths):
    return summarize(run(load("punch_drive"), fmu_paths))


@pytest.mark.parametrize("fmi", [2, 3])
def test_the_punch_drive_as_one_fmu_runs_in_fmpy(tmp_path, own_figures, fmu_dir, fmi):
    target = tmp_path / "punch_drive.fmu"
    env_dir = {"SEWFMU_FMU_DIR": str(fmu_dir)}
    proc = subprocess.run([sys.executable, "-m", "sewfmu", "export-fmu", "punch_drive", "-o",
                           str(target), "--fmi", str(fmi)], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path, env={**os.environ, **env_dir})
    assert proc.returncode == 0, proc.stderr
    assert validate_fmu(str(target)) == []
    md = read_model_description(str(target))
    names = {v.name: v for v in md.modelVariables}
    assert names["shaft.omega0"].causality == "parameter" and names["shaft.omega0"].start
    assert names["punch.F2"].causality == "output" and names["shaft.phi"].unit == "rad"
    n, h = load("punch_drive").even_steps()
    assert float(md.defaultExperiment.stepSize) == h
    assert float(md.defaultExperiment.stopTime) == pytest.approx(n * h, rel=1e-15)
    result = simulate_fmu(str(target), output_interval=h)
    got = _figures({k: result[k] for k in result.dtype.names}, result["time"])
    for key in FIGURES:               # the same figures: measured identical, to the last digit
        assert got[key] == pytest.approx(own_figures[key], abs=1e-9), key
    # a parameter of an instance, set on the one FMU
    faster = simulate_fmu(str(target), output_interval=h, start_values={"shaft.omega0": 200.0})
    assert faster["shaft.omega"][-1] == pytest.approx(200.0)


FMUCHECK = os.environ.get("SEWFMU_FMUCHECK", "")


@pytest.mark.interop
@pytest.mark.skipif(not (FMUCHECK and os.access(FMUCHECK, os.X_OK)),
                    reason="SEWFMU_FMUCHECK does not name an executable fmuCheck")
def test_the_punch_drive_as_one_fmu_runs_in_fmucheck_and_exits_cleanly(tmp_path, own_figures,
                                                                        fmu_dir):
    target = tmp_path / "punch_drive.fmu"
    proc = subprocess.run([sys.executable, "-m", "sewfmu", "export-fmu", "punch_drive", "-o",
                           str(target)], capture_output=True, text=True, timeout=300,
                          cwd=tmp_path, env={**os.environ, "SEWFMU_FMU_DIR": str(fmu_dir)})
    assert proc.returncode == 0, proc.stderr
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")}
    env.update({k: v for k, v in host_environment().items() if k in ("LD_PRELOAD", "PYTHONHOME")})
    h = load("punch_drive").even_steps()[1]
    for attempt in range(3):                          # the exit must be clean every time
        out = tmp_path / f"out{attempt}.csv"
        check = subprocess.run([FMUCHECK, "-h", repr(h), "-n", "0", "-l", "3", "-o", str(out),
                                str(target)], env=env, cwd=tmp_path, capture_output=True,
                               text=True, timeout=300)
        text = check.stdout + check.stderr
        assert check.returncode == 0 and "0 Error(s)" in text, text[-2000:]
        assert "free()" not in text and "panic" not in text, text[-2000:]
    data = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
    got = _figures({k: data[k] for k in data.dtype.names}, data["time"])
    for key in FIGURES:               # the same figures: measured identical, to the last digit
        assert got[key] == pytest.approx(own_figures[key], abs=1e-9), key


def test_what_export_fmu_refuses_is_one_line(tmp_path):
    cases = [(["punch_split", "-o", tmp_path / "a.fmu"], "the adaptive master"),
             (["punch_drive", "-o", tmp_path / "a.zip"], "give a name ending in .fmu"),
             (["punch_drive", "-o", tmp_path / "no" / "a.fmu"], "does not exist")]
    for args, expected in cases:
        proc = _export(tmp_path, *args)
        assert proc.returncode == 1 and expected in proc.stderr, proc.stderr
        assert len(proc.stderr.strip().splitlines()) == 1
    assert not list(tmp_path.glob("*.fmu"))


def test_an_input_the_scenario_leaves_unconnected_is_an_input_of_the_one_fmu(tmp_path, fmu_dir):
    """The linkage's shaft inputs given values in the scenario (held): the exported FMU
    exposes them as inputs starting at those values, and runs as sewfmu does."""
    scenario = tmp_path / "held.toml"
    scenario.write_text(
        'description = "the punch behind a linkage held at a given shaft state"\n'
        'connections = ["linkage.xi -> punch.xi", "linkage.xi_dot -> punch.xi_dot", '
        '"linkage.xi_ddot -> punch.xi_ddot"]\n'
        "[experiment]\nstop_time = 0.01\nstep = 1e-4\n"
        "[instances.linkage]\nfmu = \"PunchLinkage\"\n"
        "parameters = { phi = 1.0, omega = 50.0, epsilon = 0.0 }\n"
        "[instances.punch]\nfmu = \"PunchContact\"\n")
    target = tmp_path / "held.fmu"
    env = {**os.environ, "SEWFMU_FMU_DIR": str(fmu_dir)}
    proc = subprocess.run([sys.executable, "-m", "sewfmu", "export-fmu", str(scenario), "-o",
                           str(target)], capture_output=True, text=True, timeout=300, env=env)
    assert proc.returncode == 0, proc.stderr
    inputs = {v.name: float(v.start) for v in read_model_description(str(target)).modelVariables
              if v.causality == "input"}
    assert inputs == {"linkage.phi": 1.0, "linkage.omega": 50.0, "linkage.epsilon": 0.0}
    got = simulate_fmu(str(target), output_interval=1e-4)
    own = run(load(str(scenario)), {p.stem: p for p in fmu_dir.glob("*.fmu")})
    for column in ("linkage.xi", "punch.y", "punch.F3"):
        assert np.array_equal(got[column], own[column]), column
