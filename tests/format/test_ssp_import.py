"""SSP systems from any SSP editor run as they are: sewfmu's own exports read back give the same
figures; renamed components, another parameter-set name, a .ssv file and an FMU that sewfmu did
not build run; broken SSP files get one clear line."""
import json
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from sewfmu.cli import main
from sewfmu.scenarios.format.loader import catalogue, load
from sewfmu.scenarios.format.values import ScenarioError
from sewfmu.scenarios.interop.ssp_export import export
from sewfmu.scenarios.runs.runner import simulate, summarize

SKIP = ("scenario", "master", "step", "stop_time", "wall_time_s")


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


def _figures(scenario):
    return {k: v for k, v in summarize(simulate(scenario)).items() if k not in SKIP}


def _runs_of_catalogue():
    """Every catalogue scenario as it runs (a [compare] scenario: its first variant)."""
    out = []
    for name in sorted(catalogue()):
        sc = load(name)
        if sc.study:                 # computed, not co-simulated: the same system is there
            continue
        if sc.compare:
            sc.set_value(sc.compare["parameter"], sc.compare["values"][0])
            sc.compare = None
        out.append((name, sc))
    return out


@pytest.mark.parametrize("name, scenario", _runs_of_catalogue(), ids=lambda v: v
                         if isinstance(v, str) else "")
@pytest.mark.slow
def test_an_exported_catalogue_scenario_read_back_gives_the_same_figures(tmp_path, name,
                                                                          scenario):
    ssp = export(scenario, tmp_path / f"{name}.ssp")
    back = load(str(ssp))
    assert back.analysis == scenario.analysis and back.step == (scenario.step if scenario.master == "adaptive"
                                                        else scenario.even_steps()[1])
    assert _figures(back) == _figures(scenario)


@pytest.mark.parametrize("fmi", [2, 3])
def test_an_export_keeps_the_record_its_thinning_and_the_fmi_version(tmp_path, fmi):
    # what a TOML scenario's run records is what the SSP's run records (the SSP standard has no
    # place for it: sewfmu's annotation carries it); an independent check is the run itself
    sc = load("punch_drive")
    sc.set_value("experiment.revolutions", 2)
    sc.set_value("experiment.record_every", 4)
    sc.set_value("experiment.fmi", fmi)
    sc.record = ["punch.contact", "punch.F2", "shaft.phi", "punch.y"]
    back = load(str(export(sc, tmp_path / "narrow.ssp")))
    assert (back.record, back.record_every, back.fmi) == (sc.record, 4, fmi)
    ours, theirs = simulate(sc), simulate(back)
    assert list(theirs.columns) == sc.record
    assert len(theirs.time) == len(ours.time) < 2 * 2514 / 4
    for column in sc.record:
        assert (theirs[column] == ours[column]).all(), column


@pytest.mark.parametrize("accuracy, accept", [(1e-9, False), (1e-9, True), ("off", False)])
def test_an_export_keeps_the_accuracy_its_figures_are_held_to(tmp_path, accuracy, accept):
    sc = load("punch_drive")
    sc.set_value("experiment.accuracy", accuracy)
    sc.set_value("experiment.accept_error", accept)
    back = load(str(export(sc, tmp_path / "held.ssp")))
    assert (back.accuracy, back.accept_error) == (accuracy, accept)


def test_an_ssp_from_elsewhere_records_every_output(tmp_path):
    sc = load("punch_drive")
    sc.set_value("experiment.revolutions", 1)
    ssp = export(sc, tmp_path / "plain.ssp")
    edited = _rewrite(ssp, tmp_path / "edited.ssp",
                      lambda text: re.sub(r'\s*record_every="\d+"', "", text))
    back = load(str(edited))
    assert back.record is None and back.record_every == 1


@pytest.fixture(scope="module")
def narrow_ssp(tmp_path_factory, fmu_dir):
    """punch_drive (1 revolution) with a narrowed record, record_every 7, exported."""
    sc = load("punch_drive")
    sc.set_value("experiment.revolutions", 1)
    sc.set_value("experiment.record_every", 7)
    sc.record = ["punch.F2", "shaft.phi"]
    folder = tmp_path_factory.mktemp("narrow")
    return export(sc, folder / "narrow.ssp", fmu_dir)


@pytest.mark.parametrize("old, new, words", [
    ('record_every="7"', 'record_every="0"', r"record_every: must be a whole number >= 1, got 0"),
    ('record_every="7"', 'record_every="2.5"', r"record_every: .* got 2.5"),
    ('master="jacobi"', 'master="adaptiv"', r"experiment.master: must be one of .* 'adaptiv'"),
    ('step="[^"]*"', 'step="nan"', r"experiment.step"),
    ('master="jacobi"', 'master="jacobi" tolerence="1e-7"',
     r"unknown key 'tolerence'; did you mean 'tolerance'\?"),
    ('<sewfmu:Record column="shaft.phi" />', '<sewfmu:Record column="punch.F2" />',
     r"record lists 'punch.F2' more than once"),
    ('<sewfmu:Record column="shaft.phi" />', '<sewfmu:Record column="" />',
     r"a Record without its column"),
    ('</ssd:Annotations>\n  </ssd:DefaultExperiment>',
     '<ssc:Annotation type="org.sewfmu.experiment"><sewfmu:Experiment step="0.001" />'
     '</ssc:Annotation></ssd:Annotations></ssd:DefaultExperiment>',
     r"appears more than once"),
], ids=["record_every 0", "record_every 2.5", "unknown master", "step nan", "misspelt key",
        "duplicate column", "empty column", "two annotations"])
def test_a_bad_value_in_sewfmus_annotation_is_refused_as_in_a_scenario_file(
        tmp_path, narrow_ssp, old, new, words):
    edited = _rewrite(narrow_ssp, tmp_path / "edited.ssp",
                      lambda text: re.sub(old, new, text, count=1))
    with pytest.raises(ScenarioError, match=words) as err:
        load(str(edited))
    assert "\n" not in str(err.value)


def test_another_tools_annotation_is_not_read_as_sewfmus(tmp_path, narrow_ssp):
    # nested in sewfmu's, or beside it elsewhere in the file, with keys sewfmu knows
    foreign = ('<ssc:Annotation type="org.other"><x:foo xmlns:x="urn:x" step="0.003" '
               'master="adaptive" record_every="2"><sewfmu:Record column="punch.y" />'
               '</x:foo></ssc:Annotation>')
    edited = _rewrite(narrow_ssp, tmp_path / "edited.ssp",
                      lambda text: text.replace('<sewfmu:Record column="shaft.phi" />',
                                                '<sewfmu:Record column="shaft.phi" />' + foreign, 1)
                      .replace("</ssd:Elements>", "</ssd:Elements><ssd:Annotations>"
                               + foreign + "</ssd:Annotations>", 1))
    back = load(str(edited))
    original = load(str(narrow_ssp))
    assert (back.step, back.master, back.record_every, back.record) == \
        (original.step, "jacobi", 7, ["punch.F2", "shaft.phi"])


def test_the_fmi_version_of_sewfmus_fmus_does_not_apply_to_an_ssps_own(narrow_ssp):
    with pytest.raises(ScenarioError, match=r"experiment.fmi: chooses the FMI version of "
                                            r"sewfmu's own FMUs"):
        load(str(narrow_ssp)).set_value("experiment.fmi", 3)


def _rewrite(ssp: Path, out: Path, edit, extra: dict[str, str] | None = None) -> Path:
    """A copy of an .ssp with its SystemStructure.ssd edited and extra files added."""
    with zipfile.ZipFile(ssp) as src, zipfile.ZipFile(out, "w") as dst:
        for item in src.infolist():
            data = src.read(item)
            if item.filename == "SystemStructure.ssd":
                data = edit(data.decode("utf-8")).encode("utf-8")
            dst.writestr(item, data)
        for name, text in (extra or {}).items():
            dst.writestr(name, text)
    return out


SSV = """<?xml version="1.0" encoding="UTF-8"?>
<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"
    version="1.0" name="Variante A">
  <ssv:Parameters>
    <ssv:Parameter name="Stempel.F30"><ssv:Real value="5.0"/></ssv:Parameter>
    <ssv:Parameter name="Stempel.c3"><ssv:Real value="200000"/></ssv:Parameter>
  </ssv:Parameters>
</ssv:ParameterSet>
"""


def test_renamed_components_a_named_parameter_set_and_an_ssv_file(tmp_path):
    sc = load("punch_drive")
    sc.revolutions = 3
    sc.set_value("shaft.omega0", 200.0)
    ssp = export(sc, tmp_path / "punch.ssp")

    def edit(text):
        for old, new in (("shaft", "Welle"), ("linkage", "Getriebe"), ("punch", "Stempel")):
            text = re.sub(rf'"{old}"', f'"{new}"', text)
        text = text.replace('name="sewfmu"', 'name="Betriebspunkt"')
        # the punch (the last component) takes its parameters from a .ssv file, with a prefix
        head, tail = text.rsplit("</ssd:Component>", 1)
        return (head + '<ssd:ParameterBindings><ssd:ParameterBinding source="resources/'
                'variante.ssv" prefix="Stempel."/></ssd:ParameterBindings></ssd:Component>'
                + tail)

    edited = _rewrite(ssp, tmp_path / "edited.ssp", edit, {"resources/variante.ssv": SSV})
    back = load(str(edited))
    assert set(back.instances) == {"Welle", "Getriebe", "Stempel"}
    assert back.roles == {"shaft": "Welle", "linkage": "Getriebe", "punch": "Stempel"}
    assert back.instances["Welle"].parameters == {"omega0": 200.0}
    assert back.instances["Stempel"].parameters == {"F30": 5.0, "c3": 200000.0}
    expected = load("punch_drive")
    expected.revolutions = 3
    for target, value in (("shaft.omega0", 200.0), ("punch.F30", 5.0), ("punch.c3", 2e5)):
        expected.set_value(target, value)
    assert _figures(back) == _figures(expected)


DOUBLER = '''
from pythonfmu import Fmi2Causality, Fmi2Slave, Real


class Doubler(Fmi2Slave):
    """Twice its input: an FMU that sewfmu did not build."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.u = 0.0
        self.y = 0.0
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.y = 2.0 * self.u
        return True
'''

SYSTEM = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="1.0" name="twice">
  <ssd:System name="twice">
    <ssd:Elements>
      <ssd:Component name="motor" source="resources/MainShaft.fmu"
          type="application/x-fmu-sharedlibrary"/>
      <ssd:Component name="x2" source="resources/Doubler.fmu"
          type="application/x-fmu-sharedlibrary"/>
    </ssd:Elements>
    <ssd:Connections>
      <ssd:Connection startElement="motor" startConnector="omega" endElement="x2"
          endConnector="u"/>
    </ssd:Connections>
  </ssd:System>
  <ssd:DefaultExperiment startTime="0" stopTime="0.01"/>
</ssd:SystemStructureDescription>
"""


def test_an_fmu_that_sewfmu_did_not_build_runs(tmp_path, fmu_paths):
    (tmp_path / "Doubler.py").write_text(DOUBLER)
    subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f", "Doubler.py", "-d",
                    "built", "--no-external-tool"], cwd=tmp_path, check=True,
                   capture_output=True, timeout=300)
    ssp = tmp_path / "twice.ssp"
    with zipfile.ZipFile(ssp, "w") as z:
        z.writestr("SystemStructure.ssd", SYSTEM)
        z.write(fmu_paths["MainShaft"], "resources/MainShaft.fmu")
        z.write(tmp_path / "built" / "Doubler.fmu", "resources/Doubler.fmu")
    out = tmp_path / "out"
    assert main(["run", str(ssp), "--set", "experiment.step=1e-3", "--out", str(out)]) == 0
    result = (out / "results.csv").read_text().splitlines()
    header = [name.split(" [")[0] for name in result[0].split(",")]   # "name [unit]"
    last = dict(zip(header, map(float, result[-1].split(","))))
    assert last["x2.y"] == pytest.approx(2 * last["motor.omega"])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["provenance"]["instances"]["x2"]["fmu"] == "Doubler"


def _broken(tmp_path, edit=None, drop=None, raw=None):
    sc = load("punch_drive")
    sc.revolutions = 1
    ssp = export(sc, tmp_path / "good.ssp")
    if raw is not None:
        (tmp_path / "bad.ssp").write_bytes(raw)
        return tmp_path / "bad.ssp"
    with zipfile.ZipFile(ssp) as src, zipfile.ZipFile(tmp_path / "bad.ssp", "w") as dst:
        for item in src.infolist():
            if drop and item.filename == drop:
                continue
            data = src.read(item)
            if edit and item.filename == "SystemStructure.ssd":
                data = edit(data.decode("utf-8")).encode("utf-8")
            dst.writestr(item, data)
    return tmp_path / "bad.ssp"


@pytest.mark.parametrize("case, words", [
    (dict(drop="resources/PunchContact.fmu"), ["component punch", "PunchContact.fmu",
                                               "not in the archive"]),
    (dict(edit=lambda t: t.replace('startConnector="xi"', 'startConnector="xii"')),
     ["linkage", "has no output 'xii'"]),
    (dict(edit=lambda t: t.replace('startElement="shaft" startConnector="phi"',
                                   'startElement="shaft" startConnector="omega"')),
     ["incompatible units", "rad/s", "rad"]),
    (dict(edit=lambda t: t.replace("</ssd:System>", "</ssd:Sys>")), ["not well-formed XML"]),
    (dict(drop="SystemStructure.ssd"), ["no SystemStructure.ssd"]),
    (dict(raw=b"not a zip at all"), ["not an SSP archive"]),
    (dict(edit=lambda t: re.sub(r'<ssd:DefaultExperiment[^>]*>', "<ssd:DefaultExperiment>", t)),
     ["DefaultExperiment stopTime"]),
    (dict(edit=lambda t: t.replace('endElement="punch"', 'endElement="ram"', 1)),
     ["no component 'ram'"]),
])
def test_a_broken_ssp_gets_one_clear_line(tmp_path, capsys, case, words):
    bad = _broken(tmp_path, **case)
    assert main(["run", str(bad), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, err


def test_an_ssp_without_a_step_asks_for_one(tmp_path, capsys):
    bad = _broken(tmp_path, edit=lambda t: re.sub(r"<ssd:Annotations>.*?</ssd:Annotations>", "",
                                                  t, flags=re.S))
    assert main(["run", str(bad), "--out", str(tmp_path / "out")]) == 1
    assert "--set experiment.step" in capsys.readouterr().err
    assert main(["run", str(bad), "--set", "experiment.step=2.5e-4",
                 "--out", str(tmp_path / "out")]) == 0
