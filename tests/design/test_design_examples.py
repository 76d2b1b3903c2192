"""docs/design.md's worked examples from the papers, run as the page writes them (its Python
blocks as one script, in a fresh process, from an empty folder: conftest.py's design_page) and
each answer checked against a computation that does not use the
design wing: plain sewfmu.run calls (bisections, one-at-a-time differences) and sewfmu.sweep
grids. The examples: the fastest shaft speed at which the punch lands once per revolution, a
feed lever length for a wanted path width of the feed dog, the stitch rate with the least
residual vibration of the carriage, the ranking of the punch's parameters for the welding
force."""
import math

import numpy as np
import pytest

import sewfmu

RPM = math.pi / 30.0                        # rad/s per rpm


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch, tmp_path):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))
    monkeypatch.chdir(tmp_path)             # the plain runs' files, if any, go here


@pytest.fixture
def page(design_page):
    """The page's examples as a user runs them (one script in a fresh process: conftest.py)."""
    return design_page


def _bisect(below, lo: float, hi: float, tol: float) -> tuple[float, float]:
    """[lo, hi] narrowed to tol around where below(x) turns false, by halving: no design
    wing, sign changes only."""
    assert below(lo) and not below(hi)
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if below(mid) else (lo, mid)
    return lo, hi


# --- the fastest shaft speed at which the punch lands once per revolution ----------------------
PUNCH_FAST = {"experiment.revolutions": 3, "experiment.step": "0.1 ms"}


@pytest.mark.slow
def test_the_fastest_speed_with_one_landing_matches_a_bisection_and_a_grid_of_plain_runs(page):
    ex = page
    fast, once, twice = ex["fast"], ex["once"], ex["twice"]
    assert fast.algorithm == "brentq" and fast.converged
    assert 0.0 < twice - once <= 1e-5 * (5000 - 3000) * RPM      # the jump, bracketed

    def lands_once(omega: float) -> bool:
        # near the jump the run at twice the step (the coupling error's estimate) counts the
        # other number of landings: the estimate says so, the figure is still the run's own
        figures = sewfmu.run("punch_drive", set={**PUNCH_FAST, "shaft.omega0": omega,
                                                 "experiment.accept_error": True}).figures
        return figures["n_contacts"] == 1

    lo, hi = _bisect(lands_once, 3000 * RPM, 5000 * RPM, 0.01)
    # the jump lies in (lo, hi] and in (once, twice]: the two brackets overlap
    assert once < hi and lo < twice                              # the same jump, to 0.01 rad/s
    # and the jump is the only one in the range: one landing below it, more above it
    grid = np.linspace(3000, 5000, 41) * RPM
    swept = sewfmu.sweep("punch_drive", grid={"shaft.omega0": grid.tolist()}, set=PUNCH_FAST,
                         workers=2).table
    below = swept["shaft.omega0"] < 0.5 * (once + twice)
    assert np.all(swept["n_contacts"][below] == 1) and np.all(swept["n_contacts"][~below] >= 2)


# --- a feed lever length for a wanted path width of the feed dog --------------------------------
@pytest.mark.slow
def test_the_lever_for_a_path_width_matches_a_bisection_of_plain_runs(page):
    ex = page
    width = ex["width"]
    assert width.algorithm == "brentq" and width.converged
    assert width.figures["M_path_width_mm"] == pytest.approx(8.0, rel=1e-6)

    def narrower(l7p: float) -> bool:           # the width grows with the arm G-H (l7')
        figures = sewfmu.run("feed", set={"experiment.revolutions": 1, "feed.l7p": l7p}).figures
        return figures["M_path_width_mm"] < 8.0

    lo, hi = _bisect(narrower, 0.024, 0.034, 1e-7)
    assert width.best["feed.l7p"] == pytest.approx(0.5 * (lo + hi), rel=0.005)


# --- the stitch rate with the least residual vibration of the carriage --------------------------
@pytest.mark.slow
def test_the_global_optimum_of_the_vibration_is_the_best_of_a_dense_sweep(page):
    ex = page
    rate = ex["rate"]
    assert rate.algorithm == "differential_evolution" and rate.feasible
    found = rate.best["shaft.omega0"] / RPM
    spacing = 10.0
    rpm = np.arange(1200.0, 2000.0 + spacing / 2, spacing)
    swept = sewfmu.sweep("carriage_startstop", grid={"shaft.omega0": (rpm * RPM).tolist()},
                         set={"experiment.revolutions": 10}, workers=2).table
    assert np.all(np.isfinite(swept["peak_abs_U2_last_stitch_um"]))
    best = int(np.argmin(swept["peak_abs_U2_last_stitch_um"]))
    at = swept["shaft.omega0"][best] / RPM
    assert 1200.0 < at < 2000.0                                  # an interior minimum
    assert abs(found - at) <= spacing                            # within the grid's spacing
    # and no worse than the grid's best (the global method does not stop on a side minimum)
    assert rate.figures["peak_abs_U2_last_stitch_um"] <= \
        1.01 * swept["peak_abs_U2_last_stitch_um"][best]


# --- the ranking of the punch's parameters for the welding force --------------------------------
@pytest.mark.slow
def test_the_morris_ranking_matches_one_at_a_time_differences_of_plain_runs(page):
    ex = page
    rank, ranges = ex["rank"], ex["ranges"]
    mu_star = {name: entry["mu_star"] for name, entry in rank.indices["F2_weld_mean"].items()}
    # one at a time from the catalogue's values: the figure at each end of each range; Morris's
    # mu* is the mean |change| over a whole range, so for a figure about linear in each
    # parameter it is that difference
    base = {"experiment.revolutions": 3}
    moved = {}
    for name, (lo, hi) in ranges.items():
        ends = [sewfmu.run("punch_drive", set={**base, name: v}).figures["F2_weld_mean"]
                for v in (lo, hi)]
        moved[name] = abs(ends[1] - ends[0])
    by_runs = sorted(moved, key=moved.get, reverse=True)
    by_morris = list(rank.indices["F2_weld_mean"])
    assert by_morris[:2] == by_runs[:2] == ["punch.c2", "punch.F10"]
    for name in by_runs[:2]:
        assert mu_star[name] == pytest.approx(moved[name], rel=0.2)
    # the depth of the required displacement does not enter the six-bar linkage's runs at all
    assert moved["linkage.psi_m"] == 0.0 and mu_star["linkage.psi_m"] == 0.0
    assert by_morris[-1] == "linkage.psi_m"
