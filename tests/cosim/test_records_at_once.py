"""A step's outputs recorded at once (cosim/recorder.py: one copy from the array the instances
read their Real outputs into, one per instance with Boolean outputs) or, for a narrowed record,
value by value, against the closed form of what Jacobi computes on the fake oscillator
(tests/cosim/test_master_loop.py's system): every column, a narrowed and reordered record with an
output read for a connection but not recorded, FMI 2.0's and FMI 3.0's Boolean types, the memory
a narrowed record takes, and the run taken in stretches of any length (Master.steps)."""
import ctypes

import numpy as np
import pytest

from sewfmu.scenarios.cosim import recorder
from sewfmu.scenarios.cosim.master import Master
from sewfmu.scenarios.format.values import ScenarioError
from tests.fake_fmu import Integrator, Switch, fake_scenario, maker

M = np.array([[0.0, 1.0], [-1.0, 0.0]])
CONNECTIONS = ["b.x -> a.u", "b.x_dot -> a.u_dot", "a.x -> b.u", "a.x_dot -> b.u_dot",
               "a.x -> s.u", "a.x_dot -> s.u_dot"]
STOP, STEP = 7.0, 0.1


def _system(record, boolean=None, master="jacobi"):
    models = {"a": Integrator(gain=1.0, x0=1.0), "b": Integrator(gain=-1.0),
              "s": Switch(at=0.0)}
    made = {}
    make = maker(models, made)

    def make_with(declaration, log):
        inst = make(declaration, log)
        if boolean is not None:
            inst.BOOLEAN = boolean
        return inst

    sc = fake_scenario(models, CONNECTIONS, STOP, STEP, master)
    sc.record = record
    return Master(sc, {}, make_instance=make_with), made


def _taylor(n: int) -> np.ndarray:
    """z_k = (I + hM + h²M²/2)^k z_0: Jacobi's exact result on the oscillator, k = 0..n."""
    step = np.eye(2) + STEP * M + STEP ** 2 * M @ M / 2
    z = [np.array([1.0, 0.0])]
    for _ in range(n):
        z.append(step @ z[-1])
    return np.array(z)


@pytest.mark.parametrize("boolean", [ctypes.c_int, ctypes.c_bool], ids=["fmi2", "fmi3"])
@pytest.mark.parametrize("record", [None, ["s.on", "b.x", "s.y", "a.x"]],
                         ids=["every output, at once", "narrowed, value by value"])
def test_each_column_holds_its_own_values(boolean, record):
    # narrowed: b.x_dot feeds a.u_dot but is not recorded, and the Boolean comes first
    master, _ = _system(record, boolean)
    result = master.run()
    assert master.recorder.at_once == (record is None)
    if record:
        assert list(result.columns) == record
    z = _taylor(len(result.time) - 1)
    np.testing.assert_allclose(result["a.x"], z[:, 0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(result["b.x"], z[:, 1], rtol=0, atol=1e-12)
    if record is None:                            # the rates: x_dot = gain · u
        np.testing.assert_array_equal(result["a.x_dot"], result["b.x"])
        np.testing.assert_array_equal(result["b.x_dot"], -result["a.x"])
    # the switch passes on where a.x will be at the end of its step, and is on from 0 up
    on = result["s.on"]
    assert set(np.unique(on)) == {0.0, 1.0} and on.dtype == float
    np.testing.assert_array_equal(on, (result["s.y"] >= 0.0).astype(float))
    assert np.count_nonzero(np.diff(on)) >= 2                     # the oscillation crosses 0


def test_a_narrowed_record_takes_the_memory_of_its_own_columns(monkeypatch):
    # 71 rows: every output (6 columns and time) 3,976 bytes, a.x alone 1,136
    monkeypatch.setattr(recorder, "RECORD_BUDGET", 2000)
    master, _ = _system(["a.x"])
    result = master.run()
    np.testing.assert_allclose(result["a.x"], _taylor(70)[:, 0], rtol=0, atol=1e-12)
    master, _ = _system(None)
    with pytest.raises(ScenarioError, match=r"71 points × 7 columns"):
        master.run()


@pytest.mark.parametrize("stretch", [1, 3, 7, 1000])
def test_the_run_taken_in_stretches_records_what_one_run_records(stretch):
    whole, _ = _system(None)
    expected = whole.run()
    master, _ = _system(None)
    with master:
        while not master.finished():
            master.steps(stretch)
        master.steps(5)                    # past the end: no step is taken
        got = master.result()
    np.testing.assert_array_equal(got.time, expected.time)
    assert list(got.columns) == list(expected.columns)
    for column, values in expected.columns.items():
        np.testing.assert_array_equal(got[column], values, err_msg=column)


def test_records_are_copies_the_next_step_does_not_change():
    master, _ = _system(["a.x"])
    with master:
        master.steps(10)
        first = master.result()["a.x"].copy()
        master.steps(10)
        again = master.result()["a.x"]
    np.testing.assert_array_equal(again[:len(first)], first)
    assert len(again) == len(first) + 10
