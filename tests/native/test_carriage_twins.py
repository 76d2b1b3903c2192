"""The carriage's C twins (native/models/carriage.c) held equal to the Python models
(sewfmu.components.carriage) over random parameters and random input histories: every state
value and output at every step within 1e-12 relative, and the same refusals with the same
messages.

The Python side is called as components/carriage_fmu.py's slaves call their models: the drive's
motion(φ, ω, ε) read as x, v, a, jerk; the carriage initialized at rest in the static deflection
under a_base, stepped by model.step with the inputs (a_base, a_base_dot) of the step, read by
model.physical (before initialization: the static deflection itself).

The floor near 0: a value is compared with 1e-12 of the largest of its own magnitude, its
quantity's amplitude over the history (the largest magnitude that quantity takes in it) and
1e-300. Every output is a sum of terms of the order of that amplitude (U = Φ·q; a = d2·ω² +
d1·ε), so a rounding difference scales with the amplitude, not with a value that passes through
0. Below 1e-300 the comparison is absolute (1e-312): doubles lose their relative precision below
2.2e-308 (subnormals: one last bit of 8e-313 is 6e-12 of it), and no quantity here (m, m/s,
m/s², m/s³, rad/s, modal coordinates) means anything at 1e-300; a quantity that is exactly 0
(the table at rest) is 0 in both, as measured. Measured: the states and
outputs after initialization agree to the last bit (both call the same libm in one process);
only the outputs before initialization differ: sew_model.h has the runtime read them from a
freshly initialized state, so the C gives Φ·(Φᵀ·M·U) (what the Python slave gives after
initialization) where the Python slave gives U itself. Around the defaults (a/l in 0.1–0.95)
that round trip is ≤ 1e-13 relative and is held to 1e-12 here; it grows with the conditioning of
the modes (4e-12 at a/l = 0.99 with a soft guide, 2e-6 at a/l = 0.9999), so the wide exploration
holds the C's first row to the Python slave's row after initialization instead."""
from __future__ import annotations

import math
from dataclasses import astuple

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sewfmu.components import carriage
from sewfmu.components.pythonfmu_quirks import describe
from tests.native.model_twin import ModelError, native_model

RELATIVE = 1e-12
FLOOR = 1e-300          # the magnitude below which a value is compared absolutely
SOURCES = ("parameters", "oscillator", "carriage")


def native(name: str, params):
    return native_model(name, params, *SOURCES)


def assert_twins(c_rows, py_rows, names):
    """Every value of every row within 1e-12 of the largest of its magnitude, its column's
    amplitude over the rows and FLOOR (the module's docstring: why)."""
    assert len(c_rows) == len(py_rows)
    for column, name in enumerate(names):
        amplitude = max(FLOOR, *(abs(row[column]) for row in py_rows))
        for step, (c_row, py_row) in enumerate(zip(c_rows, py_rows)):
            c, py = c_row[column], py_row[column]
            assert abs(c - py) <= RELATIVE * max(abs(py), amplitude), \
                f"{name} at step {step}: C {c!r}, Python {py!r}"


def refusal(build) -> str | None:
    """What a model's construction says when it fails, as the Python FMU logs it (describe: a
    ParameterError's own words, anything else with its kind, "ZeroDivisionError: ..."), or
    None."""
    try:
        build()
    except ModelError as err:
        return str(err)
    except Exception as err:          # noqa: BLE001 - whatever the Python model raises
        return describe(err)
    return None


# --- CarriageModal -----------------------------------------------------------------------------
MODAL_STATE = ("q1", "q2", "dq1", "dq2")
MODAL_ROW = ("U1", "U2", "U1_dot", "U2_dot", "omega1", "omega2")


@st.composite
def carriages(draw, wide=False):
    """CarriageParams' fields in order: around the defaults (l 0.515 m, a 0.22 m, EJ 2604 N·m²,
    m_n 1 kg, m_k 2.5 kg, J_c 0.1178 kg·m², zeta 0.02), or over most of the declared ranges."""
    f = st.floats
    l = draw(f(0.05, 1.0) if wide else f(0.3, 0.8))
    a = l * draw(f(0.01, 0.99) if wide else f(0.1, 0.95))
    zeta = draw(st.one_of(st.sampled_from([0.0, 1.0]), f(0.0, 2.0)) if wide else
                st.one_of(st.just(0.0), f(0.0, 0.3)))
    if wide:
        rest = f(10.0, 1e6), f(0.01, 50.0), f(0.01, 50.0), f(1e-4, 10.0)
    else:
        rest = f(500.0, 2e4), f(0.2, 5.0), f(0.3, 10.0), f(0.01, 0.5)
    return (l, a, *(draw(s) for s in rest), zeta)


def histories(wide=False, longest=40):
    """(a_base, a_base_dot, h) per step: the default drive reaches ±54 m/s² and ±1.8e4 m/s³ at
    a step of 1e-4 s; wide: up to the inputs' declared scale and long steps."""
    a, rate, h = (1e6, 1e9, 0.05) if wide else (1e3, 1e5, 2e-3)
    step = st.tuples(st.floats(-a, a), st.floats(-rate, rate), st.floats(1e-7, h))
    return st.lists(step, min_size=1, max_size=longest)


def check_modal(params, a0, rate0, history, exact_before=True):
    py = carriage.CarriageModal(carriage.CarriageParams(*params))
    c = native("CarriageModal", params)
    # CarriageModalSlave.initialize, then one model.step per doStep
    U = py.static_deflection(a0)
    q, dq = py.modal(U), (0.0, 0.0)
    state = c.initialize([a0, rate0])
    # before initialization: the static deflection under the held a_base, at rest (or, where
    # the modes are ill-conditioned, what the slave reads once initialized: the docstring)
    before = c.outputs(state, [a0, rate0], 0.0, len(MODAL_ROW))
    U_before = U if exact_before else py.physical(q, dq)[0]
    assert_twins([before], [(*U_before, 0.0, 0.0, *py.omega)], MODAL_ROW)
    py_states, c_states, py_rows, c_rows = [(*q, *dq)], [state], [], []
    t = 0.0
    for a, rate, h in history:
        q, dq = py.step(q, dq, a, rate, h)
        state = c.advance(state, [a, rate], t, h)
        t += h
        U, dU = py.physical(q, dq)
        py_states.append((*q, *dq))
        c_states.append(state)
        py_rows.append((*U, *dU, *py.omega))
        c_rows.append(c.outputs(state, [a, rate], t, len(MODAL_ROW)))
    assert_twins(c_states, py_states, MODAL_STATE)
    assert_twins(c_rows, py_rows, MODAL_ROW)


@settings(deadline=None, max_examples=40)
@given(carriages(), st.floats(-1e3, 1e3), st.floats(-1e5, 1e5), histories())
def test_carriage_modal_steps_as_the_python_model(params, a0, rate0, history):
    check_modal(params, a0, rate0, history)


def test_carriage_modal_default_experiment():
    """The FMU's own run: defaults, a_base 0 and its rate 17967 m/s³ held, 120 steps of 1e-4 s."""
    params = astuple(carriage.CarriageParams())
    rate = 17967.066500827565
    check_modal(params, 0.0, rate, [(rate * k * 1e-4, rate, 1e-4) for k in range(120)])


@pytest.mark.slow
@settings(deadline=None, max_examples=400)
@given(carriages(wide=True), st.floats(-1e6, 1e6), st.floats(-1e9, 1e9),
       histories(wide=True, longest=200))
def test_carriage_modal_explored(params, a0, rate0, history):
    check_modal(params, a0, rate0, history, exact_before=False)


# --- CarriageDrive -----------------------------------------------------------------------------
DRIVE_ROW = ("x", "v", "a", "jerk")


@st.composite
def drive_inputs(draw, params, wide=False):
    """(φ, ω, ε) per read: φ anywhere, or exactly where a transport window opens or closes (the
    cycloid's ends, and the floor of φ/2π at a whole turn)."""
    _, window, phi_start = params
    turn = st.integers(-3, 2000 if wide else 30)
    phi = st.one_of(st.floats(-100.0, 1e5 if wide else 1e3),
                    turn.map(lambda k: phi_start + 2 * math.pi * k),
                    turn.map(lambda k: phi_start + 2 * math.pi * window + 2 * math.pi * k))
    omega = st.floats(-2000.0, 2000.0)
    epsilon = st.floats(-1e7, 1e7) if wide else st.floats(-1e5, 1e5)
    return draw(st.lists(st.tuples(phi, omega, epsilon), min_size=1, max_size=60))


def drives(wide=False):
    """CarriageDriveParams' fields: stitch_length (default 3 mm), window (0.5), phi_start (0)."""
    stitch = st.floats(1e-5, 1.0) if wide else st.floats(5e-4, 1e-2)
    window = st.floats(0.001, 0.999) if wide else st.floats(0.1, 0.9)
    start = st.one_of(st.just(0.0), st.floats(0.0, 2 * math.pi))
    return st.tuples(stitch, window, start)


def check_drive(params, reads):
    py = carriage.CarriageDrive(carriage.CarriageDriveParams(*params))
    c = native("CarriageDrive", params)
    py_rows = [tuple(py.motion(*u)) for u in reads]
    c_rows = [c.outputs([], list(u), 0.0, len(DRIVE_ROW)) for u in reads]
    assert_twins(c_rows, py_rows, DRIVE_ROW)


@settings(deadline=None, max_examples=40)
@given(drives().flatmap(lambda p: st.tuples(st.just(p), drive_inputs(p))))
def test_carriage_drive_moves_as_the_python_model(case):
    check_drive(*case)


@pytest.mark.slow
@settings(deadline=None, max_examples=1000)
@given(drives(wide=True).flatmap(lambda p: st.tuples(st.just(p), drive_inputs(p, wide=True))))
def test_carriage_drive_explored(case):
    check_drive(*case)


# --- refusals ----------------------------------------------------------------------------------
# values each check of parameters.py has its own words for: not finite, zero and negative, a
# fraction's ends, beyond the machine's scale with the hint of another unit (3 m: mm?, 63 kg:
# g?, 110 rad: deg?) and without (1e8 N·m², 1e5 kg); values whose repr is not printf's (-2^-24:
# the gap below a power of two is half the gap above); values so small that the model's powers
# underflow and Python divides by zero
SPECIAL = (math.nan, math.inf, -math.inf, 0.0, -0.0, -1.5, 1.0, 1.5, 3.0, 63.0, 110.0, 1e5, 1e8,
           1e16, 1e-5, 1.25e-300, 5e-324, 1e-160, -2.0 ** -24, 2.0 ** 70, 123456789.125)


def maybe_bad(good):
    return st.one_of(good, st.sampled_from(SPECIAL), st.floats())


@settings(deadline=None, max_examples=100)
@given(st.tuples(*(maybe_bad(s) for s in (st.floats(0.1, 1.0), st.floats(0.05, 0.6),
                                          st.floats(100.0, 1e5), st.floats(0.1, 5.0),
                                          st.floats(0.1, 5.0), st.floats(0.01, 1.0),
                                          st.floats(0.0, 0.5)))))
def test_carriage_modal_refuses_as_the_python_model(params):
    py = refusal(lambda: carriage.CarriageModal(carriage.CarriageParams(*params)))
    c = refusal(lambda: native("CarriageModal", params))
    assert c == py


@settings(deadline=None, max_examples=100)
@given(st.tuples(maybe_bad(st.floats(1e-4, 0.01)), maybe_bad(st.floats(0.1, 0.9)),
                 maybe_bad(st.floats(0.0, 6.0))))
def test_carriage_drive_refuses_as_the_python_model(params):
    py = refusal(lambda: carriage.CarriageDrive(carriage.CarriageDriveParams(*params)))
    c = refusal(lambda: native("CarriageDrive", params))
    assert c == py


@pytest.mark.parametrize("params, words", [
    ((0.515, 0.6, 2604.0, 1.0, 2.5, 0.1178, 0.02), "0 < a < l = 0.515 m, got 0.6"),
    ((0.515, 0.515, 2604.0, 1.0, 2.5, 0.1178, 0.02), "got 0.515"),
    ((515.0, 0.22, 2604.0, 1.0, 2.5, 0.1178, 0.02), 'meant in mm? give the unit: "515 mm"'),
    ((0.515, 0.22, 2604.0, 1.0, 2500.0, 0.1178, 0.02), "within [0, 50] kg"),
    ((0.515, 0.22, 2604.0, 1.0, 2.5, 0.1178, -0.0), None),
    ((0.515, 0.22, 2604.0, 1.0, 2.5, 0.1178, -2.0 ** -24), "got -5.960464477539063e-08"),
    ((0.515, 1.25e-300, 2604.0, 1.0, 2.5, 0.1178, 0.02), "ZeroDivisionError: float division"),
])
def test_carriage_modal_refusals_named(params, words):
    """A few messages spelled out, so that a shared mistake of both is seen too."""
    py = refusal(lambda: carriage.CarriageModal(carriage.CarriageParams(*params)))
    c = refusal(lambda: native("CarriageModal", params))
    assert c == py
    assert (words is None and c is None) or words in c


@pytest.mark.parametrize("params, words", [
    ((3.0, 0.5, 0.0), 'meant in mm? give the unit: "3 mm"'),
    ((3e-3, 1.0, 0.0), "parameter window: must be in (0, 1) 1, got 1.0"),
    ((3e-3, 0.5, 110.0), 'within [0, 6.28319] rad in a sewing machine\'s mechanism, got 110 '
                         '(meant in deg? give the unit: "110 deg")'),
    ((3e-3, 1e-160, 0.0), "ZeroDivisionError: float division by zero"),
])
def test_carriage_drive_refusals_named(params, words):
    py = refusal(lambda: carriage.CarriageDrive(carriage.CarriageDriveParams(*params)))
    c = refusal(lambda: native("CarriageDrive", params))
    assert c == py
    assert words in c
