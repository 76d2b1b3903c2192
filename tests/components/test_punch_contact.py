"""The punch body's exact piecewise integration against scipy and against closed forms."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from sewfmu.components.parameters import ParameterError
from sewfmu.components.punch_contact import GRAVITY, PunchContact, PunchContactParams, PunchState


def _scipy_free_flight(p, y0, v0, x, h):
    """Bilateral spring 11, no fabric: m y'' = -F10 - c1 y - b1 y' + F30 + c3 (xi - y)
    + b3 (xi' - y') - m g, with xi(t) = x0 + x1 t + x2 t²."""
    def rhs(t, s):
        xi = x[0] + x[1] * t + x[2] * t * t
        xi_dot = x[1] + 2 * x[2] * t
        f = (-p.F10 - p.c1 * s[0] - p.b1 * s[1] + p.F30 + p.c3 * (xi - s[0])
             + p.b3 * (xi_dot - s[1]))
        return [s[1], f / p.m - GRAVITY]
    sol = solve_ivp(rhs, (0, h), [y0, v0], method="DOP853", rtol=1e-12, atol=1e-15)
    return sol.y[:, -1]


@pytest.mark.parametrize("h", [1e-5, 2.5e-4, 3e-3])
def test_exact_piece_matches_scipy_without_contact(h):
    p = PunchContactParams(F30=3.0)
    model = PunchContact(p)
    x = (4.0e-3, -0.3, -25.0)                 # a descending slider
    s = model.step(PunchState(4.2e-3, 0.1, False, True), *x, h)
    y_ref, v_ref = _scipy_free_flight(p, 4.2e-3, 0.1, x, h)
    assert not s.contact
    assert s.y == pytest.approx(y_ref, abs=1e-12)
    assert s.y_dot == pytest.approx(v_ref, abs=1e-9)


def test_landing_is_located_inside_the_step():
    """One long step that contains the landing: the switch time and the state after it match a
    scipy solution with event location."""
    p = PunchContactParams()
    model = PunchContact(p)
    x = (-1.0e-3, -0.2, 0.0)                  # slider below the fabric, punch falling onto it
    h = 2e-3
    s = model.step(PunchState(0.5e-3, -0.4, False, True), *x, h)
    assert s.contact and s.landings == 1

    def rhs(t, st, contact):
        xi, xi_dot = x[0] + x[1] * t, x[1]
        f = (-p.F10 - p.c1 * st[0] - p.b1 * st[1] + p.c3 * (xi - st[0]) + p.b3 * (xi_dot - st[1]))
        if contact:
            f += -(p.c2 * st[0] + p.b2 * st[1])
        return [st[1], f / p.m - GRAVITY]
    touch = lambda t, st, contact: st[0]
    touch.terminal, touch.direction = True, -1
    a = solve_ivp(rhs, (0, h), [0.5e-3, -0.4], args=(False,), events=touch, rtol=1e-12, atol=1e-15)
    b = solve_ivp(rhs, (a.t[-1], h), a.y[:, -1], args=(True,), rtol=1e-12, atol=1e-15,
                  dense_output=True)
    assert s.y == pytest.approx(b.y[0, -1], abs=1e-11)
    assert s.y_dot == pytest.approx(b.y[1, -1], abs=1e-8)
    # the peak hold: the largest fabric force within the step, from landing (-b2·y' at y = 0)
    # to the end of the step
    y, v = b.sol(np.linspace(a.t[-1], h, 20001))
    assert s.F2_max == pytest.approx(np.max(-(p.c2 * y + p.b2 * v)), rel=1e-6)
    assert s.F2_max > -p.b2 * a.y[1, -1]


@pytest.mark.parametrize("xi, contact", [(3.0e-3, False), (-1.0e-3, True)])
def test_static_equilibrium_closed_form(xi, contact):
    """A slider held still: the punch settles where the forces balance (closed form)."""
    p = PunchContactParams(F30=4.0)
    model = PunchContact(p)
    s = PunchState(xi, 0.0, False, True)
    for _ in range(400):                       # 0.4 s: many damped periods
        s = model.step(s, xi, 0.0, 0.0, 1e-3)
    c = p.c1 + p.c3 + (p.c2 if contact else 0.0)
    y_static = (-p.F10 + p.F30 + p.c3 * xi - p.m * GRAVITY) / c
    assert s.contact == contact
    assert s.y == pytest.approx(y_static, abs=1e-12)
    out = model.outputs(s, xi, 0.0)
    assert -out.F1 + out.F2 + out.F3 - p.m * GRAVITY == pytest.approx(0.0, abs=1e-8)


def test_compression_only_spring_does_not_pull_the_punch_down():
    """Slider 20 mm below the fabric: the paper's bilateral spring 11 pulls the punch into the
    fabric; a compression-only spring 11 (it only pushes the holder up) lets the punch rest under
    the closing spring alone. Both equilibria in closed form."""
    xi = -0.02
    for compression_only, spring_c, spring_f in ((1, 0.0, 0.0), (0, 1.0e5, 1.0e5 * xi)):
        p = PunchContactParams(compression_only=compression_only)
        model = PunchContact(p)
        s = PunchState(0.0, 0.0, False, True)
        for _ in range(400):
            s = model.step(s, xi, 0.0, 0.0, 1e-3)
        assert s.contact and s.spring_on == (not compression_only)
        y_static = (-p.F10 - p.m * GRAVITY + spring_f) / (p.c1 + p.c2 + spring_c)
        assert s.y == pytest.approx(y_static, abs=1e-12)
    assert model.outputs(s, xi, 0.0).F3 < 0          # bilateral: spring 11 in tension


@pytest.mark.parametrize("name, value", [("m", 0.0), ("c2", -5.0), ("b1", float("nan")),
                                         ("compression_only", 2)])
def test_bad_parameters_are_refused_by_name(name, value):
    with pytest.raises(ParameterError, match=f"parameter {name}"):
        PunchContact(PunchContactParams(**{name: value}))


# --- a preloaded compression-only spring 11: the punch held on its stop -------------------------
def _on_stop_params(**kw):
    return PunchContactParams(compression_only=1, **{"F30": 12.0, "F10": 5.0, **kw})


def test_held_punch_follows_the_slider_and_the_stop_carries_the_closed_form_force():
    """Slider descending at constant speed: the punch rides on the stop (y = xi) and the stop
    carries F1 + m·g (xi'' = 0, no fabric); at the landing (y = 0, t = xi0/0.4 in closed form)
    the fabric's jump b2·0.4 exceeds that load, so the punch leaves the stop there."""
    p = _on_stop_params()
    model = PunchContact(p)
    xi0, speed, h = 3.0e-3, -0.4, 2.5e-4
    s = model.initial_state(xi0, 0.0)
    assert s.held                       # 5 + 2000·3e-3 + 0.62 N lies in [0, 12] N
    t = 0.0
    t_land = xi0 / -speed
    while t + h < t_land:
        xi = xi0 + speed * t
        s = model.step(s, xi, speed, 0.0, h)
        t += h
        out = model.outputs(s, xi + speed * h, speed)
        assert s.held and out.y == pytest.approx(xi0 + speed * t, abs=1e-15)
        f_closed = p.F10 + p.c1 * out.y + p.b1 * speed + p.m * GRAVITY
        assert out.F3 == pytest.approx(f_closed, rel=1e-12)
        assert out.y_ddot == 0.0 and out.Delta == pytest.approx(0.0, abs=1e-15)
    # the step that contains the landing: contact on, stop released, the state after it from
    # scipy (fabric contact, spring 11 off) started at the closed-form landing instant
    s = model.step(s, xi0 + speed * t, speed, 0.0, h)
    assert s.contact and not s.held and not s.spring_on and s.landings == 1

    def rhs(tt, st):
        f = -p.F10 - p.c1 * st[0] - p.b1 * st[1] - p.c2 * st[0] - p.b2 * st[1]
        return [st[1], f / p.m - GRAVITY]
    ref = solve_ivp(rhs, (t_land, t + h), [0.0, speed], method="DOP853", rtol=1e-12, atol=1e-15)
    assert s.y == pytest.approx(ref.y[0, -1], abs=1e-12)
    assert s.y_dot == pytest.approx(ref.y[1, -1], abs=1e-8)


def test_held_punch_is_released_into_the_spring_when_the_stop_force_passes_F30():
    """Slider accelerating upward from rest: the stop force m·(a + g) + F10 + c1·xi + b1·xi'
    grows to F30 at a closed-form instant; from there spring 11 compresses (scipy, spring on)."""
    p = _on_stop_params()
    model = PunchContact(p)
    xi0, acc, h = 2.0e-3, 20.0, 5e-4
    s = model.initial_state(xi0, 0.0, acc)
    assert s.held
    # m·(acc + g) + F10 + c1·(xi0 + acc·t²/2) + b1·acc·t = F30
    c2_, c1_, c0_ = p.c1 * acc / 2, p.b1 * acc, p.m * (acc + GRAVITY) + p.F10 + p.c1 * xi0 - p.F30
    t_release = (-c1_ + np.sqrt(c1_ ** 2 - 4 * c2_ * c0_)) / (2 * c2_)
    n = int(np.ceil(t_release / h)) + 3
    for k in range(n):
        t = k * h
        s = model.step(s, xi0 + acc * t * t / 2, acc * t, acc / 2, h)
        assert s.held == ((k + 1) * h < t_release)
    assert s.spring_on and not s.contact

    def rhs(tt, st):
        xi, xi_dot = xi0 + acc * tt * tt / 2, acc * tt
        f = (-p.F10 - p.c1 * st[0] - p.b1 * st[1] + p.F30 + p.c3 * (xi - st[0])
             + p.b3 * (xi_dot - st[1]))
        return [st[1], f / p.m - GRAVITY]
    start = [xi0 + acc * t_release ** 2 / 2, acc * t_release]
    ref = solve_ivp(rhs, (t_release, n * h), start, method="DOP853", rtol=1e-12, atol=1e-15)
    assert s.y == pytest.approx(ref.y[0, -1], abs=1e-12)
    assert s.y_dot == pytest.approx(ref.y[1, -1], abs=1e-8)
    assert model.outputs(s, xi0 + acc * (n * h) ** 2 / 2, acc * n * h).Delta > 0.0


def test_punch_bouncing_on_the_stop_comes_to_rest_instead_of_chattering():
    """The case the property test found (a light punch on a stiff, damped, preloaded stop): the
    exact motion micro-bounces on the stop, a switch every few µs. The model holds the punch on
    the stop instead; the exact bouncing (the same model with the stop disabled, which still
    fits in the switch budget over these steps) stays within 0.2 µm and 5 mm/s of it."""
    p = PunchContactParams(m=0.0078125, c1=5965.0, c2=1000.0, c3=64466.0, F10=0.0, b1=0.0,
                           b2=0.0, b3=19.0, F30=12.0, compression_only=1)
    model, bouncing = PunchContact(p), PunchContact(p)
    bouncing.has_stop = False
    s = model.initial_state(3e-3, -0.4)
    b = bouncing.initial_state(3e-3, -0.4)
    h, speed = 5e-4, -0.4
    for k in range(12):
        s = model.step(s, 3e-3 + speed * k * h, speed, 0.0, h)
        b = bouncing.step(b, 3e-3 + speed * k * h, speed, 0.0, h)
        assert abs(s.y - b.y) < 2e-7 and abs(s.y_dot - b.y_dot) < 5e-3
    assert s.held and s.y == pytest.approx(3e-3 + speed * 12 * h, abs=1e-15)
    assert s.y_dot == speed
    assert not b.held
