"""Design studies (scenarios/design/, docs/design.md): optimize, fit and sensitivity from Python
and the command line; their refusals (one line, exit 1) before anything runs; infeasible points
recorded with their reasons; a study run again into its folder resumes. The slow tests run the
design page's examples and check them against computations that do not use the design wing:
bisections over plain sewfmu.run calls, the known parameters of a synthetic trace, Sobol
indices that follow from which parameter enters a figure."""
import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

import sewfmu
from sewfmu.cli import main

SHORT = {"experiment.revolutions": 2}     # the punch's figures settle in its first revolution


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


def _force_trace(path: Path, revolutions: int = 1, **parameters) -> np.ndarray:
    r = sewfmu.run("punch_drive", set={"experiment.revolutions": revolutions, **parameters})
    t, f = r.series["time"], r.series["punch.F2"]
    with open(path, "w", newline="") as file:
        csv.writer(file).writerows([["time", "punch.F2 [N]"], *zip(t.tolist(), f.tolist())])
    return t


# --- refusals: one line, exit 1, nothing run ------------------------------------------------
def _data(tmp_path, header="time,punch.F2", rows=((0.0, 0.0), (0.01, 1.0))) -> str:
    path = tmp_path / "data.csv"
    path.write_text(header + "\n" + "".join(f"{a},{b}\n" for a, b in rows))
    return str(path)


REFUSALS = {
    "bounds in the wrong order": (["optimize", "punch_drive", "--vary", "punch.F10=40..15",
                                   "--target", "F2_weld_mean=25 N"], "is not below the upper"),
    "bound outside the declared range": (["optimize", "punch_drive", "--vary",
                                          "punch.F10=15..2e4 N", "--minimize", "F2_peak"],
                                         "outside the range [0, 10000] N"),
    "bound in a unit that does not fit": (["optimize", "punch_drive", "--vary",
                                           "punch.F10=15..40 kg", "--minimize", "F2_peak"],
                                          "'15 kg'"),
    "not a range": (["optimize", "punch_drive", "--vary", "punch.F10=15", "--minimize",
                     "F2_peak"], "expected LO..HI"),
    "unknown parameter": (["optimize", "punch_drive", "--vary", "punch.F1=15..40",
                           "--minimize", "F2_peak"], "did you mean 'F10'?"),
    "an integer parameter": (["optimize", "punch_drive", "--vary", "linkage.mode=0..1",
                              "--minimize", "F2_peak"], "only real parameters can be varied"),
    "unknown figure": (["optimize", "punch_drive", "--vary", "punch.F10=15..40",
                        "--target", "F2_weld_men=25 N"], "did you mean 'F2_weld_mean'?"),
    "unknown constraint figure": (["optimize", "punch_drive", "--vary", "punch.F10=15..40",
                                   "--minimize", "F2_peak", "--constraint", "F2_wld<=3"],
                                  "unknown key figure 'F2_wld'"),
    "constraint in a wrong unit": (["optimize", "punch_drive", "--vary", "punch.F10=15..40",
                                    "--minimize", "F2_peak", "--constraint", "F2_peak<=3 mm"],
                                   "F2_peak = '3 mm': mm is a length"),
    "unknown sensitivity figure": (["sensitivity", "punch_drive", "--vary", "punch.F10=15..40",
                                    "--figure", "F2_pek"], "did you mean 'F2_peak'?"),
    "Sobol samples not a power of 2": (["sensitivity", "punch_drive", "--vary",
                                        "punch.F10=15..40", "--figure", "F2_peak", "--samples",
                                        "12"], "power of 2"),
}


@pytest.mark.parametrize("case", list(REFUSALS))
def test_a_bad_study_is_one_line_and_exit_1(case, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv, expected = REFUSALS[case]
    assert main(argv) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("sewfmu: error: ") and expected in err[0], err
    assert not (tmp_path / "results").exists()         # refused before anything was written


DATA_REFUSALS = {
    "unknown column": ({"header": "time,punch.F3x"}, "column 'punch.F3x' is not an output",
                       "did you mean 'punch.F3'?"),
    "no time column": ({"header": "t,punch.F2"}, "no 'time' column", ""),
    "data before the run": ({"rows": ((-0.01, 0.0), (0.01, 1.0))}, "before the run starts", ""),
    "data past the run's end": ({"rows": ((0.0, 0.0), (5.0, 1.0))}, "past the run's end", ""),
    "a column in another unit": ({"header": "time,punch.F2 [kN]"}, "the output is in 'N'", ""),
    "times not increasing": ({"rows": ((0.02, 0.0), (0.01, 1.0))}, "increasing", ""),
}


@pytest.mark.parametrize("case", list(DATA_REFUSALS))
def test_bad_data_for_a_fit_is_one_line_and_exit_1(case, capsys, tmp_path):
    given, expected, hint = DATA_REFUSALS[case]
    argv = ["fit", "punch_drive", "--data", _data(tmp_path, **given), "--free",
            "punch.c2=2e4..1.5e5", "--out", str(tmp_path / "out")]
    if case == "data past the run's end":          # the study fixes the run's end
        argv += ["--set", "experiment.revolutions=2"]
    assert main(argv) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and expected in err[0] and hint in err[0], err


def test_the_api_refuses_what_the_command_line_refuses():
    with pytest.raises(sewfmu.ScenarioError, match="give one goal"):
        sewfmu.optimize("punch_drive", vary={"punch.F10": (15.0, 40.0)}, minimize="F2_peak",
                        maximize="F2_peak")
    with pytest.raises(sewfmu.ScenarioError, match="only parameters of instances"):
        sewfmu.optimize("punch_drive", vary={"experiment.step": (1e-4, 1e-3)},
                        minimize="F2_peak")
    with pytest.raises(sewfmu.ScenarioError, match="no analysis|compares several runs"):
        sewfmu.optimize("punch_speed", vary={"punch.F10": (15.0, 40.0)}, minimize="F2_peak")


# --- what runs: fast, a few short runs each ---------------------------------------------------
@pytest.mark.slow
def test_a_target_is_met_and_a_study_run_again_resumes(tmp_path):
    out = tmp_path / "preload"
    found = sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"},
                            target={"F2_weld_mean": "25 N"}, set=SHORT, out=out, plot=True)
    assert found.algorithm == "brentq" and found.converged and found.feasible
    assert found.figures["F2_weld_mean"] == pytest.approx(25.0, abs=1e-3)
    assert found.units["punch.F10"] == "N" and 15.0 < found.best["punch.F10"] < 40.0
    assert found.computed == len(found.evaluations) <= 12
    summary = json.loads((out / "optimize.json").read_text())
    assert summary["best"] == found.best and summary["target"] == {"F2_weld_mean": 25.0}
    assert (out / "convergence.png").stat().st_size > 1000
    with open(out / "evaluations.csv") as f:
        rows = list(csv.DictReader(f))
    assert [float(r["punch.F10"]) for r in rows] == list(found.evaluations["punch.F10"])
    assert {r["status"] for r in rows} == {"ok"} and all(r["F2_weld_mean"] for r in rows)

    again = sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"},
                            target={"F2_weld_mean": "25 N"}, set=SHORT, out=out)
    assert again.computed == 0 and again.best == found.best          # nothing run again
    # an interrupted study: its record listed before the first run (as a study does), then
    # two evaluations appended and the last line torn
    from sewfmu.scenarios.files.outputs import Record, claim  # as the study writes it

    lines = (out / "evaluations.csv").read_text().splitlines(keepends=True)
    (tmp_path / "killed").mkdir()
    claim(tmp_path / "killed", ["evaluations.csv"])
    with Record(tmp_path / "killed" / "evaluations.csv") as record:
        record.write("".join(lines[:3]) + lines[3][:25])
    resumed = sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N"},
                              target={"F2_weld_mean": "25 N"}, set=SHORT,
                              out=tmp_path / "killed")
    assert resumed.computed == len(found.evaluations) - 2 and resumed.best == found.best


def test_an_infeasible_point_is_recorded_with_its_reason_not_a_number(tmp_path):
    found = sewfmu.optimize("punch_drive", vary={"linkage.L_AB": "29..39 mm"},
                            target={"F2_weld_mean": "23 N"}, set=SHORT, max_evaluations=4,
                            out=tmp_path)
    statuses = list(found.evaluations["status"])
    assert statuses[0] == "infeasible" and "ok" in statuses and not found.converged
    assert "cannot be assembled" in found.evaluations["error"][0]
    assert np.isnan(found.evaluations["F2_weld_mean"][0])
    with open(tmp_path / "evaluations.csv") as f:
        first = next(csv.DictReader(f))
    assert first["status"] == "infeasible" and first["F2_weld_mean"] == ""
    assert "cannot be assembled" in first["error"]


@pytest.mark.slow
def test_a_fit_recovers_a_parameter_from_its_own_trace(tmp_path):
    _force_trace(tmp_path / "trace.csv", **{"punch.b2": 70.0})
    fit = sewfmu.fit("punch_drive", data=tmp_path / "trace.csv", free={"punch.b2": "20..300"},
                     out=tmp_path / "fit")
    assert fit.converged and fit.estimates["punch.b2"] == pytest.approx(70.0, rel=1e-6)
    assert fit.residual_rms["punch.F2"] < 1e-6 and fit.units["punch.b2"] == "N.s/m"
    assert fit.residuals.dtype.names == ("time", "punch.F2")
    summary = json.loads((tmp_path / "fit" / "fit.json").read_text())
    assert summary["estimates"] == fit.estimates and "standard_errors" in summary
    assert (tmp_path / "fit" / "fit.png").exists()


@pytest.mark.slow
def test_a_sensitivity_runs_its_samples_as_a_sweep(tmp_path):
    s = sewfmu.sensitivity("punch_drive", vary={"punch.F10": "15..40 N", "shaft.omega0":
                                                "900..1100 rpm"},
                           figures=["F2_weld_mean"], method="morris", samples=2, set=SHORT,
                           workers=2, out=tmp_path)
    assert s.runs == 6 and not s.failed
    assert list(s.table["parameter"]) == ["punch.F10", "shaft.omega0"]    # F10 ranks first
    assert s.table["mu_star"][0] > s.table["mu_star"][1] > 0
    summary = json.loads((tmp_path / "sensitivity.json").read_text())
    assert summary["figures"]["F2_weld_mean"]["ranking"] == ["punch.F10", "shaft.omega0"]
    assert (tmp_path / "sensitivity_F2_weld_mean.png").exists()
    assert (tmp_path / "sweep.csv").exists() and (tmp_path / "points.jsonl").exists()


# --- the design page, checked against independent computations (slow) -----------------------
def _bisect(f, lo: float, hi: float, tol: float) -> float:
    """A root of f between lo and hi, by bisection: sign changes only, no design wing."""
    f_lo = f(lo)
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if (f(mid) > 0) == (f_lo > 0):
            lo, f_lo = mid, f(mid)
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _figure(name: str, **parameters) -> float:
    return sewfmu.run("punch_drive", set={"experiment.revolutions": 3, **parameters}) \
        .figures[name]


@pytest.fixture(scope="module")
def page(design_page):
    """docs/design.md's examples as a user runs them: one script, a fresh process, an empty
    folder (tests/conftest.py's design_page); the names they define."""
    return design_page


@pytest.mark.slow
def test_the_preload_for_a_welding_force_matches_a_bisection_of_plain_runs(page):
    found = page["preload"].best["punch.F10"]
    bisected = _bisect(lambda f10: _figure("F2_weld_mean", **{"punch.F10": f10}) - 25.0,
                       15.0, 40.0, 0.01)
    assert found == pytest.approx(bisected, rel=0.005)


@pytest.mark.slow
def test_the_constrained_optimum_lies_on_its_constraint(page):
    weld = page["weld"]
    f10, f30 = weld.best["punch.F10"], weld.best["punch.F30"]
    assert weld.feasible and weld.algorithm == "SLSQP"
    assert weld.figures["F2_peak"] == pytest.approx(25.0, rel=1e-4)       # active
    assert f30 <= 0.005 * 20.0                                            # at its lower bound
    # without the constraint the duration would grow further: the constraint is what stops it
    assert _figure("contact_duration_deg", **{"punch.F10": 40.0}) > \
        weld.figures["contact_duration_deg"]
    bisected = _bisect(lambda f10: _figure("F2_peak", **{"punch.F10": f10}) - 25.0,
                       10.0, 40.0, 0.01)
    assert f10 == pytest.approx(bisected, rel=0.005)


@pytest.mark.slow
def test_the_fabric_is_recovered_from_its_noisy_force_trace(page):
    fabric, truth = page["fabric"], page["truth"]
    assert fabric.converged
    for name, value in truth.items():
        error = abs(fabric.estimates[name] - value)
        assert error <= 0.03 * value and error <= 2 * fabric.standard_errors[name], name


@pytest.mark.slow
def test_sobol_indices_say_which_parameter_enters_the_stroke(page):
    s = page["stroke"].indices["stroke_mm"]
    crank, speed = s["takeup.L_AB"], s["shaft.omega0"]
    # the stroke is geometry: it depends on the crank alone among the two, so S1 = ST = 1 for
    # the crank and 0 for the speed (first checked directly, from two plain runs)
    runs = [sewfmu.run("takeup", set={"experiment.revolutions": 1, "shaft.omega0": speed_})
            .figures["stroke_mm"] for speed_ in ("4000 rpm", "6000 rpm")]
    assert runs[0] == pytest.approx(runs[1], rel=1e-4)
    assert abs(crank["S1"] - 1.0) <= crank["S1_conf"] and abs(crank["ST"] - 1.0) <= crank["ST_conf"]
    assert abs(speed["S1"]) <= speed["S1_conf"] and speed["ST"] <= max(speed["ST_conf"], 1e-3)


@pytest.mark.slow
def test_the_global_method_finds_the_same_with_one_worker_or_two(tmp_path):
    kwargs = dict(vary={"punch.F10": "15..40 N"}, target={"F2_weld_mean": "25 N"}, set=SHORT,
                  method="global", max_evaluations=30)
    one = sewfmu.optimize("punch_drive", workers=1, **kwargs)
    two = sewfmu.optimize("punch_drive", workers=2, out=tmp_path, **kwargs)
    assert one.best == two.best and one.algorithm == "differential_evolution"
    assert np.array_equal(one.evaluations["punch.F10"], two.evaluations["punch.F10"])
    assert two.figures["F2_weld_mean"] == pytest.approx(25.0, rel=0.01)


@pytest.mark.slow
def test_nelder_mead_finds_the_point_whose_figures_it_is_given():
    given = {"punch.F10": 30.0, "punch.c2": 8.0e4}
    figures = sewfmu.run("punch_drive", set={**SHORT, **given}).figures
    found = sewfmu.optimize("punch_drive", vary={"punch.F10": "15..40 N",
                                                 "punch.c2": "2e4..1.5e5 N/m"},
                            target={k: figures[k] for k in ("F2_weld_mean",
                                                            "contact_duration_deg")}, set=SHORT)
    assert found.algorithm == "Nelder-Mead" and found.converged
    for name, value in given.items():
        assert found.best[name] == pytest.approx(value, rel=0.005)


@pytest.mark.slow
def test_the_commands_write_their_files(tmp_path, capsys):
    trace = tmp_path / "trace.csv"
    _force_trace(trace, **{"punch.c2": 7e4})
    assert main(["optimize", "punch_drive", "--vary", "punch.F10=15..40 N", "--target",
                 "F2_weld_mean=25 N", "--set", "experiment.revolutions=2", "--out",
                 str(tmp_path / "o"), "--plot"]) == 0
    assert main(["fit", "punch_drive", "--data", str(trace), "--free", "punch.c2=2e4..1.5e5",
                 "--out", str(tmp_path / "f")]) == 0
    assert main(["sensitivity", "punch_drive", "--vary", "punch.F10=15..40", "--vary",
                 "punch.F30=0..10", "--figure", "F2_peak", "--method", "morris", "--samples",
                 "2", "--set", "experiment.revolutions=2", "--workers", "2", "--quiet",
                 "--out", str(tmp_path / "s")]) == 0
    printed = capsys.readouterr().out
    assert re.search(r"punch\.F10 +26\.\d+ N", printed) and "punch.c2 = 70000" in printed
    for name in ("o/optimize.json", "o/evaluations.csv", "o/convergence.png", "f/fit.json",
                 "f/fit.png", "s/sensitivity.json", "s/sensitivity_F2_peak.png"):
        assert (tmp_path / name).exists(), name


@pytest.mark.parametrize("header, row, said", [
    ("time,punch.F2 [N],punch.F2", "0.01,1.0,2.0", "given twice"),
    ("time,punch.F2 [N]", "0.01,inf", "not a measurement"),
])
def test_fit_data_that_would_mislead_is_refused_in_one_line(tmp_path, header, row, said):
    """Found by the attack: a column given twice was fitted to the second (silently wrong);
    an inf cell crashed the fit."""
    from sewfmu.scenarios.design.fit import read_data

    data = tmp_path / "d.csv"
    data.write_text(f"{header}\n0.0,{row.split(',', 1)[1]}\n{row}\n", encoding="utf-8")
    with pytest.raises(sewfmu.ScenarioError, match=said):
        read_data(data)
