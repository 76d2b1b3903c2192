"""The thread take-up four-bar: closure, the rigid coupler triangle (which the paper's printed
formula breaks), analytic derivatives, the paper's central differences, the scenario and the
tolerance study."""
import math

import numpy as np
import pytest

from sewfmu.components.kinematics import AssemblyError, point_on_link
from sewfmu.components.takeup import TakeupLinkage, TakeupParams
from sewfmu.scenarios.cosim.master import run
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.mechanisms.sampling import sampled
from sewfmu.scenarios.mechanisms.takeup import path_stroke, tolerance_study
from sewfmu.scenarios.runs.runner import summarize

THETA = np.radians(np.arange(0.0, 360.0, 0.25))


def _dist(p, q):
    return np.hypot(p.x - q.x, p.y - q.y)


def test_closure_at_every_crank_angle_and_a_rigid_coupler_triangle():
    link = TakeupLinkage()
    p = link.p
    m = sampled(link.motion, THETA)
    a = type(m.B)(0.0, 0.0)
    d = type(m.B)(p.z_D, p.x_D)
    assert np.allclose(_dist(a, m.B), p.L_AB, atol=1e-12)
    assert np.allclose(_dist(m.B, m.C), p.L_BC, atol=1e-12)
    assert np.allclose(_dist(m.C, d), p.L_CD, atol=1e-12)
    assert np.allclose(_dist(m.B, m.E), p.L_BE, atol=1e-12)
    # CE by the law of cosines: the triangle keeps its shape
    ce = math.sqrt(p.L_BC ** 2 + p.L_BE ** 2 - 2 * p.L_BC * p.L_BE * math.cos(p.angle_CBE))
    assert np.allclose(_dist(m.C, m.E), ce, atol=1e-12)


def central_difference_velocity(linkage: TakeupLinkage, theta, omega: float,
                                d_theta: float = math.radians(0.5)) -> tuple:
    """The paper's velocity of E at crank angles theta: central differences in θ with step
    d_theta, times ω."""
    plus = sampled(lambda th: linkage.motion(th + d_theta).E, theta)
    minus = sampled(lambda th: linkage.motion(th - d_theta).E, theta)
    scale = omega / (2.0 * d_theta)
    return (plus.x - minus.x) * scale, (plus.y - minus.y) * scale


def _eye_by_printed_formula(link, theta):
    """E as the paper prints it, from φ_CD + ∠CBE (wrong: shown below)."""
    m = link.motion(theta)
    return point_on_link(m.B, link.p.L_BE, m.phi_CD, offset=link.p.angle_CBE)


def test_the_papers_printed_formula_deforms_the_coupler_triangle():
    link = TakeupLinkage()
    m = sampled(link.motion, THETA)
    printed = sampled(lambda theta: _eye_by_printed_formula(link, theta), THETA)
    ce = _dist(m.C, printed)
    assert np.ptp(ce) > 5e-3               # |CE| changes by more than 5 mm over a turn


def test_velocity_and_acceleration_match_finite_differences():
    link = TakeupLinkage()
    w0, eps = 500.0, 2.0e4                 # a shaft speeding up
    t = np.linspace(0.0, 0.02, 201)
    dt = 1e-7
    theta = lambda tt: w0 * tt + 0.5 * eps * tt * tt
    eye = lambda *args: link.motion(*args).E
    e = sampled(eye, theta(t), w0 + eps * t, eps)
    ep, em = sampled(eye, theta(t + dt)), sampled(eye, theta(t - dt))
    for pos, vel, acc in (("x", "vx", "ax"), ("y", "vy", "ay")):
        fd_v = (getattr(ep, pos) - getattr(em, pos)) / (2 * dt)
        fd_a = (getattr(ep, pos) - 2 * getattr(e, pos) + getattr(em, pos)) / dt ** 2
        assert np.allclose(getattr(e, vel), fd_v, rtol=1e-6, atol=1e-6)
        assert np.allclose(getattr(e, acc), fd_a, rtol=1e-3, atol=5.0)


def test_central_difference_error_shrinks_as_the_square_of_the_step():
    link = TakeupLinkage()
    omega = 5000 * 2 * math.pi / 60
    exact = sampled(lambda theta: link.motion(theta, omega).E, THETA)
    errors = []
    for deg in (2.0, 1.0, 0.5, 0.25):
        vz, vx = central_difference_velocity(link, THETA, omega, math.radians(deg))
        errors.append(np.max(np.hypot(vz - exact.vx, vx - exact.vy)))
    orders = [math.log2(a / b) for a, b in zip(errors, errors[1:])]
    assert all(abs(o - 2.0) < 0.05 for o in orders), orders


def test_takeup_scenario_figures(fmu_paths):
    result = run(load("takeup"), fmu_paths)
    fig = summarize(result)
    link = TakeupLinkage()
    e = sampled(lambda theta: link.motion(theta, 5000 * 2 * math.pi / 60).E, THETA)
    assert fig["central_difference_step_deg"] == pytest.approx(0.5, rel=1e-9)
    assert fig["path_extent_z_mm"] == pytest.approx(np.ptp(e.x) * 1e3, rel=1e-3)
    assert fig["path_extent_x_mm"] == pytest.approx(np.ptp(e.y) * 1e3, rel=1e-3)
    assert fig["peak_speed_m_s"] == pytest.approx(np.hypot(e.vx, e.vy).max(), rel=1e-4)
    assert fig["peak_acceleration_m_s2"] == pytest.approx(np.hypot(e.ax, e.ay).max(), rel=1e-4)
    # Δθ = 0.5°: the central difference is good to about 1e-4 of the peak speed
    assert 0 < fig["central_difference_max_error_m_s"] < 1e-4 * fig["peak_speed_m_s"]


@pytest.mark.slow
def test_tolerance_study():
    study = tolerance_study()
    rows = {(r["parameter"], r["change_mm"]): r for r in study["links"]}
    # a longer BE moves E along BE: exactly the change of length, at every crank angle
    assert rows[("L_BE", 0.1)]["max_path_deviation_mm"] == pytest.approx(0.1, abs=1e-9)
    # the pin adjustment: the fitted slope agrees with the local derivative of the stroke
    h = 1e-6
    def stroke(l_cd):
        link = TakeupLinkage(TakeupParams(L_CD=l_cd))
        e = sampled(lambda theta: link.motion(theta).E, THETA)
        return path_stroke(e.x, e.y)
    local = (stroke(24e-3 + h) - stroke(24e-3 - h)) / (2 * h)
    assert study["stroke_change_per_mm_of_pin_adjustment"] == pytest.approx(local, rel=5e-3)  # 0.35 %


def test_takeup_that_cannot_assemble_names_the_crank_angle():
    with pytest.raises(AssemblyError, match=r"crank angle theta = \d+\.\d°"):
        TakeupLinkage(TakeupParams(L_CD=8e-3))


@pytest.mark.slow
def test_studies_run_from_the_command_line(tmp_path, capsys):
    import json

    from sewfmu.cli import main

    assert main(["run", "takeup_tolerance", "--out", str(tmp_path / "t")]) == 0
    summary = json.loads((tmp_path / "t" / "summary.json").read_text())
    assert summary["stroke_change_per_mm_of_pin_adjustment"] == pytest.approx(
        tolerance_study()["stroke_change_per_mm_of_pin_adjustment"])
    assert "pin_adjustment" in json.loads((tmp_path / "t" / "study.json").read_text())
    assert main(["run", "takeup_tolerance", "--set", "x.y=1", "--out", str(tmp_path)]) == 1
    assert "unknown instance 'x'" in capsys.readouterr().err
