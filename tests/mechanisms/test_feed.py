"""The closed lever-hinge feed mechanism: link lengths, rigid levers, analytic derivatives, a
continuous assembly branch, the printed swings, the scenario and the lever-ratio study."""
import math

import numpy as np
import pytest

from sewfmu.components.feed import FeedLinkage, FeedParams
from sewfmu.components.kinematics import AssemblyError
from sewfmu.scenarios.cosim.master import run
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.mechanisms.feed import ratio_study
from sewfmu.scenarios.mechanisms.sampling import sampled
from sewfmu.scenarios.runs.runner import summarize

PHI1 = np.radians(np.arange(0.0, 360.0, 0.1))


def _dist(j, a, b):
    return np.hypot(j[a].x - j[b].x, j[a].y - j[b].y)


def _dir(j, a, b):
    return np.arctan2(j[b].y - j[a].y, j[b].x - j[a].x)


@pytest.mark.slow
def test_every_link_length_is_kept_at_every_crank_angle():
    link = FeedLinkage()
    p = link.p
    j = sampled(link.motion, PHI1).joints
    for a, b, length in (("A", "B", p.r_l), ("A", "K", p.r_f), ("B", "C", p.l2), ("D", "C", p.l3),
                         ("D", "E", p.l3p), ("K", "N", p.l8), ("G", "N", p.l7), ("G", "H", p.l7p),
                         ("E", "F", p.l4), ("H", "F", p.l5), ("H", "M", p.l_HM)):
        assert np.max(np.abs(_dist(j, a, b) - length)) < 1e-12, (a, b)
    wrap = lambda x: np.mod(x, 2 * np.pi)
    assert np.allclose(wrap(_dir(j, "A", "K") - _dir(j, "A", "B")), p.alpha1, atol=1e-12)
    assert np.allclose(wrap(_dir(j, "D", "E") - _dir(j, "D", "C")), p.alpha3, atol=1e-12)
    assert np.allclose(wrap(_dir(j, "G", "H") - _dir(j, "G", "N")), np.pi / 2 + p.alpha7,
                       atol=1e-12)
    # M on lever 5, on the line H -> F
    assert np.allclose(_dir(j, "H", "M"), _dir(j, "H", "F"), atol=1e-12)


def test_velocities_match_finite_differences():
    link = FeedLinkage()
    w, eps = 303.5, 5.0e3
    t = np.linspace(0.0, 0.03, 151)
    dt = 1e-7
    phi = lambda tt: w * tt + 0.5 * eps * tt * tt
    m = sampled(link.motion, phi(t), w + eps * t, eps)
    mp, mm = sampled(link.motion, phi(t + dt)), sampled(link.motion, phi(t - dt))
    for pos, vel in (("x", "vx"), ("y", "vy")):
        fd = (getattr(mp.joints["M"], pos) - getattr(mm.joints["M"], pos)) / (2 * dt)
        assert np.allclose(getattr(m.joints["M"], vel), fd, rtol=1e-6, atol=1e-8)
    for name in ("phi3", "phi4", "phi5", "phi7"):
        fd = np.unwrap(getattr(mp, name).value - getattr(mm, name).value) / (2 * dt)
        assert np.allclose(getattr(m, name).rate, fd, rtol=1e-6, atol=1e-6), name


@pytest.mark.slow
def test_the_assembly_branch_is_continuous_over_a_revolution():
    link = FeedLinkage()
    j = sampled(link.motion, np.append(PHI1, 2 * np.pi)).joints
    for name in ("C", "N", "F", "M"):
        steps = np.hypot(np.diff(j[name].x), np.diff(j[name].y))
        assert steps.max() < 0.05e-3, name        # 0.1° of crank moves no joint by 0.05 mm
        assert np.hypot(j[name].x[-1] - j[name].x[0], j[name].y[-1] - j[name].y[0]) < 1e-12
    # and each dyad stays on its chosen side (C right of B->D, N left of K->G, F left of E->H)
    side = lambda p, q, x: np.sign((j[q].x - j[p].x) * (j[x].y - j[p].y)
                                   - (j[q].y - j[p].y) * (j[x].x - j[p].x))
    assert np.all(side("B", "D", "C") < 0)
    assert np.all(side("K", "G", "N") > 0)
    assert np.all(side("E", "H", "F") > 0)


@pytest.mark.slow
def test_default_swings_are_the_printed_ones():
    m = sampled(FeedLinkage().motion, PHI1)
    swing = lambda a: math.degrees(np.ptp(np.unwrap(a.value)))
    assert swing(m.phi3) == pytest.approx(13.7, abs=0.05)
    assert swing(m.phi7) == pytest.approx(18.4, abs=0.05)


@pytest.mark.slow
def test_feed_scenario_figures(fmu_paths):
    fig = summarize(run(load("feed"), fmu_paths))
    m = sampled(FeedLinkage().motion, PHI1)
    assert fig["phi3_swing_deg"] == pytest.approx(13.7, abs=0.05)
    assert fig["phi7_swing_deg"] == pytest.approx(18.4, abs=0.05)
    assert fig["M_path_width_mm"] == pytest.approx(np.ptp(m.joints["M"].x) * 1e3, rel=1e-3)
    assert fig["M_path_height_mm"] == pytest.approx(np.ptp(m.joints["M"].y) * 1e3, rel=1e-3)
    assert fig["min_transmission_angle_F_deg"] == pytest.approx(np.degrees(m.mu_F.min()), abs=0.05)
    assert 0 < fig["min_transmission_angle_F_deg"] <= 90


@pytest.mark.slow
def test_ratio_study_reports_what_cannot_assemble_and_goes_on():
    study = ratio_study()
    amplitudes = [r["phi5_amplitude_deg"] for r in study["lever_ratio"]]
    assert all(r["assembles"] for r in study["lever_ratio"])
    assert all(a > b for a, b in zip(amplitudes, amplitudes[1:]))   # falls as l5/l4 grows
    rods = {r["l2_over_l8"]: r for r in study["rod_ratio"]}
    assert rods[1.0]["assembles"]
    assert rods[1.0]["phi5_amplitude_deg"] == pytest.approx(
        math.degrees(np.ptp(np.unwrap(sampled(FeedLinkage().motion, PHI1).phi5.value))), abs=0.01)
    assert not rods[0.7]["assembles"] and "cannot be assembled at crank angle" in rods[0.7]["error"]
    assert not rods[1.7]["assembles"]


def test_feed_that_cannot_assemble_names_the_crank_angle():
    with pytest.raises(AssemblyError, match=r"crank angle phi1 = \d+\.\d°"):
        FeedLinkage(FeedParams(l2=180e-3))
