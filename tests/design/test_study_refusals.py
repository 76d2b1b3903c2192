"""What a design study refuses before its first run, each in one line and exit 1: more runs than
the bound (counted from its settings alone: samples times the group, the budget of
evaluations; --max-runs, max_runs= or SEWFMU_MAX_RUNS raise it), a parameter both fixed
(--set) and varied (--vary, --free), a bound outside the range the model accepts (a positive
parameter's 0 included), bounds equal or reversed, a bound that is no finite number. Every run
and the sampling itself fail the test if reached."""
import math
import re

import pytest

import sewfmu
from sewfmu.cli import main


@pytest.fixture(autouse=True)
def _fmus(fmus_of_this_session):
    pass


def _data(tmp_path) -> str:
    path = tmp_path / "data.csv"
    path.write_text("time,punch.F2\n0.0,0.0\n0.01,1.0\n")
    return str(path)


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("sewfmu: error: "), err
    return err[0]


# --- more runs than the bound ------------------------------------------------------------------
# the counts, worked out here from what each method runs: Saltelli's scheme N·(D+2) (first and
# total order), Morris N·(D+1), an optimizer its budget, a fit its budget of residuals each with
# a Jacobian of n runs, plus the first guess and the optimum's series
OVERSIZE = {
    "sobol": (["sensitivity", "punch_drive", "--vary", "punch.F10=15..40", "--figure",
               "F2_peak", "--samples", str(2 ** 24)], 2 ** 24 * (1 + 2)),
    "morris": (["sensitivity", "punch_drive", "--vary", "punch.F10=15..40", "--vary",
                "punch.F30=0..10", "--figure", "F2_peak", "--method", "morris", "--samples",
                "5000"], 5000 * (2 + 1)),
    "local": (["optimize", "punch_drive", "--vary", "punch.F10=15..40", "--minimize",
               "F2_peak", "--max-evaluations", "10001"], 10001),
    "global": (["optimize", "punch_drive", "--vary", "punch.F10=15..40", "--minimize",
                "F2_peak", "--method", "global", "--max-evaluations", "50000"], 50000),
    "fit": (["fit", "punch_drive", "--data", "DATA", "--free", "punch.c2=2e4..1.5e5", "--free",
             "punch.b2=20..300", "--max-evaluations", "4000"], 4000 * (2 + 1) + 2),
}


@pytest.mark.parametrize("case", list(OVERSIZE))
def test_a_study_over_the_bound_is_refused_before_any_run(case, capsys, tmp_path, no_runs):
    argv, runs = OVERSIZE[case]
    argv = [_data(tmp_path) if a == "DATA" else a for a in argv]
    assert main(argv + ["--out", str(tmp_path / "out")]) == 1
    line = _one_line(capsys)
    assert f": {runs:,} runs (" in line and "more than the 10,000" in line, line
    assert "--max-runs N" in line and "SEWFMU_MAX_RUNS" in line, line
    assert not (tmp_path / "out").exists()


def test_the_bound_is_raised_by_the_option_the_argument_or_the_environment(
        capsys, tmp_path, monkeypatch, no_runs):
    monkeypatch.chdir(tmp_path)         # its default folder, results/..., a new one
    argv = OVERSIZE["local"][0]
    # raised: the same study goes on to its first run (here the test's stand-in, which fails),
    # saying first what it will take, --quiet or not, since that is long
    assert main(argv + ["--max-runs", "10001", "--quiet"]) == 1
    said, failed = capsys.readouterr().err.strip().splitlines()
    assert said.startswith("sewfmu: optimize punch_drive: at most 10,001 runs, about ")
    assert "was made before the refusal" in failed
    with pytest.raises(AssertionError, match="a run"):
        sewfmu.optimize("punch_drive", vary={"punch.F10": (15, 40)}, minimize="F2_peak",
                        max_evaluations=10001, max_runs=20000)
    monkeypatch.setenv("SEWFMU_MAX_RUNS", "10001")
    with pytest.raises(AssertionError, match="a run"):
        sewfmu.optimize("punch_drive", vary={"punch.F10": (15, 40)}, minimize="F2_peak",
                        max_evaluations=10001)
    # lowered: a small study is over it
    monkeypatch.setenv("SEWFMU_MAX_RUNS", "5")
    with pytest.raises(sewfmu.ScenarioError, match=r": 6 runs \(--samples 2 × 3 runs a "
                                                   r"trajectory\).* more than the 5 "):
        sewfmu.sensitivity("punch_drive", vary={"punch.F10": (15, 40), "punch.F30": (0, 10)},
                           figures=["F2_peak"], method="morris", samples=2)
    for bad in ("0", "many"):
        monkeypatch.setenv("SEWFMU_MAX_RUNS", bad)
        with pytest.raises(sewfmu.ScenarioError, match="SEWFMU_MAX_RUNS=.*whole number"):
            sewfmu.optimize("punch_drive", vary={"punch.F10": (15, 40)}, minimize="F2_peak")


def test_the_count_and_an_estimate_are_said_before_the_first_run(capsys, monkeypatch):
    """A 200-run local optimization of punch_drive: its ten revolutions at 100 rad/s in steps of
    0.25 ms are 2514 steps of three FMUs; at runs/budget.py's cost per FMU and step (50 µs) and
    start (0.05 s) each run is about 0.43 s, the study at most 200 of them: about 86 s."""
    said = []

    def first(*_, **__):
        said.append(capsys.readouterr().err)
        raise KeyboardInterrupt

    from sewfmu.scenarios.design import evaluations

    monkeypatch.setattr(evaluations, "evaluate_point", first)
    steps = math.ceil(10 * 2 * math.pi / 100.0 / 2.5e-4 * (1 - 1e-12))
    per_run = 0.05 + steps * 3 * 50e-6
    with pytest.raises(KeyboardInterrupt):
        sewfmu.optimize("punch_drive", vary={"punch.F10": (15, 40)}, minimize="F2_peak",
                        progress=True)
    assert said == [f"sewfmu: optimize punch_drive: at most 200 runs, about "
                    f"{200 * per_run:.0f} s\n"], said


# --- a parameter both fixed and varied ----------------------------------------------------------
BOTH = {
    "fit": (["fit", "punch_drive", "--data", "DATA", "--free", "punch.c2=2e4..1.5e5", "--set",
             "punch.c2=5e4"], "punch.c2", "--free"),
    "optimize": (["optimize", "punch_drive", "--vary", "punch.F10=15..40", "--minimize",
                  "F2_peak", "--set", "punch.F10=20"], "punch.F10", "--vary"),
    "sensitivity": (["sensitivity", "punch_drive", "--vary", "shaft.omega0=900..1100 rpm",
                     "--figure", "F2_peak", "--set", "shaft.omega0=1000 rpm"], "shaft.omega0",
                    "--vary"),
}


@pytest.mark.parametrize("case", list(BOTH))
def test_a_parameter_both_fixed_and_free_is_refused(case, capsys, tmp_path, no_runs):
    argv, name, option = BOTH[case]
    assert main([_data(tmp_path) if a == "DATA" else a for a in argv]) == 1
    line = _one_line(capsys)
    assert f"{name} is both fixed (--set" in line and f"({option}, " in line, line
    with pytest.raises(sewfmu.ScenarioError, match=f"{name} is both fixed"):
        {"fit": lambda: sewfmu.fit("punch_drive", data=_data(tmp_path), set={name: 5e4},
                                   free={name: (2e4, 1.5e5)}),
         "optimize": lambda: sewfmu.optimize("punch_drive", vary={name: (15, 40)},
                                             minimize="F2_peak", set={f" {name}": 20.0}),
         "sensitivity": lambda: sewfmu.sensitivity("punch_drive", vary={name: (90, 110)},
                                                   figures=["F2_peak"], set={name: 100.0}),
         }[case]()


# --- bounds the model does not accept -----------------------------------------------------------
BOUNDS = {
    # MainShaft.omega0 is positive, within the declared [0, 2000] rad/s: 0 is refused by the
    # model as a value of --set is, so a range from 0 is refused before its first point
    "optimize from 0": (["optimize", "punch_drive", "--vary", "shaft.omega0=0..1000 rpm",
                         "--minimize", "F2_peak"],
                        "the lower bound 0 rad/s lies outside the range (0, 2000] rad/s"),
    "fit from 0": (["fit", "punch_drive", "--data", "DATA", "--free", "punch.c2=0..5e4"],
                   "the lower bound 0 N/m lies outside the range (0, 1e+09] N/m"),
    "sensitivity from 0": (["sensitivity", "punch_drive", "--vary", "punch.m=0..80 g",
                            "--figure", "F2_peak"], "the lower bound 0 kg lies outside"),
    "above the range": (["sensitivity", "punch_drive", "--vary", "shaft.omega0=100..30000 rpm",
                         "--figure", "F2_peak"], "the upper bound 3141.59 rad/s lies outside"),
    "equal bounds": (["optimize", "punch_drive", "--vary", "punch.F10=20..20", "--minimize",
                      "F2_peak"], "the lower bound 20 N is not below the upper bound 20 N"),
    "reversed": (["fit", "punch_drive", "--data", "DATA", "--free", "punch.c2=9e4..5e4"],
                 "the lower bound 90000 N/m is not below the upper bound 50000 N/m"),
    "not a number": (["optimize", "punch_drive", "--vary", "punch.F10=nan..20", "--minimize",
                      "F2_peak"], "the bound 'nan' is not a finite number"),
}


@pytest.mark.parametrize("case", list(BOUNDS))
def test_a_bound_the_model_does_not_accept_is_refused_before_any_run(case, capsys, tmp_path,
                                                                     no_runs):
    argv, said = BOUNDS[case]
    assert main([_data(tmp_path) if a == "DATA" else a for a in argv]) == 1
    line = _one_line(capsys)
    assert said in line, line


@pytest.mark.parametrize("bounds, said", [((math.nan, 20.0), "finite number"),
                                          ((10.0, math.inf), "finite number"),
                                          ((0.0, 40.0), "(0, 1e+09]"),
                                          ((30.0, 30.0), "is not below")])
def test_the_api_refuses_such_bounds_alike(bounds, said, no_runs):
    name = "punch.c1" if said == "(0, 1e+09]" else "punch.F10"
    with pytest.raises(sewfmu.ScenarioError, match=f"--vary {name}: .*{re.escape(said)}"):
        sewfmu.optimize("punch_drive", vary={name: bounds}, minimize="F2_peak")
