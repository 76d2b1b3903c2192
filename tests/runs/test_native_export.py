"""export-fmu over native FMUs (experiment.fmus = "native"): the container (fmpy's container FMU)
carries only the native FMUs (no Python file anywhere, no libpython among any binary's needs),
and a host written in C (fmuCheck) runs it with no Python in its environment at all, with the
numbers of sewfmu's own run over the same FMUs. FMI 2.0 and 3.0 containers; fmuCheck runs the
FMI 2.0 one (it hosts no FMI 3.0). Slow: it builds the punch drive's native FMUs."""
import os
import shutil
import subprocess
import zipfile

import numpy as np
import pytest

import sewfmu
from sewfmu.cli import main

FMUCHECK = os.environ.get("SEWFMU_FMUCHECK", "")
PUNCH = {"MainShaft", "PunchLinkage", "PunchContact"}
SHORT = ["--set", "experiment.fmus=native", "--set", "experiment.revolutions=2"]

pytestmark = pytest.mark.slow


@pytest.fixture(autouse=True)
def _session_fmus(fmu_dir, fmu3_dir, monkeypatch):
    pytest.importorskip("sewfmu.scenarios.fmu_build.native")
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))     # the natives made from this session's


def _exported(tmp_path, fmi: int):
    out = tmp_path / f"punch_native_{fmi}.fmu"
    assert main(["export-fmu", "punch_drive", "-o", str(out), "--fmi", str(fmi), *SHORT]) == 0
    return out


@pytest.mark.parametrize("fmi", [2, 3])
def test_the_container_carries_only_native_fmus(tmp_path, fmi):
    out = _exported(tmp_path, fmi)
    with zipfile.ZipFile(out) as archive:
        names = archive.namelist()
        inside = {n.split("/")[1] for n in names if n.startswith("resources/") and n.count("/") > 1}
        assert inside == PUNCH
        assert not [n for n in names if n.endswith((".py", ".pyc"))], "Python code inside"
        assert not [n for n in names if "python" in n.lower()], "pythonfmu inside"
        for name in PUNCH:                  # each one's sources, and its binaries for both
            platforms = {n.split("/")[3] for n in names
                         if n.startswith(f"resources/{name}/binaries/") and n.count("/") == 4}
            assert platforms == ({"linux64", "win64"} if fmi == 2 else
                                 {"x86_64-linux", "x86_64-windows"}), (name, platforms)
            assert any(n.startswith(f"resources/{name}/sources/") for n in names)
        page = archive.read("documentation/index.html").decode()
        assert "needs no Python" in page
        linux = [n for n in names if n.endswith(".so")]
        archive.extractall(tmp_path / "tree", members=linux)
    readelf = shutil.which("readelf")
    if readelf:
        for name in linux:
            needs = subprocess.run([readelf, "-d", str(tmp_path / "tree" / name)],
                                   capture_output=True, text=True, check=True).stdout
            assert "libpython" not in needs, (name, needs)


@pytest.mark.interop
@pytest.mark.skipif(not (FMUCHECK and os.access(FMUCHECK, os.X_OK)),
                    reason="SEWFMU_FMUCHECK does not name an executable fmuCheck (a host "
                           "written in C): set it to run the container outside Python")
def test_a_host_with_no_python_runs_the_container_with_sewfmus_numbers(tmp_path):
    out = _exported(tmp_path, 2)
    with zipfile.ZipFile(out) as archive:
        xml = archive.read("modelDescription.xml").decode()
    step = xml.split('stepSize="')[1].split('"')[0]
    stop = xml.split('stopTime="')[1].split('"')[0]
    csv = tmp_path / "out.csv"
    # no environment at all: no PYTHONHOME, no LD_PRELOAD, no PATH
    proc = subprocess.run([FMUCHECK, "-l", "3", "-h", step, "-s", stop, "-n", "0", "-o",
                           str(csv), "-t", str(tmp_path), str(out)], env={}, cwd=tmp_path,
                          capture_output=True, text=True, timeout=300)
    text = proc.stdout + proc.stderr
    assert proc.returncode == 0 and "0 Error(s)" in text, text[-2000:]
    hosted = np.genfromtxt(csv, delimiter=",", names=True, deletechars="")
    own = sewfmu.run("punch_drive", set={"experiment.fmus": "native", "experiment.revolutions": 2,
                                         "experiment.accuracy": "off"}).series
    n = len(own)
    assert abs(len(hosted) - n) <= 1
    for column in ("shaft.phi", "linkage.xi", "punch.y", "punch.F2"):
        a, b = np.asarray(own[column]), np.asarray(hosted[column][:n])
        assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(a)), column
