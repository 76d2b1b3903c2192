"""Every FMU in a host written in C, the Modelica FMU Compliance Checker (fmuCheck), with an
embedded Python whose home holds only the standard library: the checks pass, the mechanism runs
alone over its DefaultExperiment, the regression references are reproduced, and the process exits
cleanly, each time.

The checker's path comes from SEWFMU_FMUCHECK (.ci/run sets it); without it these tests skip.
"""
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sewfmu.components.punch_linkage import PunchLinkage
from sewfmu.components.registry import FMUS
from sewfmu.scenarios.interop.hosts import host_environment
from tests.host_references import assert_reproduces, reference_case

FMUCHECK = os.environ.get("SEWFMU_FMUCHECK", "")
pytestmark = [pytest.mark.slow, pytest.mark.interop, pytest.mark.skipif(
    not (FMUCHECK and os.access(FMUCHECK, os.X_OK)),
    reason="SEWFMU_FMUCHECK does not name an executable fmuCheck (the Modelica FMU Compliance "
           "Checker, a host written in C): set it to run the FMUs outside Python")]


def _env(home: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")}
    env.update(LD_PRELOAD=host_environment()["LD_PRELOAD"], PYTHONHOME=str(home))
    return env


def _fmucheck(fmu: Path, out: Path, home: Path, *options: str) -> subprocess.CompletedProcess:
    return subprocess.run([FMUCHECK, *options, "-o", str(out), str(fmu)], env=_env(home),
                          cwd=out.parent, capture_output=True, text=True, timeout=300)


def test_the_home_holds_only_the_standard_library(stdlib_home):
    probe = ("import json, math, xml.etree.ElementTree\ntry:\n import numpy\n"
             "except ImportError:\n print('no numpy')")
    proc = subprocess.run([sys.executable, "-S", "-c", probe], env=_env(stdlib_home),
                          capture_output=True, text=True, timeout=60)
    assert proc.stdout.strip() == "no numpy", proc.stderr


@pytest.mark.parametrize("name", list(FMUS))
def test_each_fmu_runs_its_default_experiment_and_exits_cleanly(fmu_paths, stdlib_home, tmp_path,
                                                                name):
    for run in range(2):                          # repeatedly: the exit must be clean each time
        out = tmp_path / f"{name}_{run}.csv"
        proc = _fmucheck(fmu_paths[name], out, stdlib_home, "-l", "3")
        text = proc.stdout + proc.stderr
        assert proc.returncode == 0, text[-2000:]
        # (the checker's one warning: the DefaultExperiment gives no tolerance, as these FMUs
        # integrate exactly and have none)
        assert "0 Error(s)" in text and "0 warning(s) and error(s)" in text, text[-2000:]
        assert "free()" not in text and "Fatal" not in text, text[-2000:]
        data = np.genfromtxt(out, delimiter=",", names=True)
        assert len(data) > 50 and all(np.isfinite(data[c]).all() for c in data.dtype.names)


def test_the_linkage_alone_turns_through_one_revolution_at_its_start_speed(fmu_paths,
                                                                            stdlib_home, tmp_path):
    """No inputs set: the FMU extrapolates its start values (φ = 0, ω = 100 rad/s) over its
    DefaultExperiment, one revolution: the slider's excitation at φ = ω·t, from the model."""
    out = tmp_path / "PunchLinkage.csv"
    assert _fmucheck(fmu_paths["PunchLinkage"], out, stdlib_home).returncode == 0
    data = np.genfromtxt(out, delimiter=",", names=True)
    assert data["time"][-1] == pytest.approx(2 * math.pi / 100.0)
    model = PunchLinkage()
    expected = [model.motion(100.0 * t, 100.0, 0.0).xi for t in data["time"]]
    assert np.allclose(data["xi"], expected, rtol=0, atol=1e-12)
    assert np.ptp(data["xi"]) > 4.5e-3                # the whole stroke is run through


@pytest.mark.parametrize("name", list(FMUS))
def test_fmucheck_reproduces_the_regression_reference(fmu_paths, stdlib_home, tmp_path, name):
    options, inputs, ref = reference_case(name)
    args = ["-h", repr(options["StepSize"]), "-s", repr(options["StopTime"]), "-n", "0"]
    if inputs is not None:
        args += ["-i", str(inputs)]
    out = tmp_path / f"{name}.csv"
    proc = _fmucheck(fmu_paths[name], out, stdlib_home, *args)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-2000:]
    got = np.genfromtxt(out, delimiter=",", names=True)
    assert len(got) == len(ref)
    assert_reproduces(got, ref, options["RelTol"])
