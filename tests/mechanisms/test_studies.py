"""The studies are scenarios like the others: listed, shown, run with --set (command line and
API), swept; their figures for a design set by --set agree with a co-simulation of the same
design (the catalogue's scenario of that mechanism), which reaches them another way."""
import json

import pytest

import sewfmu
from sewfmu.cli import main

STUDIES = ("carriage_resonance", "feed_ratio", "takeup_tolerance")


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


def test_the_studies_are_in_the_catalogue_and_show_their_parameters():
    assert set(STUDIES) <= set(sewfmu.catalogue())
    for name in STUDIES:
        assert f'study = "{name}"' in sewfmu.show(name)
        rows = sewfmu.parameters(name)
        assert rows and all({"instance", "parameter", "unit"} <= set(r) for r in rows)
    table = sewfmu.parameters("takeup_tolerance", set={"takeup.L_AB": "10.5 mm"})
    assert next(r for r in table if r["parameter"] == "L_AB")["value"] == pytest.approx(0.0105)


@pytest.mark.slow
def test_the_take_up_stroke_of_a_design_set_by_set_agrees_with_its_co_simulation():
    study = sewfmu.run("takeup_tolerance", set={"takeup.L_AB": "10.5 mm"})
    assert study.series is None and study.study["links"]
    cosim = sewfmu.run("takeup", set={"takeup.L_AB": "10.5 mm"})
    # the study samples E every 0.5° of crank, as the co-simulation's step does
    assert study.figures["nominal_stroke_mm"] == pytest.approx(cosim.figures["stroke_mm"],
                                                               rel=1e-6)
    assert study.units["nominal_stroke_mm"] == "mm"
    default = sewfmu.run("takeup_tolerance").figures["nominal_stroke_mm"]
    assert default > study.figures["nominal_stroke_mm"] + 2.0       # a shorter crank: less


@pytest.mark.slow
def test_the_carriage_of_a_design_set_by_set_agrees_with_its_co_simulation():
    given = {"carriage.EJ": 5000.0, "shaft.omega0": "1400 rpm"}
    study = sewfmu.run("carriage_resonance", set=given)
    cosim = sewfmu.run("carriage_startstop", set={**given, "experiment.revolutions": 2})
    assert study.figures["omega1"] == pytest.approx(cosim.figures["omega1"], rel=1e-12)
    assert study.figures["machine_stitch_rate"] == pytest.approx(1400.0, rel=1e-12)
    designs = study.study["designs"]
    assert designs["traverse twice as stiff (EJ × 2)"]["parameters"] == {"EJ": 10000.0}


@pytest.mark.slow
def test_the_feed_ratios_follow_the_lever_set():
    study = sewfmu.run("feed_ratio", set={"feed.l4": "10 mm"})
    l5 = next(r for r in sewfmu.parameters("feed_ratio") if r["parameter"] == "l5")["value"]
    assert study.figures["l5_over_l4"] == pytest.approx(l5 / 0.010, rel=1e-12)
    cosim = sewfmu.run("feed", set={"feed.l4": "10 mm"})
    assert study.figures["phi5_amplitude_deg"] == pytest.approx(cosim.figures["phi5_swing_deg"],
                                                                abs=0.01)


@pytest.mark.slow
def test_a_study_on_the_command_line_takes_set_and_writes_its_files(tmp_path, capsys):
    out = tmp_path / "t"
    assert main(["run", "takeup_tolerance", "--set", "takeup.L_AB=10.5 mm", "--out", str(out),
                 "--plot"]) == 0
    printed = capsys.readouterr().out
    assert "nominal_stroke_mm" in printed and " mm" in printed and "files:" in printed
    summary = json.loads((out / "summary.json").read_text())
    assert summary["study"] == "takeup_tolerance" and summary["units"]["nominal_stroke_mm"] == "mm"
    assert {"study.json", "summary.json", "takeup_tolerance.png"} <= {p.name for p in out.iterdir()}


@pytest.mark.slow
def test_a_study_refuses_what_it_cannot_do(tmp_path, capsys):
    assert main(["run", "feed_ratio", "--set", "feed.l44=0.01"]) == 1
    assert "did you mean 'l4'" in capsys.readouterr().err
    with pytest.raises(sewfmu.ScenarioError, match="no time series"):
        sewfmu.run("takeup_tolerance").revolution()
    with pytest.raises(sewfmu.ScenarioError, match="computed, not a run of the mechanism"):
        sewfmu.run("takeup_tolerance", out=tmp_path / "a", animate=True)
    # a design that cannot be assembled: one line naming it
    with pytest.raises(sewfmu.ScenarioError, match="takeup_tolerance: .*assembled"):
        sewfmu.run("takeup_tolerance", set={"takeup.L_CD": "8 mm"})


def test_a_study_file_names_a_study_of_its_analysis(tmp_path):
    text = sewfmu.show("takeup_tolerance").replace('study = "takeup_tolerance"',
                                                   'study = "takeup_tolerence"')
    (tmp_path / "s.toml").write_text(text)
    with pytest.raises(sewfmu.ScenarioError, match="did you mean 'takeup_tolerance'"):
        sewfmu.load(tmp_path / "s.toml")


@pytest.mark.slow
def test_a_study_is_swept_like_a_scenario(tmp_path):
    sweep = sewfmu.sweep("takeup_tolerance", grid={"takeup.L_AB": ["10.5 mm", "11 mm"]},
                         workers=1, out=tmp_path, plot=True)
    assert [r["status"] for r in sweep.rows] == ["ok", "ok"]
    stroke = sweep.table["nominal_stroke_mm"]
    assert stroke[0] < stroke[1] and sweep.units["nominal_stroke_mm"] == "mm"
    assert (tmp_path / "takeup_tolerance_sweep.png").stat().st_size > 1000


def test_every_study_of_every_analysis_has_its_catalogue_scenario():
    from sewfmu.scenarios.mechanisms import studies

    for name, (analysis, _) in studies().items():
        scenario = sewfmu.load(name)
        assert (scenario.study, scenario.analysis) == (name, analysis)
