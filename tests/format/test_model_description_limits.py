"""An FMU's modelDescription.xml, from the attack: one 60 MiB attribute on its root element kept
`sewfmu references --fmu` parsing for minutes (expat 2.5 re-reads a long start tag fed in
pieces), and an FMI 1.0 FMU surfaced as fmpy's TypeError or a truncated ValidationError. Now:
one line each, at once."""
import time
import zipfile

import pytest

import sewfmu
from sewfmu.cli import main
from sewfmu.scenarios.format.fmu_file import MAX_XML_BYTES, model_description
from sewfmu.scenarios.format.values import ScenarioError

FMI1 = ('<?xml version="1.0"?><fmiModelDescription fmiVersion="1.0" modelName="M" '
        'modelIdentifier="M" guid="{x}" numberOfContinuousStates="0" '
        'numberOfEventIndicators="0"><ModelVariables/></fmiModelDescription>')


def _fmu(path, text: str):
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("modelDescription.xml", text)
    return path


FMI2 = FMI1.replace('fmiVersion="1.0"', 'fmiVersion="2.0"')


def test_an_fmi_1_fmu_is_named_as_such(tmp_path, capsys):
    fmu = _fmu(tmp_path / "old.fmu", FMI1)
    with pytest.raises(ScenarioError, match=r"old.fmu: FMI 1.0 is not supported \(FMI 2.0 and "
                                            r"3.0 are\)"):
        model_description(fmu, "")
    assert main(["references", "--fmu", str(fmu)]) == 1
    assert capsys.readouterr().err.strip().endswith("FMI 1.0 is not supported (FMI 2.0 and 3.0 "
                                                    "are)")
    scenario = tmp_path / "old.toml"         # a run of it: the same line, not fmpy's
    scenario.write_text('[experiment]\nstop_time = 0.01\nstep = 0.001\n'
                        '[instances.old]\nfmu = "old.fmu"\n')
    with pytest.raises(ScenarioError, match=r"instances.old: old.fmu: FMI 1.0 is not supported"):
        sewfmu.run(str(scenario))
    without = _fmu(tmp_path / "none.fmu", FMI1.replace(' fmiVersion="1.0"', ""))
    with pytest.raises(ScenarioError, match="without fmiVersion is not supported"):
        model_description(without, "")


@pytest.mark.slow
def test_a_root_element_with_a_60_mib_attribute_is_refused_at_once(tmp_path, capsys):
    big = "x" * (60 << 20)
    fmu = _fmu(tmp_path / "huge.fmu", FMI2.replace(
        "<fmiModelDescription", f'<fmiModelDescription huge="{big}"', 1))
    started = time.monotonic()
    assert main(["references", "--fmu", str(fmu)]) == 1
    took = time.monotonic() - started
    line = capsys.readouterr().err.strip()
    assert "does not end within its first 1 MiB" in line and "\n" not in line
    assert took < 5, took                   # was silent after 120 s


@pytest.mark.slow
def test_a_model_description_beyond_the_bound_is_refused_naming_its_size(tmp_path):
    padded = FMI2.replace("?>", "?>" + "<!--" + " " * (MAX_XML_BYTES + 1) + "-->", 1)
    fmu = _fmu(tmp_path / "big.fmu", padded)
    started = time.monotonic()
    with pytest.raises(ScenarioError, match=r"modelDescription.xml is 64 MiB, more than the 64 "
                                            r"MiB sewfmu reads"):
        model_description(fmu, "")
    assert time.monotonic() - started < 2
