"""The FMUs in other FMI tools: an SSP 1.0 export checked by pyssp-standard and the SSP schema,
the same scenario in libcosim, in ecos and in the ecos command-line tool (a host that is not
Python), the regression references, and fmutool -check."""
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from sewfmu.cli import main
from sewfmu.components.registry import FMUS
from sewfmu.scenarios.fmu_build.build import MODEL_CODE_DIR, build_fmu
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.interop.cross_check import crosscheck
from sewfmu.scenarios.interop.hosts import check_host_environment, host_environment
from sewfmu.scenarios.interop.ssp_export import export
from sewfmu.scenarios.references import regression as references

pytestmark = [pytest.mark.slow, pytest.mark.interop]

FIGURES_DEG = ("contact_onset_deg", "contact_loss_deg", "contact_duration_deg")
FIGURES_N = ("F2_peak", "F2_weld_mean")
# how far each host's figures may lie from sewfmu's own (°, N): just above what they give.
# Measured: libcosim 9.5e-5° and 2.4e-6 N, ecos 4e-12° and 6e-13 N, ecos-cli (its CSV has 6
# decimals) 0.058° (the contact duration) and 4.3e-5 N
WITHIN = {"libcosim": (2e-4, 1e-5), "ecos": (1e-9, 1e-9), "ecos-cli": (0.07, 1e-4)}


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


def test_ssp_export_is_valid_and_complete(tmp_path):
    pyssp = pytest.importorskip("pyssp_standard")
    import xmlschema
    from pyssp_standard.ssd import SSD

    sc = load("punch_drive")
    sc.set_value("shaft.omega0", 250.0)
    sc.set_value("punch.F30", 4.0)
    path = export(sc, tmp_path / "punch.ssp")
    folder = tmp_path / "unpacked"
    zipfile.ZipFile(path).extractall(folder)
    ssd_file = folder / "SystemStructure.ssd"
    schema = Path(pyssp.__file__).parent / "resources" / "SystemStructureDescription.xsd"
    xmlschema.XMLSchema10(str(schema)).validate(str(ssd_file))
    assert sorted(p.name for p in (folder / "resources").iterdir()) == \
        ["MainShaft.fmu", "PunchContact.fmu", "PunchLinkage.fmu"]
    with SSD(ssd_file, "r") as ssd:
        assert [e.name for e in ssd.system.elements] == ["shaft", "linkage", "punch"]
        connections = {(c.start_element, c.start_connector, c.end_element, c.end_connector)
                       for c in ssd.connections()}
        assert connections == {(c.src, c.src_var, c.dst, c.dst_var) for c in sc.connections}
        assert ssd.check_connections() == []
    text = ssd_file.read_text()
    assert 'name="omega0"' in text and 'value="250.0"' in text and 'value="4.0"' in text


@pytest.mark.parametrize("host, fmi", [("libcosim", 2), ("ecos", 2), ("ecos-cli", 2),
                                       ("ecos", 3), ("ecos-cli", 3)])
def test_other_hosts_give_the_same_figures(tmp_path, host, fmi, fmu3_dir):
    """libcosim and ecos are plain fixed-step Jacobi masters that read outputs right after the
    step; ecos-cli hosts the FMUs in a process that is not Python. ecos runs the FMI 3.0 FMUs
    too."""
    scenario = load("punch_drive")
    scenario.set_value("experiment.fmi", fmi)
    rows = {key: (own, other) for key, own, other, _ in
            crosscheck(scenario, host, tmp_path / host)}
    assert rows["n_contacts"][0] == rows["n_contacts"][1] == 1
    degrees, newtons = WITHIN[host]
    for key in FIGURES_DEG:
        assert abs(rows[key][0] - rows[key][1]) < degrees, (key, rows[key])
    for key in FIGURES_N:
        assert abs(rows[key][0] - rows[key][1]) < newtons, (key, rows[key])
    assert (tmp_path / host / "results.csv").exists() and (tmp_path / host / "summary.json").exists()


def test_libcosim_refuses_fmi3_fmus_in_one_clear_line(tmp_path, capsys, fmu3_dir):
    """libcosim (libcosimpy 0.0.6) runs FMI 1.0 and 2.0 only: said so, naming the FMU."""
    assert main(["crosscheck", "punch_drive", "--host", "libcosim", "--set",
                 "experiment.fmi=3", "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert "Unsupported FMI version" in err and ".fmu" in err, err


def test_a_non_python_host_without_its_environment_gets_a_clear_message(capsys, monkeypatch):
    assert len(check_host_environment({})) == 2
    assert check_host_environment({**os.environ, **host_environment()}) == []
    for key in ("LD_PRELOAD", "PYTHONHOME", "PYTHONPATH"):
        monkeypatch.delenv(key, raising=False)
    assert main(["host-env", "--check"]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "LD_PRELOAD does not name libpython" in err


@pytest.mark.parametrize("name", list(FMUS))
def test_every_fmu_matches_its_regression_reference(fmu_paths, name):
    folder = references.REFERENCE_DIR / name
    assert (folder / f"{name}_ref.csv").exists() and (folder / f"{name}_ref.opt").exists()
    assert (folder / f"{name}_in.csv").exists() == (references.cases()[name].inputs is not None)
    assert references.check(name, fmu_paths[name]) == []


def test_a_changed_fmu_is_caught_by_its_reference(tmp_path):
    """The reference check is not blind: a MainShaft built from code whose default speed is 1 %
    higher fails against the reference."""
    source = tmp_path / "components"
    shutil.copytree(MODEL_CODE_DIR, source, ignore=shutil.ignore_patterns("__pycache__"))
    code = (source / "shaft.py").read_text()
    assert "parameter(100.0," in code
    (source / "shaft.py").write_text(code.replace("parameter(100.0,", "parameter(101.0,"))
    changed = build_fmu("MainShaft", tmp_path / "fmus", source=source)
    problems = references.check("MainShaft", changed)
    assert problems and "MainShaft: phi leaves the tolerance at t = " in problems[0]


@pytest.mark.parametrize("name", list(FMUS))
def test_fmutool_check_passes(fmus, name):
    tool = Path(sys.executable).parent / "fmutool"
    if not tool.exists():
        pytest.skip("fmu-manipulation-toolbox is not installed")
    proc = subprocess.run([str(tool), "-input", str(fmus[name]), "-check"],
                          capture_output=True, text=True, timeout=120)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out
    version = "3.0" if "fmi3" in fmus[name].parts else "2.0"
    assert f"compliant with FMI-{version}" in out and "No semantic error" in out, out
    assert "ERROR" not in out


@pytest.mark.parametrize("version", ["3.10", "3.12", "3.13"])
def test_host_env_check_takes_any_home_the_fmus_run_with(tmp_path, capsys, version):
    """A home and a libpython of another Python version, given with --home and --preload (a
    foreign PYTHONHOME exported to sewfmu's own process would stop its Python from starting):
    accepted when both are one version of 3.10-3.13, one clear line when they differ."""
    def install(v: str) -> tuple[Path, Path]:
        home = tmp_path / f"python{v}"
        (home / "lib" / f"python{v}").mkdir(parents=True)
        (home / "lib" / f"python{v}" / "os.py").write_text("")
        library = home / "lib" / f"libpython{v}.so"
        library.write_text("")
        return home, library

    home, library = install(version)
    assert main(["host-env", "--check", "--home", str(home), "--preload", str(library)]) == 0
    assert capsys.readouterr().out.strip().endswith("# this environment has all of it")
    _, other = install("3.11" if version != "3.11" else "3.12")
    assert main(["host-env", "--check", "--home", str(home), "--preload", str(other)]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "give both of one version" in err, err
