"""Every FMU, FMI 2.0 and 3.0, in fmusim (the Modelica Reference-FMUs' simulator, written in C;
docs/fmi.md says how it was built here), with an embedded Python whose home holds only the
standard library: each reproduces its regression reference (the run sewfmu's own host made),
and the linkage alone follows the six-bar's kinematics computed by the model in this process.

fmusim is taken from SEWFMU_FMUSIM, else from PATH; without it these tests skip."""
import math
import os
import shutil
import subprocess

import numpy as np
import pytest

from sewfmu.components.punch_linkage import PunchLinkage
from sewfmu.components.registry import FMUS
from sewfmu.scenarios.interop.hosts import host_environment
from tests.host_references import assert_reproduces, reference_case

FMUSIM = os.environ.get("SEWFMU_FMUSIM") or shutil.which("fmusim") or ""
pytestmark = [pytest.mark.slow, pytest.mark.interop, pytest.mark.skipif(
    not os.access(FMUSIM, os.X_OK),
    reason="no fmusim (Reference-FMUs' simulator, a host written in C): set SEWFMU_FMUSIM or "
           "put it on PATH (docs/fmi.md: how to build it)")]


def _fmusim(fmu, out, home, *options) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")}
    env.update(LD_PRELOAD=host_environment()["LD_PRELOAD"], PYTHONHOME=str(home))
    return subprocess.run([FMUSIM, "--interface-type", "cs", *options, "--output-file",
                           str(out), str(fmu)], env=env, cwd=out.parent, capture_output=True,
                          text=True, timeout=300)


def _read(path):
    # fmusim quotes its column names
    data = np.genfromtxt(path, delimiter=",", names=True, deletechars='"')
    return {name.strip('"'): data[name] for name in data.dtype.names}


@pytest.mark.parametrize("name", list(FMUS))
def test_fmusim_reproduces_the_regression_reference(fmus, stdlib_home, tmp_path, name):
    options, inputs, ref = reference_case(name)
    args = ["--stop-time", repr(options["StopTime"]), "--output-interval",
            repr(options["StepSize"])]
    if inputs is not None:
        args += ["--input-file", str(inputs)]
    out = tmp_path / f"{name}.csv"
    proc = _fmusim(fmus[name], out, stdlib_home, *args)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-2000:]
    got = _read(out)
    n = len(got["time"])
    # where the stop time is not a whole number of steps, fmusim ends at the last whole one;
    # the reference takes a last, shorter step
    short_last = ref["time"][-1] - ref["time"][-2] < options["StepSize"] * (1 - 1e-9)
    assert n == len(ref) or (n == len(ref) - 1 and short_last)
    assert np.allclose(got["time"], ref["time"][:n], rtol=1e-12, atol=0)
    assert_reproduces(got, ref, options["RelTol"], rows=n)


def test_the_linkage_alone_follows_the_six_bar(fmus, stdlib_home, tmp_path):
    """No inputs: the FMU holds its start values (φ = 0, ω = 100 rad/s) and extrapolates them
    over one revolution, so the slider's excitation is the model's at φ = ω·t."""
    out = tmp_path / "PunchLinkage.csv"
    proc = _fmusim(fmus["PunchLinkage"], out, stdlib_home, "--stop-time",
                   repr(2 * math.pi / 100.0), "--output-interval", "2.5e-4")
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-2000:]
    data = _read(out)
    model = PunchLinkage()
    expected = [model.motion(100.0 * t, 100.0, 0.0).xi for t in data["time"]]
    assert np.allclose(data["xi"], expected, rtol=0, atol=1e-12)
    assert np.ptp(data["xi"]) > 4.5e-3                 # the whole stroke is run through
