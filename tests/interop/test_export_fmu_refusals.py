"""What `sewfmu export-fmu` and the exported FMU refuse, and how the refusal reaches a host:

- a component's refusal (a bad start value set by the host) reaches fmpy with its component, its
  parameter, the value and the range, logging on or off, FMI 2.0 and 3.0, and fmpy does not
  crash (before: a segmentation fault with logging on, 4 of 4, and no words with logging off);
- an FMU's log line holds no '%' (fmpy's FMI 2.0 logger proxy takes it as a printf format);
- what `sewfmu run` refuses is not exported (a Jacobi step that diverges, a linkage that cannot
  be assembled), in one line;
- the texts of a scenario go into HTML escaped (the FMU's documentation page, the FMUs' pages,
  report.html).
"""
import os
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description

from tests.paths import REPO

pytestmark = pytest.mark.slow

HOSTILE = '<script>alert("x")</script> & \'quotes\''

# a host in a child process, so that a crash is a return code and not the end of the tests
_HOST = textwrap.dedent("""
    import sys
    from fmpy import read_model_description, simulate_fmu
    fmu, logging, name, value = sys.argv[1], sys.argv[2] == "on", sys.argv[3], float(sys.argv[4])
    h = float(read_model_description(fmu).defaultExperiment.stepSize)
    try:
        simulate_fmu(fmu, debug_logging=logging, start_values={name: value}, output_interval=h)
    except Exception as err:
        print("REFUSED", err)
    else:
        print("RAN")
""")


def _env(fmu_dir: Path) -> dict:
    return {**os.environ, "SEWFMU_FMU_DIR": str(fmu_dir)}


def _export(tmp_path: Path, fmu_dir: Path, *args) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sewfmu", "export-fmu", *map(str, args)],
                          capture_output=True, text=True, timeout=300, cwd=tmp_path,
                          env=_env(fmu_dir))


@pytest.fixture(scope="module", params=[2, 3], ids=["fmi2", "fmi3"])
def exported(request, tmp_path_factory, fmu_dir, fmu3_dir):
    folder = tmp_path_factory.mktemp(f"export{request.param}")
    target = folder / "punch_drive.fmu"
    proc = _export(folder, fmu_dir, "punch_drive", "-o", target, "--fmi", request.param)
    assert proc.returncode == 0, proc.stderr
    return target


@pytest.mark.parametrize("logging", ["on", "off"])
@pytest.mark.parametrize("name, value, component, words", [
    ("shaft.omega0", -5.0, "shaft (MainShaft)", ["parameter omega0", "> 0 rad/s", "got -5.0"]),
    ("punch.m", -1.0, "punch (PunchContact)", ["parameter m", "> 0 kg", "got -1.0"]),
    ("shaft.omega0", 5000.0, "shaft (MainShaft)",
     ["parameter omega0", "within [0, 2000] rad/s", "got 5000"]),
])
def test_a_components_refusal_reaches_fmpy_with_its_reason(exported, logging, name, value,
                                                            component, words):
    proc = subprocess.run([sys.executable, "-c", _HOST, str(exported), logging, name,
                           repr(value)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, (proc.returncode, proc.stdout[-3000:], proc.stderr[-3000:])
    assert "REFUSED" in proc.stdout and "failed with status 3" in proc.stdout, proc.stdout
    errors = [line for line in proc.stdout.splitlines() if line.startswith("[ERROR]")]
    # the first error a reader meets is the cause: the component and its parameter, not an
    # input made NaN downstream of it
    assert errors and component in errors[0], errors
    assert all(w in errors[0] for w in words), errors[0]
    # every line downstream says where its NaN comes from
    assert all("failed first" in line for line in errors if " is nan at " in line), errors


def test_the_container_holds_the_fmi3_builds_of_the_components(exported):
    with zipfile.ZipFile(exported) as fmu:
        config = fmu.read("resources/container.json").decode()
        assert '"fmiMajorVersion": "2"' not in config
        assert '"fmiMajorVersion": "3"' in config
    # the declared ranges go with the exposed parameters
    names = {v.name: v for v in read_model_description(str(exported)).modelVariables}
    assert (names["shaft.omega0"].min, names["shaft.omega0"].max) == ("0.0", "2000.0")


_PERCENT_HOST = textwrap.dedent("""
    import sys
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    md = read_model_description(sys.argv[1])
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(sys.argv[1]),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="shaft")
    fmu.instantiate(loggingOn=True)            # fmpy's callbacks, behind its logger proxy
    fmu.setString([0], ["%s%s%s%s%s%s%s%s"])   # a String set on a Real: refused with the value
    fmu.freeInstance()
    print("ALIVE")
""")


def test_a_percent_in_a_log_line_is_not_a_printf_format(fmu_paths):
    proc = subprocess.run([sys.executable, "-c", _PERCENT_HOST, str(fmu_paths["MainShaft"])],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0 and "ALIVE" in proc.stdout, (proc.returncode, proc.stdout,
                                                            proc.stderr)
    line = next(x for x in proc.stdout.splitlines() if "cannot be set this way" in x)
    assert "%" not in line and "shaft (MainShaft)" in line, line


@pytest.mark.parametrize("args, words", [
    # punch_split for Jacobi at 2 ms: `sewfmu run` stops it as diverging after 19 steps
    (["punch_split", "--set", 'experiment.master="jacobi"', "--set", "experiment.step=2e-3"],
     ["not exported", "diverged", "body, fabric", "experiment.step"]),
    # a linkage that cannot be assembled: every value within its declared range, refused by
    # the FMU at initialization
    (["punch_drive", "--set", "linkage.L_O1A=0.5"],
     ["not exported", "linkage (PunchLinkage)", "cannot be assembled"]),
    # a value outside the declared range
    (["punch_drive", "--set", "punch.m=-1"], ["punch", "parameter m", "-1 kg", "[0, 50]"]),
])
def test_what_sewfmu_run_refuses_is_not_exported_in_one_line(tmp_path, fmu_dir, args, words):
    target = tmp_path / "x.fmu"
    proc = _export(tmp_path, fmu_dir, *args, "-o", target)
    assert proc.returncode == 1, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert all(w in proc.stderr for w in words), proc.stderr
    assert not list(tmp_path.glob("*.fmu")) and not list(tmp_path.glob(".*.partial"))


def test_the_scenarios_description_is_escaped_in_the_fmus_page(tmp_path, fmu_dir):
    scenario = tmp_path / "hostile.toml"
    source = REPO / "scenarios" / "catalogue" / "punch_drive.toml"
    text = source.read_text().splitlines()
    assert text[0].startswith("description = ")
    text[0] = 'description = """' + HOSTILE + '"""'
    scenario.write_text("\n".join(text) + "\n")
    target = tmp_path / "hostile.fmu"
    proc = _export(tmp_path, fmu_dir, scenario, "-o", target)
    assert proc.returncode == 0, proc.stderr
    with zipfile.ZipFile(target) as fmu:
        page = fmu.read("documentation/index.html").decode()
    assert "<script>" not in page and "&lt;script&gt;alert(&quot;x&quot;)" in page, page
    assert "&amp;" in page
    # the modelDescription keeps the text as it is (XML escapes it itself)
    assert read_model_description(str(target)).description == HOSTILE


def test_an_fmus_own_page_escapes_its_texts():
    from sewfmu.components.shaft_fmu import MainShaftSlave
    from sewfmu.scenarios.fmu_build.documentation import page

    hostile = type("Hostile", (MainShaftSlave,), {"__doc__": HOSTILE, "model_name": HOSTILE})
    text = page(hostile, 2)
    assert "<script>" not in text and text.count("&lt;script&gt;") == 3      # title, h1, doc


def test_report_html_escapes_every_text(tmp_path):
    from sewfmu.scenarios.runs import report

    section = report.Section(HOSTILE)
    section.table([HOSTILE, "b", "c"], [[HOSTILE, 1.0, True]])
    section.note(HOSTILE)
    picture = tmp_path / "p.png"
    picture.write_bytes(b"\x89PNG\r\n\x1a\n")
    section.pictures([(HOSTILE, picture)])
    out = tmp_path / "report.html"
    report.write(out, HOSTILE, HOSTILE, [section])
    text = out.read_text()
    assert "<script>" not in text and '"x"' not in text, text
