"""The run loop and the algorithms on fake instances (tests/fake_fmu.py): each result against the
closed form of what that algorithm computes, in milliseconds, without an FMU.

The system: two integrators in a loop, a' = b and b' = -a (a harmonic oscillator, z = (a, b),
z' = M z), each extrapolating its input over a step from its rate. Jacobi then takes a second
order Taylor step, z ← (I + hM + h²M²/2) z; the iterative master, converged, the trapezoidal rule,
z ← (I - hM/2)⁻¹ (I + hM/2) z, which keeps |z| = 1.
"""
import dataclasses

import numpy as np
import pytest

from sewfmu.scenarios.cosim.algorithms import ALGORITHMS
from sewfmu.scenarios.cosim.fmi_calls import CosimError, Status
from sewfmu.scenarios.cosim.master import Master
from sewfmu.scenarios.format.master_settings import (
    SETTINGS,
    AdaptiveSettings,
    IterativeSettings,
    SettingError,
)
from sewfmu.scenarios.format.values import ScenarioError
from tests.fake_fmu import Failing, Gain, Integrator, Switch, fake_scenario, maker

M = np.array([[0.0, 1.0], [-1.0, 0.0]])
LOOP = ["b.x -> a.u", "b.x_dot -> a.u_dot", "a.x -> b.u", "a.x_dot -> b.u_dot"]


def oscillator(master: str, stop: float = 2.0, step: float = 0.1, **experiment):
    models = {"a": Integrator(gain=1.0, x0=1.0), "b": Integrator(gain=-1.0)}
    made = {}
    sc = fake_scenario(models, LOOP, stop, step, master, **experiment)
    return Master(sc, {}, make_instance=maker(models, made)).run(), made


def test_jacobi_takes_the_taylor_step_of_the_exchanged_rates():
    result, _ = oscillator("jacobi")
    h, z = 0.1, np.array([1.0, 0.0])
    step = np.eye(2) + h * M + h * h / 2 * M @ M
    for k, t in enumerate(result.time):
        assert t == pytest.approx(k * h, abs=1e-15)
        assert result["a.x"][k] == pytest.approx(z[0], abs=1e-14)
        assert result["b.x"][k] == pytest.approx(z[1], abs=1e-14)
        z = step @ z
    assert len(result.time) == 21 and result.time[-1] == 2.0


@pytest.mark.parametrize("acceleration", ["aitken", "iqn-ils", "none"])
def test_the_iterative_master_converges_to_the_trapezoidal_rule(acceleration):
    result, made = oscillator("iterative", tolerance=1e-12, acceleration=acceleration)
    h = 0.1
    step = np.linalg.solve(np.eye(2) - h / 2 * M, np.eye(2) + h / 2 * M)
    z = np.array([1.0, 0.0])
    for k in range(len(result.time)):
        assert (result["a.x"][k], result["b.x"][k]) == pytest.approx(tuple(z), abs=1e-10)
        z = step @ z
    radius = np.hypot(result["a.x"], result["b.x"])
    assert np.max(np.abs(radius - 1.0)) < 1e-10           # the trapezoidal rule keeps |z|
    assert result.coupling["unconverged_steps"] == 0
    # the loop's two values are linear in the assumed ones: IQN-ILS's secant step solves
    # them after two differences (4 passes with the first and the checking one)
    assert 2 <= result.coupling["iterations_per_step"] <= (4 if acceleration == "iqn-ils" else 12)
    # it rolls back: its FMUs were told their state may be set back; Jacobi's were not
    assert made["a"].no_set_prior == {False}
    assert oscillator("jacobi")[1]["a"].no_set_prior == {True}


def test_gauss_seidel_refuses_a_loop_and_matches_jacobi_along_a_chain():
    with pytest.raises(ScenarioError, match="gauss-seidel.*cannot run the feedback loop of a, b"):
        oscillator("gauss-seidel")
    # a chain: the first integrates 1 (x = t), the second x (exactly t²/2 with the rate)
    results = {}
    for master in ("jacobi", "gauss-seidel"):
        models = {"a": Integrator(), "b": Integrator()}
        sc = fake_scenario(models, ["a.x -> b.u", "a.x_dot -> b.u_dot"], 1.0, 0.125, master,
                           parameters={"a": {"u": 1.0, "u_dot": 0.0}})
        results[master] = Master(sc, {}, make_instance=maker(models)).run()
        t = results[master].time
        assert results[master]["a.x"] == pytest.approx(t, abs=1e-15)
        assert results[master]["b.x"] == pytest.approx(t * t / 2, abs=1e-15)
    assert np.array_equal(results["jacobi"]["b.x"], results["gauss-seidel"]["b.x"])


# A chain through a direct feedthrough: a integrates 1 (a.x = t), g passes y = 2·u on at once, c
# integrates g.y held over each step (c.u_dot = 0). What c sees depends on the exchange's order.
H = 0.125
CHAIN = ["a.x -> g.u", "g.y -> c.u"]


def feedthrough_chain(master: str, **experiment):
    models = {"a": Integrator(), "g": Gain(k=2.0), "c": Integrator()}
    sc = fake_scenario(models, CHAIN, 1.0, H, master, **experiment,
                       parameters={"a": {"u": 1.0, "u_dot": 0.0}, "c": {"u_dot": 0.0}})
    return Master(sc, {}, make_instance=maker(models)).run()


def test_the_order_of_the_exchange_decides_what_a_feedthrough_chain_computes():
    jacobi, gauss_seidel = feedthrough_chain("jacobi"), feedthrough_chain("gauss-seidel")
    t = jacobi.time
    assert np.array_equal(t, gauss_seidel.time) and len(t) == 9
    # Jacobi: after the step g's input is set from a.x(t + h) and g.y read after that, so c steps
    # from c.u = 2t: c.x(nh) = h·Σ_{k<n} 2kh = t·(t - h)
    assert jacobi["g.y"] == pytest.approx(2 * t, abs=1e-12)
    assert jacobi["c.x"] == pytest.approx(t * (t - H), abs=1e-12)
    # Gauss–Seidel sweeps consumers first: g takes a.x as it was before a's step (one step old),
    # c takes g.y before g's step (two steps old): c.x(nh) = h·Σ_{0<k<n} 2(k - 1)h
    assert gauss_seidel["g.y"] == pytest.approx(2 * np.maximum(t - H, 0.0), abs=1e-12)
    assert gauss_seidel["c.x"] == pytest.approx(np.where(t > 0, (t - H) * (t - 2 * H), 0.0),
                                                abs=1e-12)
    assert jacobi["c.x"][-1] - gauss_seidel["c.x"][-1] == pytest.approx(0.875 - 0.65625)
    # (the chain of two integrators above, whose rate is exchanged too, does not tell them apart)


@pytest.mark.parametrize("master", ["jacobi", "iterative", "adaptive"])
def test_a_feedthrough_output_is_read_after_its_inputs_are_set(master):
    """The contract (components/slave.py): outputs read after inputs were set reflect those
    inputs. Every master that exchanges the Jacobi way records g.y = 2·a.x at every point, also
    at the adaptive master's uneven steps; reading g.y before setting g.u would give 2·a.x of the
    step before."""
    result = feedthrough_chain(master)
    t = result.time
    assert result["a.x"] == pytest.approx(t, abs=1e-12)
    assert result["g.y"] == pytest.approx(2 * t, abs=1e-12)
    # and c stepped from that g.y: each step integrates 2·(the step's start)
    integral = np.concatenate([[0.0], np.cumsum(np.diff(t) * 2 * t[:-1])])
    assert result["c.x"] == pytest.approx(integral, abs=1e-12)


def test_the_adaptive_master_grows_its_steps_brackets_a_switch_and_rolls_back_exactly():
    models = {"a": Integrator(), "s": Switch(at=0.3)}
    sc = fake_scenario(models, ["a.x -> s.u", "a.x_dot -> s.u_dot"], 1.0, 0.01, "adaptive",
                       parameters={"a": {"u": 1.0, "u_dot": 0.0}})
    result = Master(sc, {}, make_instance=maker(models)).run()
    t, on = result.time, result["s.on"]
    assert result.coupling["steps"] < 25                   # 100 steps of 0.01 at a fixed step
    assert result.coupling["rejected_steps"] >= 1          # the step that crossed the switch
    first = int(np.argmax(on > 0.5))
    assert t[first - 1] < 0.3 <= t[first] and t[first] - t[first - 1] <= 0.01 / 16 + 1e-15
    # every rejected step was taken back: the integral of 1 is the time, to rounding
    assert result["a.x"] == pytest.approx(t, abs=1e-13)
    assert t[-1] == 1.0


@pytest.mark.parametrize("status, freed", [(Status.DISCARD, True), (Status.FATAL, False)])
def test_a_refused_step_names_the_instance_the_time_and_its_reason(status, freed):
    models = {"a": Integrator(gain=1.0, x0=1.0), "b": Failing(at=0.5, status=status)}
    made = {}
    sc = fake_scenario(models, ["a.x -> b.u", "a.x_dot -> b.u_dot", "b.x -> a.u",
                                "b.x_dot -> a.u_dot"], 1.0, 0.1)
    with pytest.raises(CosimError) as err:
        Master(sc, {}, make_instance=maker(models, made)).run()
    assert str(err.value) == "b failed during step from t = 0.5 to 0.6 s: the fabric tore"
    assert made["a"].calls[-1] == "free"
    # after Discard the instance is freed; after Fatal FMI allows no further call
    assert (made["b"].calls[-1] == "free") == freed


def test_record_every_keeps_every_nth_point_and_the_end():
    result, _ = oscillator("jacobi", stop=1.0, step=0.1, record_every=3)
    assert result.time == pytest.approx([0.0, 0.3, 0.6, 0.9, 1.0], abs=1e-15)
    full, _ = oscillator("jacobi", stop=1.0, step=0.1)
    assert np.array_equal(result["a.x"], full["a.x"][[0, 3, 6, 9, 10]])


def test_a_saved_point_is_come_back_to_exactly():
    models = {"a": Integrator(gain=1.0, x0=1.0), "b": Integrator(gain=-1.0)}
    with Master(fake_scenario(models, LOOP, 1.0, 0.1), {}, make_instance=maker(models)) as run:
        for _ in range(3):
            run.step()
        snapshot = run.save_state()
        saved = {i.name: (list(i.in_buf), list(i.out_buf), i.model.x) for i in run.instances}
        for _ in range(4):
            run.step()
        first = run.result()
        run.restore_state(snapshot)
        assert run.k == 3 and len(run.result().time) == 4
        # every FMU's state, the inputs the master had set and the outputs read, as saved
        assert {i.name: (list(i.in_buf), list(i.out_buf), i.model.x)
                for i in run.instances} == saved
        for _ in range(4):
            run.step()
        again = run.result()
    assert np.array_equal(first["a.x"], again["a.x"]) and np.array_equal(first.time, again.time)


def test_an_unconnected_input_or_an_unknown_output_is_refused_before_any_call():
    models = {"a": Integrator(), "b": Integrator()}
    made = {}
    sc = fake_scenario(models, ["a.x -> b.u"], 1.0, 0.1)
    with pytest.raises(ScenarioError, match=r"input a\.u is neither connected nor given"):
        Master(sc, {}, make_instance=maker(models, made)).run()
    assert made["a"].calls == [] and made["b"].calls == []
    sc = fake_scenario(models, ["a.y -> b.u"], 1.0, 0.1)
    with pytest.raises(ScenarioError, match=r"a \(Integrator\) has no output 'y'"):
        Master(sc, {}, make_instance=maker(models)).run()


def test_a_tolerance_the_master_cannot_honour_is_refused_in_one_line():
    with pytest.raises(ScenarioError, match=r"^fake\.toml: experiment\.tolerance = 1: the "
                                            r"adaptive master honours tolerances from 1e-08"):
        oscillator("adaptive", tolerance=1.0, tolerance_master="adaptive")


def test_every_master_has_its_settings_class_with_the_documented_defaults():
    assert set(ALGORITHMS) == set(SETTINGS)
    for name, algorithm in ALGORITHMS.items():
        assert algorithm.Settings is SETTINGS[name] and algorithm.name == name
    # the defaults docs/running.md gives, each within the range its master honours
    defaults = {name: dataclasses.asdict(cls()) for name, cls in SETTINGS.items()}
    assert defaults == {"jacobi": {}, "gauss-seidel": {},
                        "iterative": {"tolerance": 1e-6, "acceleration": "aitken"},
                        "adaptive": {"tolerance": 1e-5}}
    for cls in (IterativeSettings, AdaptiveSettings):
        low, high = cls.TOLERANCES
        assert low <= cls().tolerance <= high
        assert cls(tolerance=low).tolerance == low and cls(tolerance=high).tolerance == high
        for outside in (low / 2, high * 2):
            with pytest.raises(SettingError, match=rf"^experiment\.tolerance = {outside:g}: "
                                                   rf"the {cls.master} master honours"):
                cls(tolerance=outside)
    with pytest.raises(SettingError, match=r"^experiment\.acceleration = 'newton': one of"):
        IterativeSettings(acceleration="newton")
