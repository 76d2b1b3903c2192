"""The native FMUs through fmpy: the Python FMU's DefaultExperiment at every row, FMU state that
repeats steps bit for bit, binaries that need no Python and no mingw runtime, fmuCheck in an
environment with nothing of Python. MainShaft FMI 2.0 is the fast loop's (one build); every
other FMU and FMI 3.0 are slow (a build each)."""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import fmpy
import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from sewfmu.scenarios.fmu_build.native import MODEL_FILES, MODELS, RUNTIME
from tests.native.fmpy_native import Instance, reference_of, worst_relative

# the checker as every host test finds it: SEWFMU_FMUCHECK (.ci/run sets it), else skipped
FMUCHECK = Path(os.environ.get("SEWFMU_FMUCHECK", "") or "/nonexistent/fmuCheck")
SLOW = pytest.mark.slow


def _cases(fast=(("MainShaft", 2),)):
    """(name, fmi) of every FMU whose C model files exist, the fast ones unmarked."""
    cases = []
    for name, files in MODEL_FILES.items():
        for fmi in (2, 3):
            marks = [] if (name, fmi) in fast else [SLOW]
            if not all((MODELS / f).is_file() for f in files):
                marks.append(pytest.mark.skip(reason=f"{name}: native/models/ lacks one of "
                                                     f"{', '.join(files)}"))
            cases.append(pytest.param(name, fmi, marks=marks, id=f"{name}-fmi{fmi}"))
    return cases


def _python_fmu(native: Path, fmi: int) -> Path:
    """The Python FMU the fixture built the native one from."""
    return native.parent.parent / f"python{fmi}" / native.name


@pytest.mark.parametrize("name, fmi", _cases())
def test_the_default_experiment_gives_the_python_fmus_rows(native_fmu, name, fmi):
    fmu = native_fmu(name, fmi)
    columns, reference = reference_of(_python_fmu(fmu, fmi), name)
    # every step a row (fmpy would otherwise widen the output interval to 1000 rows at most)
    step = float(Instance.describe(fmu).defaultExperiment.stepSize)
    result = simulate_fmu(str(fmu), output_interval=step)
    assert len(result) == len(reference)
    for i, column in enumerate(columns):
        got = result[column].astype(float)
        assert worst_relative(got, reference[:, i]) <= 1e-9, column


@pytest.mark.parametrize("name, fmi", _cases())
def test_the_native_fmu_carries_the_python_fmus_reference_and_declarations(native_fmu, name, fmi):
    fmu = native_fmu(name, fmi)
    python = _python_fmu(fmu, fmi)
    with zipfile.ZipFile(fmu) as native_zip, zipfile.ZipFile(python) as python_zip:
        ref = f"extra/org.fmi-standard.fmi-ls-ref/{name}_out.csv"
        assert native_zip.read(ref) == python_zip.read(ref)
        xml = native_zip.read("modelDescription.xml").decode()
        names = native_zip.namelist()
    assert "python" not in xml.lower()
    assert not any(n.startswith("resources/") for n in names)
    assert "sources/description.c" in names
    assert ("sources/buildDescription.xml" in names) == (fmi == 3)
    native_md, python_md = Instance.describe(fmu), Instance.describe(python)
    assert native_md.guid != python_md.guid
    keys = ("name", "valueReference", "type", "causality", "variability", "unit", "displayUnit",
            "min", "max", "start", "description")
    assert [[getattr(v, k, None) for k in keys] for v in native_md.modelVariables] == \
        [[getattr(v, k, None) for k in keys] for v in python_md.modelVariables]
    experiment = ("startTime", "stopTime", "stepSize")
    assert [getattr(native_md.defaultExperiment, k) for k in experiment] == \
        [getattr(python_md.defaultExperiment, k) for k in experiment]
    assert validate_fmu(str(fmu)) == []
    if fmi == 3:
        lxml = pytest.importorskip("lxml.etree")
        schema = Path(fmpy.__file__).parent / "schema" / "fmi3" / "fmi3BuildDescription.xsd"
        with zipfile.ZipFile(fmu) as archive:
            build = lxml.fromstring(archive.read("sources/buildDescription.xml"))
        assert lxml.XMLSchema(lxml.parse(str(schema))).validate(build)
    assert native_md.coSimulation.canGetAndSetFMUstate
    assert native_md.coSimulation.canSerializeFMUstate
    assert not native_md.coSimulation.needsExecutionTool


@SLOW
def test_a_rebuild_of_the_same_sources_keeps_its_token(native_fmu, tmp_path):
    from sewfmu.scenarios.fmu_build.native import build_native_fmu  # a second build, here

    first = native_fmu("MainShaft", 2)
    again = build_native_fmu("MainShaft", tmp_path, fmi=2, python_dir=_python_fmu(first, 2).parent)
    assert Instance.describe(first).guid == Instance.describe(again).guid


@pytest.mark.parametrize("name, fmi", _cases())
def test_a_restored_state_repeats_the_steps_bit_for_bit(native_fmu, name, fmi):
    fmu = native_fmu(name, fmi)
    inst = Instance(fmu, fmi)
    outputs = [v.name for v in inst.md.modelVariables if v.causality == "output"
               and v.type in ("Real", "Float64")]
    stop = float(inst.md.defaultExperiment.stopTime)
    h = stop / 40
    try:
        inst.start()
        t = 0.0
        for _ in range(10):
            inst.fmu.doStep(t, h)
            t += h
        get = inst.fmu.getFMUstate if fmi == 2 else inst.fmu.getFMUState
        state = get()
        serialize = inst.fmu.serializeFMUstate if fmi == 2 else inst.fmu.serializeFMUState
        data = serialize(state)

        def run(t):
            rows = []
            for _ in range(20):
                inst.fmu.doStep(t, h)
                t += h
                rows.append(inst.outputs(outputs))
            return rows
        first = run(t)
        (inst.fmu.setFMUstate if fmi == 2 else inst.fmu.setFMUState)(state)
        second = run(t)
        deserialize = inst.fmu.deSerializeFMUstate if fmi == 2 else inst.fmu.deserializeFMUState
        (inst.fmu.setFMUstate if fmi == 2 else inst.fmu.setFMUState)(deserialize(data))
        third = run(t)
    finally:
        inst.free()
    assert np.array_equal(np.array(first), np.array(second))
    assert np.array_equal(np.array(first), np.array(third))
    assert not any(status >= 3 for status, _ in inst.lines), inst.lines


@pytest.mark.parametrize("name, fmi", _cases())
def test_the_binaries_need_no_python_and_no_mingw_runtime(native_fmu, name, fmi, tmp_path):
    fmu = native_fmu(name, fmi)
    linux, windows = ("linux64", "win64") if fmi == 2 else ("x86_64-linux", "x86_64-windows")
    with zipfile.ZipFile(fmu) as archive:
        archive.extractall(tmp_path)
    so = tmp_path / "binaries" / linux / f"{name}.so"
    dll = tmp_path / "binaries" / windows / f"{name}.dll"
    assert so.is_file() and dll.is_file()
    if shutil.which("readelf"):
        needed = subprocess.run(["readelf", "-d", str(so)], capture_output=True, text=True,
                                check=True).stdout
        assert "python" not in needed.lower(), needed
    objdump = shutil.which("x86_64-w64-mingw32-objdump")
    if objdump is None:
        pytest.skip("no x86_64-w64-mingw32-objdump (apt install mingw-w64): the DLL's imports "
                    "are not read")
    imports = [line.split(":", 1)[1].strip().lower()
               for line in subprocess.run([objdump, "-p", str(dll)], capture_output=True,
                                          text=True, check=True).stdout.splitlines()
               if "DLL Name:" in line]
    assert imports, "the DLL imports nothing?"
    assert not [d for d in imports if "python" in d or "libgcc" in d or "winpthread" in d], imports
    # it exports the FMI functions and nothing else
    table = subprocess.run([objdump, "-p", str(dll)], capture_output=True, text=True,
                           check=True).stdout
    exported = re.findall(r"^\s*\[\s*\d+\] (\w+)$", table, re.MULTILINE)
    assert len(exported) > 40 and all(e.startswith(f"fmi{fmi}") for e in exported), exported


@pytest.mark.parametrize("name, fmi", _cases())
def test_the_linux_binary_exports_every_function_of_its_fmi_version(native_fmu, name, fmi,
                                                                  tmp_path):
    if not shutil.which("nm"):
        pytest.skip("no nm: the binary's symbols are not read")
    header = (RUNTIME / f"fmi{fmi}" / f"fmi{fmi}Functions.h").read_text()
    declared = set(re.findall(rf"FMI{fmi}_Export\s+fmi{fmi}\w+TYPE\s+(fmi{fmi}\w+);", header))
    folder = "linux64" if fmi == 2 else "x86_64-linux"
    with zipfile.ZipFile(native_fmu(name, fmi)) as archive:
        so = tmp_path / f"{name}.so"
        so.write_bytes(archive.read(f"binaries/{folder}/{name}.so"))
    symbols = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True,
                             text=True, check=True).stdout.split()
    exported = {s for s in symbols if s.startswith(f"fmi{fmi}")}
    assert len(declared) > 40 and declared <= exported, sorted(declared - exported)
    # nothing else: the runtime's own functions stay inside (several FMUs in one process)
    assert not [s for s in symbols if s.startswith(("sew_", "SEW_"))]


@pytest.mark.interop
@pytest.mark.parametrize("name, fmi", [c for c in _cases() if c.values[1] == 2])
def test_fmucheck_runs_the_native_fmu_with_nothing_of_python(native_fmu, name, fmi, tmp_path):
    # fmuCheck (FMI Library 2.4.1) reads FMI 1.0 and 2.0 only
    if not FMUCHECK.is_file():
        pytest.skip(f"no fmuCheck at {FMUCHECK} (set SEWFMU_FMUCHECK)")
    fmu = native_fmu(name, fmi)
    done = subprocess.run([str(FMUCHECK), "-l", "3", "-o", str(tmp_path / "out.csv"), str(fmu)],
                          capture_output=True, text=True, env={"PATH": "/usr/bin:/bin"},
                          timeout=120)
    text = done.stdout + done.stderr
    assert done.returncode == 0, text
    assert "\t0 Error(s)" in text, text
    rows = (tmp_path / "out.csv").read_text().splitlines()
    assert len(rows) > 2 and "nan" not in rows[-1].lower(), rows[-3:]


@SLOW
@pytest.mark.parametrize("name", ["MainShaft", "PunchContact"])
@pytest.mark.parametrize("fmi", [2, 3])
def test_the_sources_it_ships_compile_into_a_binary_with_the_same_numbers(native_fmu, name, fmi,
                                                                         tmp_path):
    if not shutil.which("gcc"):
        pytest.skip("no gcc")
    fmu = native_fmu(name, fmi)
    with zipfile.ZipFile(fmu) as archive:
        archive.extractall(tmp_path)
    sources = tmp_path / "sources"
    if fmi == 2:
        listed = [f.get("name") for f in ElementTree.parse(tmp_path / "modelDescription.xml")
                  .getroot().iter("File")]
    else:
        listed = [f.get("name") for f in ElementTree.parse(sources / "buildDescription.xml")
                  .getroot().iter("SourceFile")]
    assert sorted(listed) == sorted(p.name for p in sources.glob("*.c"))
    binary = tmp_path / "binaries" / ("linux64" if fmi == 2 else "x86_64-linux") / f"{name}.so"
    binary.unlink()
    subprocess.run(["gcc", "-std=c99", "-O2", "-ffp-contract=off", "-shared", "-fPIC",
                    f"-I{sources}", *(str(sources / f) for f in listed), "-o", str(binary),
                    "-lm"], check=True)
    columns, reference = reference_of(_python_fmu(fmu, fmi), name)
    step = float(Instance.describe(fmu).defaultExperiment.stepSize)
    result = simulate_fmu(str(tmp_path), output_interval=step)
    for i, column in enumerate(columns):
        assert worst_relative(result[column].astype(float), reference[:, i]) <= 1e-9, column
