"""Run.revolution(k): one whole turn of the shaft against the crank angle, with no wrap-around (a
plot against it draws no line from 355° back to 0°), matching the shaft's own angle."""
import numpy as np
import pytest

import sewfmu


@pytest.fixture(scope="module")
def three_turns(fmu_dir):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("SEWFMU_FMU_DIR", str(fmu_dir))
        return sewfmu.run("punch_drive", set={"experiment.revolutions": 3})


@pytest.mark.parametrize("k, n", [(0, 0), (1, 1), (-1, 2), (2, 2), (-3, 0)])
def test_a_revolution_is_the_shafts_turn_against_an_increasing_crank_angle(three_turns, k, n):
    turn = three_turns.revolution(k)
    deg = turn["crank_deg"]
    assert len(turn) > 100 and np.all(np.diff(deg) > 0)
    assert deg[0] >= 0.0 and deg[-1] < 360.0
    assert deg[0] < 1.5 and deg[-1] > 358.5        # the whole turn: steps of 1.43° at 100 rad/s
    np.testing.assert_allclose(np.radians(deg) + 2 * np.pi * n, turn["shaft.phi"], atol=1e-9)
    # the recorded columns, as the series holds them at those times
    rows = np.isin(three_turns.series["time"], turn["time"])
    np.testing.assert_array_equal(turn["punch.F2"], three_turns.series["punch.F2"][rows])
    assert set(three_turns.series.dtype.names) < set(turn.dtype.names)


def test_the_last_revolution_is_the_one_without_the_end_of_the_run(three_turns):
    last = three_turns.revolution()
    assert last["time"][-1] < three_turns.series["time"][-1]
    np.testing.assert_array_equal(last, three_turns.revolution(-1))


def test_a_revolution_the_run_does_not_hold_is_refused(three_turns):
    with pytest.raises(sewfmu.ScenarioError, match="holds 3 whole revolutions"):
        three_turns.revolution(3)
