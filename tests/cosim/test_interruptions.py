"""The interruption after the attack on the way out of any FMU, in this process: the first of
two signals decides and a second one is not raised over it; a run stuck in initialization is
under experiment.step_timeout; a hang in the coupling-error estimate's coarser run says so and
keeps the finished run's record; a user's own SIGINT handler is called between two steps; the
guardian's board names the instance and call a run is in. Fake instances (tests/fake_fmu.py);
records against the closed form x = u·t."""
import os
import signal
import threading
import time

import numpy as np
import pytest

from sewfmu.scenarios.cosim import guardian, interrupt, watchdog
from sewfmu.scenarios.cosim.fmi_calls import StepTimeout
from sewfmu.scenarios.cosim.master import Master
from tests.cosim.test_watchdog import Blocking, _closed_form, _run
from tests.fake_fmu import Integrator, fake_scenario, maker

H, U = 0.1, 2.0


def _spin():
    for _ in range(10000):        # a signal's handler runs between two bytecodes here
        pass


def test_the_first_of_two_signals_decides_and_the_second_is_not_raised_over_it():
    before = {s: signal.getsignal(s) for s in interrupt.SIGNALS}
    try:
        interrupt.interrupt_on_signals()
        with pytest.raises(interrupt.Interrupted) as caught:
            os.kill(os.getpid(), signal.SIGTERM)
            _spin()
        os.kill(os.getpid(), signal.SIGINT)      # while the first is answered (its record)
        _spin()
        assert caught.value.signum == signal.SIGTERM and caught.value.exit_status == 143
        assert interrupt.under_way == signal.SIGTERM
    finally:
        for s, handler in before.items():
            signal.signal(s, handler)
        interrupt._own = False
        interrupt.settled()
    assert interrupt.under_way is None and interrupt.pending == []


@pytest.mark.parametrize("apart, decides", [(0.0, signal.SIGTERM), (0.2, signal.SIGINT)])
def test_of_sigint_and_sigterm_at_the_same_instant_sigterm_decides(apart, decides):
    """Pending together, the kernel delivers SIGINT first whichever was sent first: within
    SAME_INSTANT SIGTERM decides; later, the first does."""
    before = {s: signal.getsignal(s) for s in interrupt.SIGNALS}
    try:
        interrupt.interrupt_on_signals()
        with pytest.raises(interrupt.Interrupted) as caught:
            os.kill(os.getpid(), signal.SIGINT)
            _spin()
        time.sleep(apart)
        os.kill(os.getpid(), signal.SIGTERM)
        _spin()
        assert caught.value.signum == decides
        assert caught.value.reason == f"interrupted ({signal.Signals(decides).name})"
    finally:
        for s, handler in before.items():
            signal.signal(s, handler)
        interrupt._own = False
        interrupt.settled()


class SlowInit(Integrator):
    """exitInitializationMode (the fake's pull of its inputs at initialization) blocks."""

    def __init__(self):
        super().__init__()
        self.release = threading.Event()

    def set_parameter(self, name, value):
        super().set_parameter(name, value)
        if name == "u":
            self.release.wait(30)


def test_step_timeout_covers_initialization(hook):
    model = SlowInit()
    hook.models.append(model)
    started = time.monotonic()
    _run(model, step_timeout=0.2).run()
    (err, at), = hook.handed
    assert isinstance(err, StepTimeout)
    assert str(err) == "a took longer than experiment.step_timeout = 0.2 s in set a parameter " \
                       "at t = 0 s"
    assert 0.2 <= at - started < 0.2 + 0.8


def test_a_hang_in_the_estimates_coarser_run_says_so_and_keeps_the_finished_record(hook):
    finished = _run(Integrator(), stop=0.5).run()
    model = Blocking(at=0.2)
    hook.models.append(model)
    kept = []
    with watchdog.keeping(lambda result, reason: kept.append(result) or "kept"), \
            watchdog.keeping_instead(finished, "while estimating the coupling error, after "
                                               "the run"):
        _run(model, step_timeout=0.25).run()
    (err, _), = hook.handed
    assert str(err) == ("a took longer than experiment.step_timeout = 0.25 s in doStep at "
                        "t = 0.2 s of the coarser run that estimates the coupling error, after "
                        "the run; kept")
    assert kept == [finished]
    _closed_form(finished, 6)


@pytest.mark.slow
def test_a_users_own_sigint_handler_is_called_between_two_steps_and_the_run_goes_on():
    heard = []
    before = signal.signal(signal.SIGINT, lambda signum, frame: heard.append(signum))
    try:
        model = Blocking(at=10.0, delay=0.01)
        threading.Timer(0.2, os.kill, (os.getpid(), signal.SIGINT)).start()
        result = _run(model, stop=5.0).run()        # 50 steps of 10 ms: the signal lands within
    finally:
        signal.signal(signal.SIGINT, before)
    assert heard == [signal.SIGINT]
    _closed_form(result, 51)


def test_a_users_handler_that_raises_stops_the_run_cleanly():
    def stop(signum, frame):
        raise SystemExit(7)

    before = signal.signal(signal.SIGINT, stop)
    made = {}
    try:
        model = Blocking(at=10.0, delay=0.01)
        threading.Timer(0.2, os.kill, (os.getpid(), signal.SIGINT)).start()
        scenario = fake_scenario({"a": model}, [], 5.0, H,
                                 parameters={"a": {"u": U, "u_dot": 0.0}})
        with pytest.raises(SystemExit):
            Master(scenario, {}, make_instance=maker({"a": model}, made)).run()
    finally:
        signal.signal(signal.SIGINT, before)
    assert not made["a"].instantiated               # freed before the exit went on


def test_the_board_names_the_instance_and_call_the_run_is_in():
    board = guardian.Board()
    board.names(["shaft", "motor"])
    board.q[guardian.WHERE] = 1 * 32 + guardian.CODE["exitInitializationMode"]
    board.d[guardian.T] = 0.0125
    assert board.where() == ("motor", "exitInitializationMode")
    line = guardian._line(board, signal.SIGTERM, None, True)
    assert line.startswith("sewfmu: interrupted (SIGTERM) while motor was in "
                           "exitInitializationMode at t = 0.0125 s; ")
    board.q[guardian.WHERE] = -1
    assert board.where() == (None, None)


def test_a_watched_run_writes_its_beat_time_and_calls_on_the_board():
    models = {"a": Integrator()}
    scenario = fake_scenario(models, [], 1.0, H, parameters={"a": {"u": U, "u_dot": 0.0}})
    master = Master(scenario, {}, make_instance=maker(models))
    before = watchdog.board().q[guardian.BEAT]
    result = master.run()
    paper = watchdog.board()
    assert paper.q[guardian.STATE] == guardian.IDLE
    assert paper.d[guardian.T] == pytest.approx(1.0 - H)       # the last step's start
    assert paper.q[guardian.BEAT] - before == 10 + 1     # 10 steps and the instantiation
    assert paper.where()[0] == "a"
    np.testing.assert_allclose(result["a.x"], U * result.time, rtol=1e-12, atol=1e-12)
