"""The compiled Jacobi loop (scenarios/cosim/stepper.py, jacobi_loop.c) against the Python loop
it stands in for: on native FMUs the same records bit for bit (FMI 2.0 and 3.0), the same one
line where a step fails (a refused input, a discarded doStep), Ctrl-C answered between two
chunks with the Python loop's record so far; and the runs it must leave to the Python loop (Python
FMUs, other masters, feedback loops, experiment.step_timeout) left there."""
import signal
import threading
import time

import numpy as np
import pytest

import sewfmu
from sewfmu.scenarios.cosim import interrupt, stepper
from sewfmu.scenarios.cosim.interrupt import Interrupted
from sewfmu.scenarios.cosim.master import Master

pytestmark = pytest.mark.slow          # each needs the native FMUs built (tests/conftest.py)

SCENARIOS = ["punch_drive", "carriage_startstop", "feed", "takeup"]
# the linkage's angular acceleration input leaves its declared range in the shaft's ramp: the
# native linkage refuses it as it is set (tests/cosim/test_native_runs.py)
REFUSED_INPUT = {"shaft.omega0": 2000.0, "shaft.ramp_time": 2e-4, "experiment.stop_time": 1e-3,
                 "experiment.step": 1e-5}
# a punch so stiff that a step needs more switch-search intervals than it may take: Discard
DISCARDED_STEP = {"experiment.step": 1e-3, "punch.c3": 1e9, "punch.m": 1e-4}


@pytest.fixture(autouse=True)
def _builder():
    pytest.importorskip("sewfmu.scenarios.fmu_build.native")
    if stepper.library() is None:
        pytest.skip("no C compiler for the compiled loop")


@pytest.fixture
def chunks(monkeypatch):
    """The chunks the compiled loop ran (a list that grows as it runs them)."""
    ran = []
    steps = stepper.CompiledLoop.steps

    def counted(self, k, end, paper):
        ran.append((k, end))
        return steps(self, k, end, paper)

    monkeypatch.setattr(stepper.CompiledLoop, "steps", counted)
    return ran


def _master(name: str, fmu_dir, fmi: int = 2, record=None, **settings) -> Master:
    from sewfmu.scenarios.fmu_build.up_to_date import fmus_for  # the builder, for its FMUs

    sc = sewfmu.load(name, set={"experiment.fmus": "native", "experiment.fmi": fmi, **settings})
    if record is not None:
        sc.record = record
    return Master(sc, fmus_for(sc, fmu_dir))


def _both(monkeypatch, chunks, make):
    """(run of the compiled loop, run of the Python loop) of the Master `make()` gives: each the
    Master, its result (or None) and its error's text (or None)."""
    runs = []
    for compiled in (True, False):
        monkeypatch.setattr(stepper, "enabled", compiled)
        before = len(chunks)
        master, result, error = make(), None, None
        try:
            result = master.run()
        except sewfmu.Error as err:
            error = str(err)
        assert (len(chunks) > before) == compiled, "the compiled loop ran" if compiled else \
            "the Python loop ran"
        runs.append((master, result, error))
    return runs


def _same_records(a, b) -> None:
    ta, ca = a.recorder.arrays()
    tb, cb = b.recorder.arrays()
    assert len(ta) >= 1 and np.array_equal(ta, tb)
    assert list(ca) == list(cb)
    for column in ca:
        assert np.array_equal(ca[column], cb[column]), column


# FMI 3.0 on punch_drive alone: the loop's FMI 3.0 calls, to keep CI within its time
@pytest.mark.parametrize("scenario, fmi", [(s, 2) for s in SCENARIOS] + [("punch_drive", 3)])
def test_the_compiled_loop_records_the_python_loops_numbers(scenario, fmi, fmu_dir, fmu3_dir,
                                                            monkeypatch, chunks):
    (compiled, result, error), (python, expected, _) = _both(
        monkeypatch, chunks, lambda: _master(scenario, fmu_dir, fmi))
    assert error is None
    _same_records(compiled, python)
    assert compiled.k == python.k == python.n_steps and compiled.t == python.t
    assert result.log == expected.log


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("case", [REFUSED_INPUT, DISCARDED_STEP], ids=["input", "doStep"])
def test_a_failed_step_is_the_python_loops_one_line(case, fmi, fmu_dir, fmu3_dir, monkeypatch,
                                                    chunks):
    (compiled, _, said), (python, _, expected) = _both(
        monkeypatch, chunks, lambda: _master("punch_drive", fmu_dir, fmi, **case))
    assert expected is not None and "\n" not in expected
    assert said == expected
    assert compiled.k == python.k and compiled._failed_at == python._failed_at
    _same_records(compiled, python)
    # the instance that failed is marked as the Python loop marks it (freed, not Fatal)
    assert [i.failed for i in compiled.instances] == [i.failed for i in python.instances]


def test_a_signal_is_answered_between_two_chunks(fmu_dir, monkeypatch, chunks):
    """Ctrl-C during a chunk stops the run when the chunk ends, with the record so far: the
    Python loop's rows up to that step."""
    monkeypatch.setattr(stepper, "CHUNK", 50)
    steps = stepper.CompiledLoop.steps         # the counting one

    def signalled(self, k, end, paper):
        done = steps(self, k, end, paper)
        if len(chunks) == 3:
            interrupt.pending.append(signal.SIGINT)     # as Python's handler marks it
        return done

    monkeypatch.setattr(stepper.CompiledLoop, "steps", signalled)
    master = _master("punch_drive", fmu_dir)
    with pytest.raises(Interrupted) as err:
        master.run()
    assert master.k == 150 and len(chunks) == 3
    assert err.value.where == f"at t = {150 * master.h:g} s"
    kept = err.value.result
    monkeypatch.setattr(stepper, "enabled", False)
    whole = _master("punch_drive", fmu_dir).run()
    rows = len(kept.time)
    assert rows == 151 and np.array_equal(kept.time, whole.time[:rows])
    for column, values in kept.columns.items():
        assert np.array_equal(values, whole.columns[column][:rows]), column


@pytest.mark.parametrize("why, name, settings", [
    ("Python FMUs", "punch_drive", {"experiment.fmus": "python"}),
    ("another master", "punch_drive", {"experiment.master": "gauss-seidel"}),
    ("a step timeout", "punch_drive", {"experiment.step_timeout": 60}),
    ("a feedback loop", "punch_split", {"experiment.master": "jacobi"}),
    ("some outputs recorded", "punch_drive", {"record": ["punch.y", "shaft.phi"]}),
])
def test_what_the_compiled_loop_cannot_do_stays_with_the_python_loop(why, name, settings,
                                                                     fmu_dir, chunks):
    master = _master(name, fmu_dir, **{"experiment.revolutions": 1, **settings})
    master.run()
    assert chunks == [], why
    assert len(master.recorder.arrays()[0]) > 1


def test_closing_from_another_thread_stops_the_compiled_loop_between_two_chunks(fmu_dir,
                                                                                 chunks):
    """close() waits for the chunk under way (the instances it frees are the chunk's), and the
    stepping thread stops at the next one, as the Python loop stops at its next step."""
    master = _master("punch_drive", fmu_dir, **{"experiment.revolutions": 2000})
    master.__enter__()
    told = []

    def stepping():
        try:
            master.steps(10**9)
        except sewfmu.Error as err:
            told.append(str(err))

    thread = threading.Thread(target=stepping)
    thread.start()
    while not chunks and thread.is_alive():
        time.sleep(0.001)
    time.sleep(0.02)
    master.close()
    thread.join()
    assert told and "the run is not open" in told[0], told
    assert 0 < master.k < master.n_steps and master.k % stepper.CHUNK == 0
    assert chunks and chunks[-1][1] == master.k      # it stopped where a chunk ended
