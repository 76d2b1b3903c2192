"""sewfmu.check refuses a run the master would refuse at its start (cosim/master.planned_steps):
more than 10^8 FMU steps (communication steps × instances), a step longer than the run. Before,
check passed experiment.revolutions = 1e9 and experiment.step = 1e-12, and the page started a
run's process that stopped with "more than the 1e+08 a run may take". The boundary is computed
here from the scenario's own numbers, not from the code: punch_drive turns at omega0 = 100 rad/s
(a constant speed: a revolution takes 2π/100 s), steps 2.5e-4 s, and has 3 instances."""
import math

import pytest

import sewfmu

OMEGA, STEP, INSTANCES, MOST = 100.0, 2.5e-4, 3, 1e8


def _work(revolutions: float, step: float = STEP) -> float:
    return math.ceil(2 * math.pi * revolutions / OMEGA / step * (1 - 1e-12)) * INSTANCES


def test_the_scenario_is_what_the_boundary_assumes():
    scenario = sewfmu.load("punch_drive")
    assert scenario.step == STEP and len(scenario.instances) == INSTANCES
    assert scenario.instances["shaft"].parameters["omega0"] == OMEGA


def test_a_run_just_under_the_most_work_passes_and_just_over_is_refused():
    under = math.floor(MOST / INSTANCES * OMEGA * STEP / (2 * math.pi))    # revolutions
    assert _work(under) <= MOST < _work(under + 1)
    sewfmu.check("punch_drive", set={"experiment.revolutions": under})
    with pytest.raises(sewfmu.ScenarioError, match="may take") as refused:
        sewfmu.check("punch_drive", set={"experiment.revolutions": under + 1})
    assert f"{_work(under + 1) / INSTANCES:.3g} communication steps" in str(refused.value)


@pytest.mark.parametrize("values, says", [
    ({"experiment.revolutions": 1e9}, "may take"), ({"experiment.step": 1e-12}, "may take"),
    ({"experiment.step": 5e-324}, "1e18 steps"), ({"experiment.step": 1.0}, "longer than the run"),
    ({"experiment.revolutions": 1e9, "experiment.step": 1e-3}, "may take")])
def test_a_run_too_large_to_run_is_refused_by_check_in_one_line(values, says):
    with pytest.raises(sewfmu.ScenarioError, match=says) as refused:
        sewfmu.check("punch_drive", set=values)
    assert "\n" not in str(refused.value)
