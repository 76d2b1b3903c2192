"""The bound of a run's coupling error (scenarios/runs/accuracy.py) is the documented formula:
own f = 7 · Δf + σf, Δf the coarser run's difference (under a fixed step, against the run read
on the coarser run's samples; under the adaptive master over (r**0.5 − 1), r its tolerance's
ratio), σf the larger change of f when the run's samples are read every other one, and ±f the
largest own of the figures of f's unit, each relative to its figure. Checked on fake FMUs (a
harmonic oscillator, tests/fake_fmu.py) whose samples under Jacobi have a closed form, so that a
factor, a divisor or an order changed without measuring them again (bench/estimate_bounds.py
--scan) fails here; and the hardest runs that scan found stay bounded. In milliseconds, no FMU."""
from types import SimpleNamespace

import numpy as np
import pytest

from sewfmu.console import print_run
from sewfmu.scenarios.cosim.master import Master
from sewfmu.scenarios.mechanisms.base import Mechanism
from sewfmu.scenarios.runs import accuracy
from sewfmu.scenarios.runs.runner import summarize
from tests.fake_fmu import Integrator, fake_scenario, maker

M = np.array([[0.0, 1.0], [-1.0, 0.0]])          # a' = b, b' = -a: a = cos t, b = -sin t
LOOP = ["b.x -> a.u", "b.x_dot -> a.u_dot", "a.x -> b.u", "a.x_dot -> b.u_dot"]
STOP, FROM = 8.0, 4.0                              # the peak is read over [4, 8]: cos(2π) = 1


class Oscillator(Mechanism):
    """Three figures, two of one unit: the end value and the sampled peak of a, the end of b."""
    name = "oscillator"
    figures = {"a_end": "m", "a_peak": "m", "b_end": "m/s"}

    def summary_of_run(self, result) -> dict:
        late = result.time >= FROM - 1e-12
        return {"a_end": float(result["a.x"][-1]), "a_peak": float(result["a.x"][late].max()),
                "b_end": float(result["b.x"][-1])}


def oscillator(master: str, step: float, **experiment):
    sc = fake_scenario(fresh(), LOOP, STOP, step, master, **experiment)
    sc.analysis, sc.mechanism = "oscillator", Oscillator()
    return sc


def fresh():
    return {"a": Integrator(gain=1.0, x0=1.0), "b": Integrator(gain=-1.0)}


def run(sc):
    return Master(sc, {}, make_instance=maker(fresh())).run()


@pytest.fixture
def fakes(monkeypatch):
    """The coarser run of accuracy.estimate made on fake instances too."""
    monkeypatch.setattr(accuracy, "simulate", lambda sc, fmu_dir=None: run(sc))


def jacobi_samples(h: float, n: int) -> np.ndarray:
    """(a, b) at the n + 1 communication points: Jacobi with the exchanged rates is the
    second-order Taylor step z <- (I + hM + h²M²/2) z (tests/cosim/test_master_loop.py)."""
    step = np.eye(2) + h * M + h * h / 2 * M @ M
    z = [np.array([1.0, 0.0])]
    for _ in range(n):
        z.append(step @ z[-1])
    return np.array(z)


def figures(t: np.ndarray, z: np.ndarray) -> dict:
    late = t >= FROM - 1e-12
    return {"a_end": z[-1, 0], "a_peak": z[late, 0].max(), "b_end": z[-1, 1]}


def test_the_bound_under_jacobi_is_the_formula_on_the_closed_form(fakes):
    h, n = 0.1, 80
    sc = oscillator("jacobi", h)
    result = run(sc)
    found = accuracy.estimate(sc, result, summarize(result))
    t, z = np.arange(n + 1) * h, jacobi_samples(h, n)
    fine = figures(t, z)
    coarse = figures(np.arange(n // 2 + 1) * 2 * h, jacobi_samples(2 * h, n // 2))
    thinned = [figures(t[k], z[k]) for k in (np.r_[0:n + 1:2], np.r_[0, 1:n:2, n])]
    # the coupling: the coarser run against the run read where the coarser run has its samples
    delta = {f: abs(thinned[0][f] - coarse[f]) / (2.0 ** 1.0 - 1.0) for f in fine}
    sigma = {f: max(abs(fine[f] - s[f]) for s in thinned) for f in fine}
    assert sigma["a_peak"] > 0 and sigma["a_end"] == 0.0      # the peak moves with the samples
    own = {f: 7.0 * delta[f] + 1.0 * sigma[f] for f in fine}
    expected = {f: max(own[f], abs(fine[f]) * max(own[g] / abs(fine[g]) for g in unit))
                for unit in (("a_end", "a_peak"), ("b_end",)) for f in unit}
    assert found["figures"] == pytest.approx(expected, rel=1e-9)
    assert "untrusted" not in found and found["method"].startswith("the run at twice the step")
    # it bounds the error of a against the exact solution, a's two figures making up for each
    # other; b's end value, alone in its unit, shows what no two runs can see: its error at h is
    # that at 2h (0.00103 against 0.00116; its phase and amplitude errors, of orders 2 and 3,
    # cancel in between), so their difference is a tenth of it (docs/running.md)
    exact = {"a_end": np.cos(STOP), "a_peak": 1.0, "b_end": -np.sin(STOP)}
    for f in ("a_end", "a_peak"):
        assert abs(fine[f] - exact[f]) <= found["figures"][f], f
    assert abs(fine["b_end"] - exact["b_end"]) == pytest.approx(0.0010337, abs=1e-7)
    assert abs(coarse["b_end"] + np.sin(STOP)) == pytest.approx(0.0011623, abs=1e-7)
    assert found["figures"]["b_end"] < abs(fine["b_end"] - exact["b_end"])


def test_the_adaptive_masters_divisor_is_its_tolerance_ratio_to_the_power_05(fakes):
    sc = oscillator("adaptive", 0.1, tolerance=1e-4)
    result = run(sc)
    found = accuracy.estimate(sc, result, summarize(result))
    assert found["method"].startswith("the run at tolerance 0.0008")
    fine, coarse = summarize(result), summarize(run(oscillator("adaptive", 0.1, tolerance=8e-4)))
    n = len(result.time)
    thinned = [summarize(type(result)(result.scenario, result.time[k],
                                      {c: v[k] for c, v in result.columns.items()}, 0.0))
               for k in (np.unique(np.r_[0:n:2, n - 1]), np.unique(np.r_[0, 1:n:2, n - 1]))]
    divisor = 8.0 ** 0.5 - 1.0                     # 1.83: the measured order, not 7
    own = {f: 7.0 * abs(fine[f] - coarse[f]) / divisor
           + 1.0 * max(abs(fine[f] - s[f]) for s in thinned) for f in ("a_end", "a_peak", "b_end")}
    bound = {f: max(own[f], abs(fine[f]) * max(own[g] / abs(fine[g]) for g in unit))
             for unit in (("a_end", "a_peak"), ("b_end",)) for f in unit}
    assert found["figures"] == pytest.approx(bound, rel=1e-9)


def test_no_coarser_run_within_a_factor_2_of_the_loosest_tolerance(fakes):
    sc = oscillator("adaptive", 0.1, tolerance=6e-3)
    result = run(sc)
    found = accuracy.estimate(sc, result, summarize(result))
    assert found["figures"] == {} and "within a factor 2" in found["none"]
    assert accuracy.coarser(oscillator("adaptive", 0.1, tolerance=5e-3))[1] == 2.0


# Runs of the scans (bench/estimate_bounds.py --scan) whose true error came closest to their ±,
# one of each kind: the run's figures, the coarser run's, the two thinnings', the exact ones (the
# monolithic solution at rtol 1e-10; the carriage run at 1e-5 s). The first is the closest: its
# F2_peak ± is 1.02 times its error. SHORT is a run it misses, as docs/running.md says.
HARDEST = [{'what': 'punch_split jacobi 0.4585 ms',
  'kind': 'step',
  'ratio': 1.9985422740524783,
  'units': {'contact_onset_deg': 'deg',
            'contact_loss_deg': 'deg',
            'contact_duration_deg': 'deg',
            'F2_peak': 'N',
            'F2_weld_mean': 'N'},
  'run': {'contact_onset_deg': 111.21102434678231,
          'contact_loss_deg': 248.59585267777646,
          'contact_duration_deg': 137.38482833099414,
          'F2_peak': 24.419631208364493,
          'F2_weld_mean': 22.818714088460474},
  'coarse': {'contact_onset_deg': 111.29870739604034,
             'contact_loss_deg': 248.8935632456163,
             'contact_duration_deg': 137.59485584957594,
             'F2_peak': 24.38450666158229,
             'F2_weld_mean': 22.791907986698426},
  'thinned': [{'contact_onset_deg': 111.3621868415856,
               'contact_loss_deg': 248.65312395867372,
               'contact_duration_deg': 137.2909371170881,
               'F2_peak': 24.419631208364493,
               'F2_weld_mean': 22.8111178807653},
              {'contact_onset_deg': 111.25444810894562,
               'contact_loss_deg': 249.1072858764878,
               'contact_duration_deg': 137.85283776754216,
               'F2_peak': 24.419631208364493,
               'F2_weld_mean': 22.807345345758208}],
  'exact': {'contact_onset_deg': 111.1936562549915,
            'contact_loss_deg': 248.5356074484866,
            'contact_duration_deg': 137.3419511934951,
            'F2_peak': 24.17933625742365,
            'F2_weld_mean': 22.822991999230265}},
 {'what': 'punch_drive jacobi 0.081 ms',
  'kind': 'step',
  'ratio': 2.0,
  'units': {'contact_onset_deg': 'deg',
            'contact_loss_deg': 'deg',
            'contact_duration_deg': 'deg',
            'F2_peak': 'N',
            'F2_weld_mean': 'N'},
  'run': {'contact_onset_deg': 111.19808677052247,
          'contact_loss_deg': 248.5410283886778,
          'contact_duration_deg': 137.34294161815535,
          'F2_peak': 24.17931307038444,
          'F2_weld_mean': 22.82280519155257},
  'coarse': {'contact_onset_deg': 111.20571187259874,
             'contact_loss_deg': 248.54489164086684,
             'contact_duration_deg': 137.33917976826808,
             'F2_peak': 24.179216227652542,
             'F2_weld_mean': 22.822491700311904},
  'thinned': [{'contact_onset_deg': 111.20574975231833,
               'contact_loss_deg': 248.54489164086684,
               'contact_duration_deg': 137.3391418885485,
               'F2_peak': 24.17931307038444,
               'F2_weld_mean': 22.822488873650208},
              {'contact_onset_deg': 111.205889514168,
               'contact_loss_deg': 248.54382584034062,
               'contact_duration_deg': 137.3379363261726,
               'F2_peak': 24.17931307038444,
               'F2_weld_mean': 22.822499527816156}],
  'exact': {'contact_onset_deg': 111.1936562549915,
            'contact_loss_deg': 248.5356074484866,
            'contact_duration_deg': 137.3419511934951,
            'F2_peak': 24.17933625742365,
            'F2_weld_mean': 22.822991999230265}},
 {'what': 'carriage 0.545 ms',
  'kind': 'step',
  'ratio': 1.999515503875969,
  'units': {'peak_abs_U2_last_stitch_um': 'um', 'peak_abs_U2_um': 'um'},
  'run': {'peak_abs_U2_last_stitch_um': 1609.5944431589169, 'peak_abs_U2_um': 2953.978169807351},
  'coarse': {'peak_abs_U2_last_stitch_um': 1609.5893289934263,
             'peak_abs_U2_um': 2949.8577013017416},
  'thinned': [{'peak_abs_U2_last_stitch_um': 1609.5944431589169,
               'peak_abs_U2_um': 2953.978169807351},
              {'peak_abs_U2_last_stitch_um': 1608.7686365719112,
               'peak_abs_U2_um': 2945.733621919198}],
  'exact': {'peak_abs_U2_last_stitch_um': 1611.5949470234777, 'peak_abs_U2_um': 2944.137270074881}},
 {'what': 'punch_split adaptive tol 3.67e-4',
  'kind': 'tolerance',
  'ratio': 8.0,
  'units': {'contact_onset_deg': 'deg',
            'contact_loss_deg': 'deg',
            'contact_duration_deg': 'deg',
            'F2_peak': 'N',
            'F2_weld_mean': 'N'},
  'run': {'contact_onset_deg': 111.17909040998816,
          'contact_loss_deg': 248.53513417202475,
          'contact_duration_deg': 137.3560437620366,
          'F2_peak': 24.177788445468224,
          'F2_weld_mean': 22.822922699746687},
  'coarse': {'contact_onset_deg': 111.18519276282841,
             'contact_loss_deg': 248.53094256262884,
             'contact_duration_deg': 137.34574979980044,
             'F2_peak': 24.173924522827825,
             'F2_weld_mean': 22.820259419541074},
  'thinned': [{'contact_onset_deg': 111.1790904213038,
               'contact_loss_deg': 248.53566128553615,
               'contact_duration_deg': 137.35657086423237,
               'F2_peak': 24.177788445468224,
               'F2_weld_mean': 22.82249219483155},
              {'contact_onset_deg': 111.17909042776833,
               'contact_loss_deg': 248.53516920769175,
               'contact_duration_deg': 137.35607877992342,
               'F2_peak': 24.177788445468224,
               'F2_weld_mean': 22.822468915710854}],
  'exact': {'contact_onset_deg': 111.1936562549915,
            'contact_loss_deg': 248.5356074484866,
            'contact_duration_deg': 137.3419511934951,
            'F2_peak': 24.17933625742365,
            'F2_weld_mean': 22.822991999230265}}]
SHORT = {'what': 'punch_split iterative 0.105 ms',
 'kind': 'step',
 'ratio': 2.0,
 'units': {'contact_onset_deg': 'deg',
           'contact_loss_deg': 'deg',
           'contact_duration_deg': 'deg',
           'F2_peak': 'N',
           'F2_weld_mean': 'N'},
 'run': {'contact_onset_deg': 111.20702713350961,
         'contact_loss_deg': 248.54402842349313,
         'contact_duration_deg': 137.3370012899835,
         'F2_peak': 24.174541101485207,
         'F2_weld_mean': 22.822992159330198},
 'coarse': {'contact_onset_deg': 111.22184401097377,
            'contact_loss_deg': 248.54917902584046,
            'contact_duration_deg': 137.3273350148667,
            'F2_peak': 24.175011136563924,
            'F2_weld_mean': 22.8219710802808},
 'thinned': [{'contact_onset_deg': 111.24490760488035,
              'contact_loss_deg': 248.54843074064297,
              'contact_duration_deg': 137.30352313576262,
              'F2_peak': 24.174541101485207,
              'F2_weld_mean': 22.822057202283915},
             {'contact_onset_deg': 111.20847477481604,
              'contact_loss_deg': 248.57205097638266,
              'contact_duration_deg': 137.36357620156662,
              'F2_peak': 24.174541101485207,
              'F2_weld_mean': 22.822388218419047}],
 'exact': {'contact_onset_deg': 111.1936562549915,
           'contact_loss_deg': 248.5356074484866,
           'contact_duration_deg': 137.3419511934951,
           'F2_peak': 24.17933625742365,
           'F2_weld_mean': 22.822991999230265}}


def _ratios(row) -> dict:
    """± / true error of each figure of a recorded run."""
    bound = accuracy.bound(row["run"], row["coarse"], row["thinned"], row["units"], row["ratio"],
                           row["kind"])
    return {f: bound[f] / abs(row["run"][f] - x) for f, x in row["exact"].items()}


@pytest.mark.parametrize("row", HARDEST, ids=[r["what"] for r in HARDEST])
def test_the_hardest_measured_runs_stay_within_the_bound(row, monkeypatch):
    assert min(_ratios(row).values()) >= 1.0, _ratios(row)
    if row is HARDEST[0]:                            # and half the factor would not do
        monkeypatch.setattr(accuracy, "SAFETY", accuracy.SAFETY / 2)
        assert _ratios(row)["F2_peak"] < 0.6


def test_the_run_the_bound_misses_is_still_missed():
    """punch_split under the iterative master at 0.105 ms: F2_peak 0.0048 N off, its coarser run
    as far off the same way (the force interpolated across the landing's step), so the two agree
    and the ± is 0.69 of the error; its weld mean, read from the same F2, is far inside. Should
    the bound come to hold here, docs/running.md's list of misses shrinks."""
    ratios = _ratios(SHORT)
    assert 0.6 < ratios["F2_peak"] < 0.8 and min(r for f, r in ratios.items() if f != "F2_peak") > 10


def test_runs_that_count_different_events_or_a_figure_far_off_have_no_bound():
    units = {"n_contacts": "1", "onset": "deg", "force": "N"}
    run_, coarse = {"n_contacts": 1, "onset": 111.2, "force": 24.2}, \
        {"n_contacts": 2, "onset": 111.3, "force": 24.0}
    whole, figure = accuracy.distrust(run_, coarse, [run_, run_], units)
    assert "count n_contacts differently (1 here, 2 in the coarser run" in whole
    whole, figure = accuracy.distrust(run_, {**coarse, "n_contacts": 1, "force": -1.0},
                                      [run_, run_], units)
    assert whole is None and list(figure) == ["force"]
    assert "further from 24.2 than it is from zero" in figure["force"]
    summary = {"onset": 111.2, "force": 24.2, "coupling_error": {
        "method": "m", "figures": {"onset": 0.1}, "untrusted": {"force": figure["force"]}}}
    assert accuracy.beyond(summary, 0.05) == [f"force: no bound ({figure['force']})"]


def test_a_figure_without_a_bound_says_so_on_the_console(capsys, tmp_path):
    errors = {"method": "the run at twice the step (0.0005 s) and its samples thinned",
              "figures": {"onset": 0.74}, "untrusted": {"force": "the coarser run gives -1"}}
    run_ = SimpleNamespace(runs=None, summary={"coupling_error": errors},
                           figures={"onset": 111.2, "force": 24.2},
                           units={"onset": "deg", "force": "N"})
    print_run("x", run_, tmp_path)
    out = capsys.readouterr().out
    assert "± 0.7400 deg" in out and "no ±" in out.splitlines()[2]
    assert "(± : a bound of the coupling error, from the run at twice the step" in out
    assert "(no ± for force: the coarser run gives -1)" in out
    run_.summary["coupling_error"] = {"method": "m", "figures": {},
                                      "failed": "the run at twice the step diverged"}
    print_run("x", run_, tmp_path)
    assert "(no ±, no bound of the coupling error: the run at twice the step diverged)" in \
        capsys.readouterr().out
