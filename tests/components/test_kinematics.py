"""Linkage kinematics against independent computations: finite differences of positions, link
lengths, the setup position, and linkages that cannot assemble."""
import math

import numpy as np
import pytest

from sewfmu.components.kinematics import (
    LEFT,
    RIGHT,
    AssemblyError,
    Motion,
    angle,
    dyad_rrp,
    dyad_rrr,
    link_angle,
    point_on_link,
)
from sewfmu.components.punch_linkage import REQUIRED_DISPLACEMENT, PunchLinkage, PunchLinkageParams
from sewfmu.scenarios.mechanisms.sampling import sampled


def _crank_driven_dyad(t, side):
    """A four-bar: crank at O (r = 0.3) driven non-uniformly, dyad to the rocker pivot (2, 0.5);
    t a float or an array of times."""
    def at(tt):
        th, w, dw = 0.7 + 3.0 * tt + 0.8 * tt * tt, 3.0 + 1.6 * tt, 1.6
        a = point_on_link(Motion(0.0, 0.0), 0.3, angle(th, w, dw))
        return dyad_rrr(a, 1.9, Motion(2.0, 0.5), 0.8, side)
    return sampled(at, t)


@pytest.mark.parametrize("side", [LEFT, RIGHT])
def test_dyad_velocity_and_acceleration_match_finite_differences(side):
    t = np.linspace(0.0, 2.0, 41)
    dt = 1e-5
    x0, xm, xp = (_crank_driven_dyad(t + s, side) for s in (0.0, -dt, dt))
    for pos, vel, acc in ((("x"), "vx", "ax"), ("y", "vy", "ay")):
        fd_vel = (getattr(xp, pos) - getattr(xm, pos)) / (2 * dt)
        fd_acc = (getattr(xp, pos) - 2 * getattr(x0, pos) + getattr(xm, pos)) / dt ** 2
        assert np.allclose(getattr(x0, vel), fd_vel, rtol=1e-6, atol=1e-8)
        assert np.allclose(getattr(x0, acc), fd_acc, rtol=1e-4, atol=1e-4)


def test_dyad_keeps_link_lengths_and_branch():
    x = _crank_driven_dyad(np.linspace(0, 2, 50), LEFT)
    t = np.linspace(0, 2, 50)
    a = sampled(lambda th: point_on_link(Motion(0.0, 0.0), 0.3, angle(th)), 0.7 + 3.0 * t + 0.8 * t ** 2)
    assert np.allclose(np.hypot(x.x - a.x, x.y - a.y), 1.9, atol=1e-12)
    assert np.allclose(np.hypot(x.x - 2.0, x.y - 0.5), 0.8, atol=1e-12)
    cross = (2.0 - a.x) * (x.y - a.y) - (0.5 - a.y) * (x.x - a.x)
    assert np.all(cross > 0)


def test_slider_on_line_matches_finite_differences():
    def slider_at(t):
        c = point_on_link(Motion(0.0, 0.0), 0.2, angle(1.0 + 5.0 * t, 5.0, 0.0))
        return dyad_rrp(c, 1.0, (0.1, 0.0), math.pi / 2, -1)
    slider = lambda t: sampled(slider_at, t)
    t, dt = np.linspace(0, 1, 21), 1e-5
    s0, sm, sp = slider(t), slider(t - dt), slider(t + dt)
    assert np.allclose(s0.x, 0.1)
    assert np.allclose(s0.vy, (sp.y - sm.y) / (2 * dt), rtol=1e-6)
    assert np.allclose(s0.ay, (sp.y - 2 * s0.y + sm.y) / dt ** 2, rtol=1e-4, atol=1e-3)


def test_link_angle_rate_matches_finite_differences():
    def ang(t):                                                        # the rocker
        return sampled(lambda tt: link_angle(Motion(2.0, 0.5), _crank_driven_dyad(tt, LEFT)), t)
    t, dt = np.linspace(0, 2, 21), 1e-5
    a0, am, ap = ang(t), ang(t - dt), ang(t + dt)
    assert np.allclose(a0.rate, (ap.value - am.value) / (2 * dt), rtol=1e-6, atol=1e-8)
    assert np.allclose(a0.accel, (ap.value - 2 * a0.value + am.value) / dt ** 2, rtol=1e-4, atol=1e-3)


def test_dyad_that_cannot_meet_names_the_first_failing_sample():
    with pytest.raises(AssemblyError, match="cannot meet") as err:
        sampled(lambda x: dyad_rrr(Motion(0.0, 0.0), 1.0, Motion(x, 0.0), 1.0, LEFT),
                [0.5, 1.0, 3.0, 4.0])
    assert err.value.index == 2


# --- the six-bar punch drive -------------------------------------------------------------------
def test_six_bar_keeps_every_link_length_over_a_revolution():
    link = PunchLinkage()
    p = link.p
    j = sampled(link.joints, np.linspace(0, 2 * math.pi, 721))
    dist = lambda a, b: np.hypot(j[a].x - j[b].x, j[a].y - j[b].y)
    for a, b, length in (("O1", "A", p.L_O1A), ("A", "B", p.L_AB), ("O2", "B", p.L_O2B),
                         ("O2", "C", p.L_O2C), ("C", "D", p.L_CD)):
        assert np.allclose(dist(a, b), length, atol=1e-12), (a, b)
    assert np.allclose(j["D"].x, p.x_D, atol=1e-15)
    # the bell crank is rigid: the angle from O2B clockwise to O2C stays 110°
    ang_b = np.arctan2(j["B"].y - p.y_O2, j["B"].x - p.x_O2)
    ang_c = np.arctan2(j["C"].y - p.y_O2, j["C"].x - p.x_O2)
    assert np.allclose(np.mod(ang_b - ang_c, 2 * math.pi), p.angle_BO2C, atol=1e-12)


def test_setup_position_is_the_slider_top():
    link = PunchLinkage()
    phi = np.linspace(0, 2 * math.pi, 3601)
    e = sampled(link.motion, phi, 1.0, 0.0)
    assert e.xi[0] == pytest.approx(link.p.xi0, abs=1e-15)
    assert abs(e.xi_dot[0]) < 1e-12          # dξ/dφ = 0 at the top
    assert np.all(e.psi >= -1e-15)
    assert 4.5e-3 < e.psi.max() < 5.5e-3     # "the slider stroke is about 5 mm"
    # the dwell: near the bottom the slider moves less than 0.1 mm over 60° of crank
    bottom = np.abs(np.degrees(phi) - 180) <= 30
    assert np.ptp(e.psi[bottom]) < 1e-4


@pytest.mark.parametrize("mode", [0, REQUIRED_DISPLACEMENT])
def test_excitation_derivatives_match_finite_differences_with_acceleration(mode):
    link = PunchLinkage(PunchLinkageParams(mode=mode))
    # a shaft speeding up: phi = w0 t + eps t²/2
    w0, eps = 150.0, 900.0
    t = np.linspace(0.001, 0.05, 97)
    dt = 1e-6
    xi = lambda tt: sampled(link.motion, w0 * tt + 0.5 * eps * tt ** 2, w0 + eps * tt, eps).xi
    e = sampled(link.motion, w0 * t + 0.5 * eps * t ** 2, w0 + eps * t, eps)
    assert np.allclose(e.xi_dot, (xi(t + dt) - xi(t - dt)) / (2 * dt), rtol=1e-5, atol=1e-7)
    assert np.allclose(e.xi_ddot, (xi(t + dt) - 2 * xi(t) + xi(t - dt)) / dt ** 2,
                       rtol=2e-3, atol=0.05)


def test_required_displacement_law():
    p = PunchLinkageParams(mode=REQUIRED_DISPLACEMENT)
    link = PunchLinkage(p)
    dwell = p.phi_descent + 0.5 * p.phi_dwell
    e = sampled(link.motion, [0.0, dwell, 2 * math.pi - 1e-9, 4 * math.pi + dwell], 1.0, 0.0)
    assert np.allclose(e.psi, [0.0, p.psi_m, 0.0, p.psi_m], atol=1e-12)
    assert np.allclose(e.xi_dot, 0.0, atol=1e-9)       # cycloidal: at rest at both ends


def test_linkage_that_cannot_assemble_names_the_crank_angle():
    # a coupler too short to reach the rocker over part of the turn
    with pytest.raises(AssemblyError, match=r"crank angle alpha = \d+\.\d°"):
        PunchLinkage(PunchLinkageParams(L_AB=29.0e-3))
    with pytest.raises(AssemblyError, match="cannot be assembled"):
        PunchLinkage(PunchLinkageParams(L_CD=2.0e-3))
