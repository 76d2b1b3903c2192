"""Every line a native FMU logs is free of '%' as a whole (FMI 2.0's logger is printf-like: C
hosts pass the line on as the format), the instance name a host gave and any text of the host's
(a log category) included, as the Python FMUs' error_line writes it: '%' as " percent". And
fmi2SetDebugLogging/fmi3SetDebugLogging refuse a category the modelDescription does not
declare, naming it and the declared ones."""
from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import pytest
from fmpy.fmi1 import FMICallException

from tests.native.fmpy_native import ERROR, Instance

NAME = "x%n%s%n"                      # what crashed a printf-like logger (a %n write)
SAID = "x percentn percents percentn"
VERSIONS = [2, pytest.param(3, marks=pytest.mark.slow)]


def _refusing_calls(inst: Instance) -> None:
    """Calls each refused or discarded with a line: an unknown value reference, an unknown
    category (the host's text, with '%' in it), a garbled serialized state, a step before
    initialization."""
    fmu = inst.fmu
    garbage = b"%s%n%s%n not a state" + bytes(40)
    calls = [
        lambda: fmu.setReal([99999], [1.0]) if inst.fmi == 2 else fmu.setFloat64([99999], [1.0]),
        lambda: fmu.setDebugLogging(True, ["cat%s%n"]),
        lambda: (fmu.deSerializeFMUstate(garbage) if inst.fmi == 2
                 else fmu.deserializeFMUState(garbage)),
        lambda: fmu.doStep(0.0, 0.1),
    ]
    for call in calls:
        with pytest.raises(FMICallException):
            call()


@pytest.mark.parametrize("fmi", VERSIONS, ids=lambda f: f"fmi{f}")
@pytest.mark.parametrize("model", ["MainShaft", "PunchContact"])
def test_no_logged_line_carries_a_percent_sign(native_fmu, model, fmi):
    inst = Instance(native_fmu(model, fmi), fmi, name=NAME)
    _refusing_calls(inst)
    if model == "MainShaft":       # a refusal that names a number the host gave
        with pytest.raises(FMICallException):
            inst.start(-1.0)
    inst.free()
    assert len(inst.lines) >= 4
    for status, line in inst.lines:
        assert "%" not in line, line
        assert line.startswith(f"{SAID} ({model}): "), line
    assert any("unknown log category 'cat percents percentn'" in line for _, line in inst.lines)


@pytest.mark.skipif(not sys.platform.startswith("linux") or not shutil.which("gcc"),
                    reason="a C host built with gcc on Linux")
@pytest.mark.parametrize("model", ["MainShaft", "PunchContact"])
def test_a_printf_like_c_logger_survives_a_percent_in_the_instance_name(native_fmu, model,
                                                                         tmp_path):
    source = Path(__file__).parent / "printf_host" / "printf_logger.c"
    host = tmp_path / "printf_logger"
    built = subprocess.run(["gcc", "-std=c99", "-Wall", "-Wextra", "-o", str(host), str(source),
                            "-ldl"], capture_output=True, text=True)
    assert built.returncode == 0 and not built.stderr, built.stderr
    with zipfile.ZipFile(native_fmu(model, 2)) as archive:
        archive.extractall(tmp_path / "fmu")
    guid = ElementTree.parse(tmp_path / "fmu" / "modelDescription.xml").getroot().get("guid")
    binary = tmp_path / "fmu" / "binaries" / "linux64" / f"{model}.so"
    for name in (NAME, "pump%s%s%s%s%s%s%s%s"):
        done = subprocess.run([str(host), str(binary), guid, name], capture_output=True,
                              text=True, timeout=60)
        assert done.returncode == 0, (done.returncode, done.stdout, done.stderr)
        lines = done.stdout.splitlines()
        assert lines[-1] == "done"
        said = name.replace("%", " percent")
        # one line per refused call (MainShaft refuses the negative start time too)
        assert len(lines) - 1 == (5 if model == "MainShaft" else 4), lines
        for line in lines[:-1]:
            assert line.startswith(f"{ERROR}|{said} ({model}): "), line


@pytest.mark.parametrize("fmi", VERSIONS, ids=lambda f: f"fmi{f}")
def test_an_unknown_log_category_is_refused_naming_the_declared_ones(native_fmu, fmi):
    fmu_path = native_fmu("PunchContact", fmi)
    with zipfile.ZipFile(fmu_path) as archive:
        root = ElementTree.fromstring(archive.read("modelDescription.xml"))
    declared = [c.get("name") for c in root.iter("Category")]
    assert declared                    # the Python FMU's LogCategories, carried over
    inst = Instance(fmu_path, fmi, name="punch1")
    for category in declared:          # each declared one is taken
        inst.fmu.setDebugLogging(True, [category])
    assert inst.lines == []
    with pytest.raises(FMICallException) as caught:
        inst.fmu.setDebugLogging(True, [declared[0], "nosuchcategory"])
    assert caught.value.status == ERROR
    status, line = inst.lines[-1]
    assert status == ERROR and "unknown log category 'nosuchcategory'" in line, line
    assert f"(known: {', '.join(declared)})" in line, line
    inst.free()
