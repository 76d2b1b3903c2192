"""The linkages' C twins (native/models/punch_linkage.c, takeup.c, feed.c over kinematics.c) held
equal to the Python models (sewfmu.components.punch_linkage, takeup, feed) over random parameters
around the defaults and random shaft motion (phi, omega, epsilon): every output within 1e-12
relative, the punch's top (alpha0, y_top) too, and the same refusals with the same messages
(a parameter out of its range, a six-bar or four-bar that cannot be assembled somewhere on the
turn, the required displacement longer than a revolution).

The Python side is read as components/linkage_slave.py's LinkageSlave reads it: the model's
motion(phi, omega, epsilon), each output where its port's `source` says; one test goes through
the slave classes themselves, in-process.

The floor near 0: an output is compared within 1e-12 of the larger of its own magnitude and its
quantity's scale in the mechanism: a position that of the mechanism's size (its largest length
or pivot coordinate), a velocity size·|omega|, an acceleration size·(omega² + |epsilon|), an
angle π. Each output is a sum of terms of that order (xi = xi0 - (y_top - y_D); a velocity
r·ω·sin), so a rounding difference in one of them scales with it, not with a value that passes
through 0 (psi at the top, xi_dot at a dead point). Measured: both agree to the last bit (the
same operations, the same libm, in one process)."""
from __future__ import annotations

import math
from dataclasses import fields

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sewfmu.components.feed import FeedLinkage, FeedParams
from sewfmu.components.feed_fmu import FeedLinkageSlave
from sewfmu.components.fmi2_layer import Fmi2Layer
from sewfmu.components.kinematics import AssemblyError
from sewfmu.components.parameters import ANY, CHOICE, POSITIVE, ParameterError, parameter_info
from sewfmu.components.punch_fmu import PunchLinkageSlave
from sewfmu.components.punch_linkage import PunchLinkage, PunchLinkageParams
from sewfmu.components.takeup import TakeupLinkage, TakeupParams
from sewfmu.components.takeup_fmu import TakeupLinkageSlave
from tests.native.model_twin import ModelError, native_model

RELATIVE = 1e-12
SOURCES = ("parameters", "kinematics", "punch_linkage", "takeup", "feed")
# what Python raises where the C model returns -1 (the model's own checks, and float division
# by zero or x ** 2 out of range on the way)
REFUSALS = (ParameterError, AssemblyError, ZeroDivisionError, OverflowError)

# model name -> (parameter dataclass, Python model, slave class, relative spread of the random
# parameters: about half of the draws cannot be assembled somewhere on the turn)
LINKAGES = {
    "PunchLinkage": (PunchLinkageParams, PunchLinkage, PunchLinkageSlave, 0.15),
    "TakeupLinkage": (TakeupParams, TakeupLinkage, TakeupLinkageSlave, 0.35),
    "FeedLinkage": (FeedParams, FeedLinkage, FeedLinkageSlave, 0.08),
}


def python_params(name: str, values):
    """The parameter dataclass of `values` (floats in field order), a choice made int as
    SewSlave.model makes it."""
    params_class = LINKAGES[name][0]
    infos = parameter_info(params_class)
    return params_class(**{info.name: int(v) if info.allowed == CHOICE and math.isfinite(v)
                           else v for info, v in zip(infos, values)})


def row_of(slave_class, motion) -> list[float]:
    """The slave's outputs read from a motion, each where its port's `source` says."""
    row = []
    for port in slave_class.outputs:
        value = motion
        for key in (port.source or port.name).split("."):
            value = value[key] if isinstance(value, dict) else getattr(value, key)
        row.append(float(value))
    return row


def size_of(name: str, values) -> float:
    """The mechanism's size: its largest length or pivot coordinate (m)."""
    infos = parameter_info(LINKAGES[name][0])
    return max(abs(v) for info, v in zip(infos, values) if info.unit == "m")


def assert_rows(name: str, c_row, py_row, size: float, u) -> None:
    """Every output within 1e-12 of the larger of its magnitude and its quantity's scale (the
    module's docstring: why)."""
    omega, epsilon = abs(u[1]), abs(u[2])
    scale = {"m": size, "m/s": size * omega, "m/s2": size * (omega * omega + epsilon),
             "rad": math.pi}
    for port, c, py in zip(LINKAGES[name][2].outputs, c_row, py_row):
        assert abs(c - py) <= RELATIVE * max(abs(py), scale[port.unit]), \
            f"{name}.{port.name} at (phi, omega, epsilon) = {u}: C {c!r}, Python {py!r}"


def assert_twins(name: str, values, inputs) -> bool:
    """The C model and the Python model built from `values`: the same refusal, or the same
    outputs at every (phi, omega, epsilon) of `inputs`. True where both built."""
    _, model_class, slave_class, _ = LINKAGES[name]
    try:
        model = model_class(python_params(name, values))
    except REFUSALS as err:
        with pytest.raises(ModelError) as refused:
            native_model(name, values, *SOURCES)
        assert str(refused.value) == str(err)
        return False
    c = native_model(name, values, *SOURCES)
    if name == "PunchLinkage":        # the top of the slider, worked out once in build
        assert abs(c.derived[0] - model.alpha0) <= RELATIVE * math.pi
        assert abs(c.derived[1] - model.y_top) <= RELATIVE * size_of(name, values)
    for u in inputs:
        try:
            py_row = row_of(slave_class, model.motion(*u))
        except REFUSALS as err:
            with pytest.raises(ModelError) as refused:
                c.outputs([], u, 0.0, len(slave_class.outputs))
            assert str(refused.value) == str(err)
            continue
        c_row = c.outputs([], u, 0.0, len(slave_class.outputs))
        assert_rows(name, c_row, py_row, size_of(name, values), u)
    return True


@st.composite
def parameters(draw, name: str, spread: float | None = None):
    """Values of the linkage's parameters in field order, each around its default: a length
    or angle within ±spread of it, a coordinate that is 0 by default within ±spread·20 mm, an
    angle of any sign ±spread rad from it, a choice any of its choices."""
    params_class, _, _, default_spread = LINKAGES[name]
    spread = default_spread if spread is None else spread
    values = []
    for info in parameter_info(params_class):
        if info.allowed == CHOICE:
            values.append(float(draw(st.sampled_from(info.choices))))
        elif info.unit == "rad" and info.allowed == ANY:
            values.append(info.default + draw(st.floats(-spread, spread)))
        elif info.default == 0.0:
            values.append(draw(st.floats(-spread, spread)) * 0.02)
        else:
            values.append(info.default * (1.0 + draw(st.floats(-spread, spread))))
    return values


# shaft motion within the inputs' declared ranges (phi is cumulative: many turns either way)
shaft = st.tuples(st.floats(-1e4, 1e4), st.floats(-2000.0, 2000.0), st.floats(-1e7, 1e7))
motions = st.lists(shaft, min_size=1, max_size=12)


# --- the models, called alone --------------------------------------------------------------------
def test_the_models_are_stateless_linkages():
    for name, (params_class, *_) in LINKAGES.items():
        defaults = [float(f.default) for f in fields(params_class)]
        model = native_model(name, defaults, *SOURCES).model
        assert model.name.decode() == name
        assert model.n_state == 0 and not model.advance and not model.initialize
        assert model.n_derived == (2 if name == "PunchLinkage" else 0)


@settings(max_examples=10, deadline=None)
@given(values=parameters("PunchLinkage"), inputs=motions)
def test_punch_linkage_twin(values, inputs):
    assert_twins("PunchLinkage", values, inputs)


@settings(max_examples=6, deadline=None)
@given(values=parameters("TakeupLinkage"), inputs=motions)
def test_takeup_twin(values, inputs):
    assert_twins("TakeupLinkage", values, inputs)


# the Python assembly check of the feed mechanism takes 0.3 s: few draws in the fast loop
@settings(max_examples=3, deadline=None)
@given(values=parameters("FeedLinkage"), inputs=motions)
def test_feed_twin(values, inputs):
    assert_twins("FeedLinkage", values, inputs)


def _bad_values(info) -> list[float]:
    """Values the parameter check refuses, one for each of its messages."""
    if info.allowed == CHOICE:
        return [2.0, -1.0, math.nan]
    low, high = info.bounds
    meant = {"m": 1e3, "rad": 180.0 / math.pi}[info.unit]
    # finite; the sign; beyond the machine's scale, with and without "meant in mm/deg?"
    bad = [math.nan, math.inf, -math.inf, high * meant * 0.5, high * meant * 3.0]
    if info.allowed != ANY:
        bad += [-1e-5, -0.25, -1e-300] + ([0.0, -0.0] if info.allowed == POSITIVE else [])
    else:
        bad += [low * meant * 0.5, -high * 1e6]
    return bad


@pytest.mark.parametrize("name", sorted(LINKAGES))
def test_a_parameter_out_of_its_range_is_refused_with_pythons_message(name):
    defaults = [float(f.default) for f in fields(LINKAGES[name][0])]
    for i, info in enumerate(parameter_info(LINKAGES[name][0])):
        for bad in _bad_values(info):
            values = defaults[:i] + [bad] + defaults[i + 1:]
            assert not assert_twins(name, values, []), f"{info.name} = {bad!r} was taken"


@pytest.mark.parametrize("name, changes", [
    # the coupler too short to reach the rocker, with a pivot coordinate listed as 1e-05
    ("PunchLinkage", {"L_AB": 0.02, "x_O2": 1e-5}),
    ("PunchLinkage", {"x_D": 0.06}),              # the rod cannot reach the slider line at 181.5°
    ("PunchLinkage", {"y_O2": 0.046}),            # the coupler cannot reach the rocker at 206.9°
    ("PunchLinkage", {"mode": 1, "phi_dwell": 1.2}),        # longer than a revolution
    ("TakeupLinkage", {"L_CD": 0.01}),            # at 104.3°
    ("FeedLinkage", {"l3": 0.01, "x_G": -1.5e-5}),
    ("FeedLinkage", {"r_f": 0.0246}),             # rod 4 cannot reach lever 5 at 154.8°
])
def test_what_cannot_be_assembled_is_refused_with_pythons_message(name, changes):
    params_class = LINKAGES[name][0]
    values = [float(changes.get(f.name, f.default)) for f in fields(params_class)]
    assert not assert_twins(name, values, [])


# --- through the slave classes ------------------------------------------------------------------
def slave_of(slave_class):
    """The slave class joined with its FMI 2.0 layer, as `sewfmu build` joins them, in-process."""
    joined = type(slave_class.__name__, (slave_class, Fmi2Layer), {"__doc__": slave_class.__doc__})
    return joined(instance_name="twin")


def slave_row(slave_class, values, u) -> list[float]:
    """The slave's outputs after a host set its parameters to `values` and its inputs to u."""
    slave = slave_of(slave_class)
    vr = {variable.name: ref for ref, variable in slave.vars.items()}
    for info, value in zip(parameter_info(slave_class.params_class), values):
        if info.allowed == CHOICE:
            slave.set_integer([vr[info.name]], [int(value)])
        else:
            slave.set_real([vr[info.name]], [value])
    slave.set_real([vr["phi"], vr["omega"], vr["epsilon"]], list(u))
    return slave.get_real([vr[port.name] for port in slave_class.outputs])


@pytest.mark.parametrize("name", sorted(LINKAGES))
@settings(max_examples=2, deadline=None)
@given(data=st.data())
def test_the_slaves_row_is_the_c_models_row(name, data):
    # a small spread: a draw that cannot be assembled gives NaN rows, not a comparison
    values = data.draw(parameters(name, spread=0.01))
    u = data.draw(shaft)
    slave_class = LINKAGES[name][2]
    c_row = native_model(name, values, *SOURCES).outputs([], u, 0.0, len(slave_class.outputs))
    assert_rows(name, c_row, slave_row(slave_class, values, u), size_of(name, values), u)


# --- longer exploration --------------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(LINKAGES))
# 60 examples: each builds the Python model, whose assembly check (3600 crank angles) is
# most of the time; the fast tests above and a hypothesis profile with more examples go wider
@settings(max_examples=max(60, settings.default.max_examples), deadline=None)
@given(data=st.data())
def test_linkage_twins_explored(name, data):
    spread = data.draw(st.sampled_from([0.02, LINKAGES[name][3], 2 * LINKAGES[name][3]]))
    values = data.draw(parameters(name, spread=spread))
    assert_twins(name, values, data.draw(st.lists(shaft, min_size=1, max_size=40)))


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(LINKAGES))
@settings(max_examples=max(60, settings.default.max_examples), deadline=None)
@given(data=st.data())
def test_any_value_of_one_parameter_explored(name, data):
    params_class = LINKAGES[name][0]
    infos = parameter_info(params_class)
    i = data.draw(st.integers(0, len(infos) - 1))
    values = [float(f.default) for f in fields(params_class)]
    values[i] = float(data.draw(st.sampled_from(infos[i].choices)) if infos[i].allowed == CHOICE
                      else data.draw(st.floats(allow_nan=True, allow_infinity=True)))
    assert_twins(name, values, data.draw(st.lists(shaft, min_size=1, max_size=5)))
