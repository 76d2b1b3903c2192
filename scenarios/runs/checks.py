"""What a run checks before its first step, without running: every value the scenario gives
against its FMU's declared type and range (cosim/system.check_parameters), from the
modelDescriptions of the FMU files (built first if out of date). `sewfmu.check` and a sweep's
check of every point before the first one runs."""
from __future__ import annotations

from pathlib import Path

from sewfmu.scenarios.cosim.instances import extracted_fmu
from sewfmu.scenarios.cosim.system import check_parameters
from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
from sewfmu.scenarios.format.scenario import Scenario


def check_values(scenario: Scenario, paths: dict | None = None) -> None:
    """Raise ScenarioError naming the first value a run of `scenario` would refuse; `paths`:
    FMU name -> file, when the caller has them."""
    paths = paths or fmus_for(scenario)
    check_parameters(scenario, {inst.name: extracted_fmu(Path(paths[inst.fmu]))[1]
                                for inst in scenario.instances.values()})
