"""The way out of an FMU call that never returns (scenarios/cosim/watchdog.py), in this process:
fake instances (tests/fake_fmu.py) whose doStep blocks on an Event stand for an FMU that does not
return, a real signal is sent to this process, and the watchdog's hook (what the command line
and a sweep's worker give it to end their process) records what it was handed instead of ending
pytest. The records are checked against the closed form x = u·t of a fake integrator."""
import os
import signal
import sys
import threading
import time

import numpy as np
import pytest

from sewfmu.scenarios.cosim import interrupt, watchdog
from sewfmu.scenarios.cosim.fmi_calls import StepTimeout
from sewfmu.scenarios.cosim.master import Master
from sewfmu.scenarios.format.values import ScenarioError
from tests.fake_fmu import Gain, Integrator, fake_scenario, maker

H = 0.1           # s, the communication step of every run here
U = 2.0           # the integrator's input: x = U·t exactly


class Blocking(Integrator):
    """An integrator whose doStep from t >= at waits for `release` (a call that does not return
    until the test says so); `took` the time it waited."""

    def __init__(self, at: float, delay: float = 0.0):
        super().__init__()
        self.at, self.delay = at, delay
        self.release, self.blocked = threading.Event(), threading.Event()

    def step(self, t, h):
        if t >= self.at - 1e-12 and not self.release.is_set():
            self.blocked.set()
            self.release.wait(30)          # the test's guard: never longer
        time.sleep(self.delay)
        return super().step(t, h)


def _run(model, stop=1.0, **experiment):
    models = {"a": model}
    scenario = fake_scenario(models, [], stop, H, parameters={"a": {"u": U, "u_dot": 0.0}},
                             **experiment)
    return Master(scenario, {}, make_instance=maker(models))


def _signal_when(model, sig=signal.SIGINT):
    """Send `sig` to this process once the model's doStep blocks; when it was sent."""
    sent = []

    def send():
        model.blocked.wait(10)
        sent.append(time.monotonic())
        os.kill(os.getpid(), sig)
    threading.Thread(target=send, daemon=True).start()
    return sent


def _closed_form(result, rows: int):
    assert len(result.time) == rows
    np.testing.assert_allclose(result.time, H * np.arange(rows), rtol=0, atol=1e-12)
    np.testing.assert_allclose(result["a.x"], U * result.time, rtol=1e-12, atol=1e-12)


def test_a_signal_to_a_run_stuck_in_do_step_ends_it_after_the_grace(hook):
    model = Blocking(at=0.3)
    hook.models.append(model)
    kept = []
    sent = _signal_when(model)
    with watchdog.keeping(lambda result, reason: kept.append((result, reason)) or "kept here"):
        with pytest.raises(interrupt.Interrupted):
            _run(model).run()
    assert len(hook.handed) == 1
    err, at = hook.handed[0]
    assert isinstance(err, interrupt.Interrupted) and err.exit_status == 130
    assert err.reason == "interrupted (SIGINT) while a was in doStep at t = 0.3 s"
    assert err.kept == "kept here"
    assert watchdog.GRACE <= at - sent[0] < watchdog.GRACE + 0.5
    (result, reason), = kept
    assert reason == err.reason
    _closed_form(result, 4)                 # t = 0, 0.1, 0.2, 0.3: the steps completed


def test_a_signal_the_main_thread_answers_in_time_is_no_business_of_the_watchdog(hook):
    model = Blocking(at=10.0, delay=0.05)   # slow steps, none stuck
    # SIGTERM as the command line has it (left at its default, it would end pytest: as it must)
    before = signal.signal(signal.SIGTERM, interrupt._interrupt)
    threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGTERM)).start()
    try:
        with pytest.raises(interrupt.Interrupted) as caught:
            _run(model, stop=100.0).run()
    finally:
        signal.signal(signal.SIGTERM, before)
        interrupt.pending.clear()
    assert hook.handed == []
    err = caught.value
    assert err.exit_status == 143
    assert err.where.startswith("at t = ") and err.result is not None
    rows = len(err.result.time)
    assert 2 <= rows < 50
    assert err.where == f"at t = {H * (rows - 1):g} s"
    _closed_form(err.result, rows)


def test_a_step_beyond_step_timeout_is_refused_naming_instance_call_time_and_limit(hook):
    model = Blocking(at=0.5)
    hook.models.append(model)
    started = time.monotonic()
    result = _run(model, step_timeout=0.25).run()   # the hook releases it: the run goes on
    (err, at), = hook.handed
    assert isinstance(err, StepTimeout)
    assert str(err) == "a took longer than experiment.step_timeout = 0.25 s in doStep at t = 0.5 s"
    assert 0.25 <= at - started < 0.25 + 0.6
    _closed_form(result, 11)


@pytest.mark.parametrize("call, named", [("_set_reals", "set inputs"),
                                         ("_get_reals", "get outputs")])
def test_the_call_a_run_is_in_is_named_from_the_main_threads_stack(call, named):
    """Instance.exchange makes two calls: the one under way is read from its source line."""
    made = {}
    models = {"a": Integrator(), "g": Gain(3.0)}
    sc = fake_scenario(models, ["a.x -> g.u"], 1.0, H,
                       parameters={"a": {"u": U, "u_dot": 0.0}})
    seen = []
    with Master(sc, {}, make_instance=maker(models, made)):
        g = made["g"]
        original = getattr(g, call)

        def in_the_call():             # what the watchdog would see, were it stuck here
            seen.append(watchdog.stuck_call())
            return original()
        setattr(g, call, in_the_call)
        g.exchange()
    assert seen == [("g", named)]
    assert watchdog.stuck_call() == (None, None)          # here: in no FMU call


@pytest.mark.slow
def test_a_process_not_sewfmus_own_is_told_where_the_run_is_stuck_and_not_ended(capfd):
    watchdog.end_process_with(None)         # the API in a user's script: no hook
    model = Blocking(at=0.2)
    _signal_when(model)
    threading.Timer(watchdog.GRACE + 1.0, model.release.set).start()
    with pytest.raises(interrupt.Interrupted):
        _run(model).run()
    err = capfd.readouterr().err.strip().splitlines()
    assert err == ["sewfmu: interrupted (SIGINT) while a was in doStep at t = 0.2 s: the call "
                   "does not return, and sewfmu ends only its own processes; another SIGINT "
                   "ends this one"]


def test_an_ignored_signal_stays_ignored_within_a_run():
    """A sweep's worker ignores Ctrl-C (its main process decides): a run must not take it up."""
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with interrupt.deferred():
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
            assert signal.getsignal(signal.SIGTERM) is interrupt._mark
    finally:
        signal.signal(signal.SIGINT, before)


@pytest.mark.parametrize("value, expected", [(2, 2.0), ("500 ms", 0.5), ("2 min", 120.0),
                                             ("off", None)])
def test_step_timeout_takes_seconds_with_a_unit_or_off(value, expected):
    sc = fake_scenario({}, [], 1.0, H)
    sc.set_value("experiment.step_timeout", value)
    assert sc.step_timeout == expected


@pytest.mark.parametrize("value", [0, -1, float("inf"), float("nan"), True, "2 kg", "soon"])
def test_step_timeout_refuses_what_is_not_a_positive_finite_time(value):
    sc = fake_scenario({}, [], 1.0, H)
    with pytest.raises(ScenarioError, match="experiment.step_timeout"):
        sc.set_value("experiment.step_timeout", value)


def test_step_timeout_changes_no_sweep_point_identity():
    """It only stops a run: the points of a sweep resumed with another limit are the same."""
    from sewfmu.scenarios.format.experiment import experiment_of

    sc = fake_scenario({}, [], 1.0, H)
    before = experiment_of(sc)
    sc.set_value("experiment.step_timeout", 5)
    assert experiment_of(sc) == before and "step_timeout" not in before


def test_an_interruption_python_drops_is_raised_again_by_the_next_run(capsys):
    """Ctrl-C landing in a weakref callback (importlib has them) is printed as "Exception
    ignored" and lost: the run started next would reach an FMU that never returns with no
    interruption to answer. The command line's handlers note it first; the run raises it."""
    import weakref

    before = {s: signal.getsignal(s) for s in interrupt.SIGNALS}
    hook = sys.unraisablehook
    try:
        interrupt.interrupt_on_signals()

        class Thing:
            pass

        def callback(_):
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):        # the handler runs here, between two bytecodes
                pass

        thing = Thing()
        ref = weakref.ref(thing, callback)
        del thing                     # the callback runs, the KeyboardInterrupt is dropped
        assert ref() is None and interrupt.pending == [signal.SIGINT]
        model = Blocking(at=10.0)
        with pytest.raises(interrupt.Interrupted) as caught:
            _run(model).run()
        assert caught.value.where == "while loading the FMUs"
        assert not model.blocked.is_set() and interrupt.pending == []
        assert "Exception ignored" not in capsys.readouterr().err
    finally:
        for s, handler in before.items():
            signal.signal(s, handler)
        sys.unraisablehook = hook
        interrupt.pending.clear()
