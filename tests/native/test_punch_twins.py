"""The punch's C twins against the Python models, call for call: native/models/oscillator.c
(components/oscillator.py), punch_contact.c (punch_contact.py's PunchContact, punch_split.py's
PunchBody) and fabric.c (punch_split.py's Fabric), each called as components/punch_fmu.py's
slaves call the Python model (inputs in the slave's order, the state as PunchState's fields).

Parameters are drawn from their dataclass's metadata around their defaults (×/÷ 3), dampings
also 0, spring 11 bilateral and compression only, its preload F30 off and on (and a property of
its own for the punch riding on a preloaded stop: held, released, held again). Inputs are
histories of steps: the excitation carried on by its Taylor polynomial and now and then jumping,
or the slider's stroke through bottom dead centre at a machine's speed. Every output and every
state value after every step agrees within 1e-12 relative; near 0 (a fabric force at the end of
a contact is the difference of two terms of ~10 N) a relative bound says nothing, so the floor is
1e-12 of the quantity's scale in the mechanism (10 mm, 1 m/s, 1000 m/s², 1 kN, 10 ms): what
rounding leaves of such a difference. Flags and counts agree exactly. Measured: the twins agree
bit for bit (every example of test_twin_explored, compared exactly)."""
from __future__ import annotations

import ctypes
import math
from dataclasses import fields, replace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sewfmu.components.oscillator import DampedOscillator
from sewfmu.components.parameters import CHOICE, NONNEGATIVE, ParameterError, parameter_info
from sewfmu.components.punch_contact import (
    PunchContact,
    PunchContactParams,
    PunchState,
    StepTooLong,
    ZenoError,
)
from sewfmu.components.punch_fmu import FabricSlave, PunchBodySlave, PunchContactSlave
from sewfmu.components.punch_split import Fabric, FabricParams, PunchBody, PunchBodyParams
from tests.native.model_twin import ModelError, library, native_model

PUNCH = ("parameters", "punch_contact", "oscillator")
FABRIC = ("parameters", "fabric")
RELATIVE = 1e-12
# the scale of a quantity of each unit in the punch drive: the floor is RELATIVE of it
SCALE = {"m": 1e-2, "m/s": 1.0, "m/s2": 1e3, "N": 1e3, "N/s": 1e6, "s": 1e-2}
STATE_UNITS = {"y": "m", "y_dot": "m/s", "F2_max": "N"}      # the others are flags and counts
FACTOR = 3.0
# a parameter that is 0 by default (the preload F30) is drawn off, or on around this
ON_AROUND = {"N": 20.0}
D_HAS_STOP = 11                     # punch_contact.c's derived[D_HAS_STOP]


def _agree(c: float, py: float, unit: str) -> bool:
    """The C value c agrees with the Python value py of a quantity of this unit ("exact": a
    flag or a count)."""
    if unit not in SCALE:
        return c == py
    return abs(c - py) <= max(RELATIVE * abs(py), RELATIVE * SCALE[unit])


def _assert_row(c_row, py_row, ports, where):
    for port, c, py in zip(ports, c_row, py_row, strict=True):
        unit = port.unit if port.kind == "Real" else "exact"
        assert _agree(c, float(py), unit), f"{where}: {port.name} C {c!r} Python {py!r}"


def _assert_state(c_state, py_state: PunchState, where):
    for name, c in zip(PunchState._fields, c_state, strict=True):
        py = float(getattr(py_state, name))
        assert _agree(c, py, STATE_UNITS.get(name, "exact")), \
            f"{where}: state {name} C {c!r} Python {py!r}"


def _around(default: float):
    return st.floats(-math.log(FACTOR), math.log(FACTOR)).map(lambda x: default * math.exp(x))


def _params(cls, **fixed):
    """An instance of a parameter dataclass, each field drawn from its metadata (or from the
    strategy `fixed` gives it)."""
    def one(f):
        allowed, unit = f.metadata["allowed"], f.metadata["unit"]
        if allowed == CHOICE:
            return st.sampled_from(f.metadata["choices"])
        if f.default == 0.0:
            return st.one_of(st.just(0.0), _around(ON_AROUND[unit]))
        if allowed == NONNEGATIVE:
            return st.one_of(_around(f.default), st.just(0.0))
        return _around(f.default)
    return st.builds(cls, **{f.name: fixed[f.name] if f.name in fixed else one(f)
                             for f in fields(cls)})


def _values(params):
    return [getattr(params, f.name) for f in fields(params)]


# the excitation: where the linkage puts the slider (top 4.5 mm, pressing into the fabric
# below 0), how fast, and the step sizes of a host
XI = st.floats(-1.5e-3, 5e-3)
# at rest now and then: where a preloaded stop holds the punch from the start
XI_DOT = st.one_of(st.floats(-1.0, 1.0), st.just(0.0))
XI_DDOT = st.floats(-500.0, 500.0)
H = st.one_of(st.floats(1e-6, 1e-3), st.sampled_from([1e-4, 2.5e-4]))


def _taylor_history(start, steps):
    """[(xi, xi_dot, xi_ddot, h)] at each step's start: the excitation carried on by its Taylor
    polynomial, a new acceleration at each step, and now and then a jump."""
    xi, xi_dot, xi_ddot = start
    history = []
    for h, next_ddot, jump in steps:
        history.append((xi, xi_dot, xi_ddot, h))
        xi, xi_dot = xi + xi_dot * h + 0.5 * xi_ddot * h * h, xi_dot + xi_ddot * h
        xi_ddot = next_ddot
        if jump is not None:
            xi, xi_dot = jump
    return history


def _stroke_history(top, bottom, speed, phase, h, n):
    """The slider's harmonic stroke between top and bottom at the shaft speed (rad/s), from a
    phase between top and bottom dead centre: the punch rides on the stop of spring 11 (if
    preloaded), lands, presses the fabric, lifts off."""
    centre, amplitude = 0.5 * (top + bottom), 0.5 * (top - bottom)
    history = []
    for k in range(n):
        angle = phase + speed * k * h
        history.append((centre + amplitude * math.cos(angle),
                        -amplitude * speed * math.sin(angle),
                        -amplitude * speed ** 2 * math.cos(angle), h))
    return history


STROKE = st.builds(_stroke_history, top=st.floats(3e-3, 5e-3), bottom=st.floats(-1.5e-3, 0.0),
                   speed=st.floats(100.0, 500.0),
                   phase=st.one_of(st.just(0.0), st.floats(0.0, math.pi)),
                   h=st.sampled_from([1e-4, 2.5e-4, 5e-4]), n=st.integers(2, 30))
HISTORY = st.one_of(
    st.builds(_taylor_history, st.tuples(XI, XI_DOT, XI_DDOT),
              st.lists(st.tuples(H, XI_DDOT, st.one_of(st.none(), st.tuples(XI, XI_DOT))),
                       min_size=1, max_size=10)),
    STROKE)
# spring 11 compression only and preloaded: the punch rides on its stop from top dead centre
ON_STOP = dict(compression_only=st.just(1), F30=_around(30.0))
STROKE_FROM_TOP = st.builds(_stroke_history, top=st.floats(3e-3, 5e-3),
                            bottom=st.floats(-1.5e-3, 0.0), speed=st.floats(100.0, 500.0),
                            phase=st.just(0.0), h=st.sampled_from([1e-4, 2.5e-4, 5e-4]),
                            n=st.integers(10, 40))


def _run_punch(model, native, n_row, ports, history, ext=None):
    """Both models through one history; ext (F2, F2_dot) per step for PunchBody, else none.
    Returns the Python model's refusal of a step (which the C model refused the same way)."""
    xi, xi_dot, xi_ddot, _ = history[0]
    force = ext[0] if ext else None
    u = [xi, xi_dot, xi_ddot] + ([force, 0.0] if ext else [])
    py = model.initial_state(xi, xi_dot, xi_ddot, *([force] if ext else []))
    c = native.initialize(u)
    _assert_state(c, py, "initial state")
    t = 0.0
    for k, (xi, xi_dot, xi_ddot, h) in enumerate(history):
        e = ext[1][k % len(ext[1])] if ext else ()
        u = [xi, xi_dot, xi_ddot, *e]
        row = _project(model.outputs(py, xi, xi_dot, xi_ddot, *e[:1]), ports)
        _assert_row(native.outputs(c, u, t, n_row), row, ports, f"outputs before step {k}")
        try:
            py = model.step(py, xi, xi_dot, 0.5 * xi_ddot, h, *e)
        except (StepTooLong, ZenoError) as err:
            with pytest.raises(ModelError) as refused:
                native.advance(c, u, t, h)
            assert str(refused.value) == str(err)
            return err
        c = native.advance(c, u, t, h)
        t += h
        _assert_state(c, py, f"state after step {k} (h = {h!r})")
    return None


def _project(outputs, ports):
    return [getattr(outputs, p.name) for p in ports]


def check_punch_contact(params, history):
    native = native_model("PunchContact", _values(params), *PUNCH)
    ports = PunchContactSlave.outputs
    _run_punch(PunchContact(params), native, len(ports), ports, history)


def check_punch_body(params, history, force):
    native = native_model("PunchBody", _values(params), *PUNCH)
    ports = PunchBodySlave.outputs
    _run_punch(PunchBody(params), native, len(ports), ports, history, ext=(force[0][0], force))


def check_fabric(params, steps):
    """FabricSlave's state (F2_max, t_switch) and row, as it works them out from Fabric."""
    fabric = Fabric(params)
    native = native_model("Fabric", _values(params), *FABRIC)
    ports = FabricSlave.outputs
    c = native.initialize([0.0, 0.0, 0.0])
    t = 0.0
    for k, (y, v, a, h) in enumerate(steps):
        seen = fabric.step(y, v, a, h)
        f2_max = seen.F2_max
        t_switch = t + seen.switches[-1][0] if seen.switches else -1.0
        c = native.advance(c, [y, v, a], t, h)
        t += h
        assert _agree(c[0], f2_max, "N") and _agree(c[1], t_switch, "s"), (k, c, seen)
        f2 = fabric.force(y, v)
        row = (f2, fabric.force_rate(y, v, a), f2 > 0.0, max(f2_max, f2), t_switch)
        _assert_row(native.outputs(c, [y, v, a], t, len(ports)), row, ports, f"step {k}")


# the fabric's force on PunchBody, per step (F2, F2_dot), cycled through the history: off
# (the punch in the air), light, pressing
F2 = st.one_of(st.just(0.0), st.floats(0.0, 20.0), st.floats(0.0, 200.0))
F2_DOT = st.one_of(st.just(0.0), st.floats(-2e4, 2e4), st.floats(-2e5, 2e5))
FORCE = st.lists(st.tuples(F2, F2_DOT), min_size=1, max_size=4)
Y = st.floats(-2e-3, 2e-3)
Y_DOT = st.floats(-1.0, 1.0)
Y_DDOT = st.floats(-3000.0, 3000.0)
# each property: its check and what it is given
PROPERTIES = {
    "PunchContact": (check_punch_contact, dict(params=_params(PunchContactParams),
                                                history=HISTORY)),
    "PunchBody": (check_punch_body, dict(params=_params(PunchBodyParams), history=HISTORY,
                                         force=FORCE)),
    "PunchContact on its stop": (check_punch_contact,
                                 dict(params=_params(PunchContactParams, **ON_STOP),
                                      history=STROKE_FROM_TOP)),
    "PunchBody on its stop": (check_punch_body,
                              dict(params=_params(PunchBodyParams, **ON_STOP),
                                   history=STROKE_FROM_TOP,
                                   force=FORCE)),
    "Fabric": (check_fabric, dict(params=_params(FabricParams),
                                  steps=st.lists(st.tuples(Y, Y_DOT, Y_DDOT, H), min_size=1,
                                                 max_size=8))),
}


def _explore(model: str, examples: int) -> None:
    check, given_ = PROPERTIES[model]
    settings(max_examples=examples, deadline=None)(given(**given_)(check))()


@pytest.mark.parametrize("model, examples", [("PunchContact", 60), ("PunchBody", 40),
                                             ("PunchContact on its stop", 60),
                                             ("PunchBody on its stop", 60),
                                             ("Fabric", 60)])
def test_twin(model, examples):
    _explore(model, examples)


@pytest.mark.slow
@pytest.mark.parametrize("model", sorted(PROPERTIES))
def test_twin_explored(model):
    """Many more examples (about 40 s in all)."""
    _explore(model, 1000)


def test_too_long_a_step_is_refused_by_both_with_the_same_words():
    model = PunchContact()
    native = native_model("PunchContact", _values(PunchContactParams()), *PUNCH)
    s, c = model.initial_state(4.5e-3, 0.0), native.initialize([4.5e-3, 0.0, 0.0])
    with pytest.raises(StepTooLong) as err:
        model.step(s, 4.5e-3, 0.0, 0.0, 10.0)
    with pytest.raises(ModelError) as refused:
        native.advance(c, [4.5e-3, 0.0, 0.0], 0.0, 10.0)
    assert str(refused.value) == str(err.value)


def test_a_chattering_contact_is_refused_by_both_with_the_same_words():
    """tests/components/test_punch_contact.py's light punch on a stiff, damped, preloaded stop,
    with the stop disabled in both (has_stop): the exact micro-bouncing overruns the switch
    budget of a 5 ms step."""
    p = PunchContactParams(m=0.0078125, c1=5965.0, c2=1000.0, c3=64466.0, F10=0.0, b1=0.0,
                           b2=0.0, b3=19.0, F30=12.0, compression_only=1)
    model = PunchContact(p)
    model.has_stop = False
    native = native_model("PunchContact", _values(p), *PUNCH)
    native.derived[D_HAS_STOP] = 0.0
    ports = PunchContactSlave.outputs
    refusal = _run_punch(model, native, len(ports), ports,
                         _taylor_history((3e-3, -0.4, 0.0), [(5e-3, 0.0, None)] * 3))
    assert isinstance(refusal, ZenoError)


def _bad_value(info):
    """Values the parameter's rules refuse: below its sign, not finite, beyond the machine's
    scale of its unit (up to where the hint 'meant in g?' stops), not a choice."""
    high = info.bounds[1]
    if info.allowed == CHOICE:
        return st.sampled_from([2, -1, 3])
    below = st.floats(max_value=-1e-300) if info.allowed == NONNEGATIVE else \
        st.floats(max_value=0.0)
    return st.one_of(below, st.sampled_from([math.nan, math.inf, -math.inf]),
                     st.floats(min_value=high * (1 + 1e-12), allow_infinity=False),
                     st.floats(min_value=high * (1 + 1e-12), max_value=high * 2000.0))


def _refused(cls):
    """(name, value) of one parameter of cls and a value its rules refuse."""
    return st.sampled_from(parameter_info(cls)).flatmap(
        lambda info: _bad_value(info).map(lambda v: (info.name, v)))


@pytest.mark.parametrize("cls, model_class, name, sources", [
    (PunchContactParams, PunchContact, "PunchContact", PUNCH),
    (PunchBodyParams, PunchBody, "PunchBody", PUNCH),
    (FabricParams, Fabric, "Fabric", FABRIC),
])
def test_bad_parameters_are_refused_by_both_with_the_same_words(cls, model_class, name,
                                                                sources):
    @settings(max_examples=40, deadline=None)
    @given(bad=_refused(cls))
    def check(bad):
        field, value = bad
        params = replace(cls(), **{field: value})
        with pytest.raises(ParameterError) as err:
            model_class(params)
        with pytest.raises(ModelError) as refused:
            native_model(name, _values(params), *sources)
        assert str(refused.value) == str(err.value)
    check()


class _Oscillator(ctypes.Structure):
    """native/models/oscillator.h's SewOscillator."""
    _fields_ = [(n, ctypes.c_double) for n in (
        "m b c f0 f1 f2 p0 p1 p2 l1_re l1_im l2_re l2_im k1_re k1_im k2_re k2_im".split())] + \
        [("critical", ctypes.c_int)]


@settings(max_examples=60, deadline=None)
@given(m=_around(0.063), c=st.floats(1e2, 1e6), damping=st.one_of(
           st.floats(0.0, 3.0), st.sampled_from([1.0, 1.0 + 1e-14, 1.0 - 1e-9, 0.0])),
       f=st.tuples(*[st.floats(-1e3, 1e3)] * 3), y0=st.floats(-1e-2, 1e-2),
       v0=st.floats(-1.0, 1.0), taus=st.lists(st.floats(0.0, 1e-2), min_size=1, max_size=4))
def test_oscillator_twin(m, c, damping, f, y0, v0, taus):
    """Under, over and critically damped (damping: b over the critical 2·sqrt(m·c))."""
    lib = library("oscillator")
    b = damping * 2.0 * math.sqrt(m * c)
    native = _Oscillator()
    lib.sew_oscillator_init(ctypes.byref(native), *map(ctypes.c_double, (m, b, c, *f, y0, v0)))
    model = DampedOscillator(m, b, c, *f, y0, v0)
    assert bool(native.critical) == model.critical
    lib.sew_oscillator_accel.restype = ctypes.c_double
    for tau in taus:
        y, v = ctypes.c_double(), ctypes.c_double()
        lib.sew_oscillator_state(ctypes.byref(native), ctypes.c_double(tau), ctypes.byref(y),
                                 ctypes.byref(v))
        py_y, py_v = model.state(tau)
        assert _agree(y.value, py_y, "m") and _agree(v.value, py_v, "m/s"), (tau, y, v)
        a = lib.sew_oscillator_accel(ctypes.byref(native), *map(ctypes.c_double, (tau, py_y,
                                                                                   py_v)))
        assert _agree(a, model.accel(tau, py_y, py_v), "m/s2")
