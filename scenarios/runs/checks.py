"""What a run checks before its first step, without running: every value the scenario gives
against its FMU's declared type and range (cosim/system.check_parameters, from the
modelDescriptions of the FMU files, built first if out of date); for sewfmu's own FMUs also the
sign and range each parameter is checked against when the FMU initializes (a stiffness of 0 is
within the declared [0, 1e9] and still refused there); and the run's steps and their number,
as the master refuses them (cosim/master.planned_steps).
`sewfmu.check` and a sweep's check of every point before the first one runs."""
from __future__ import annotations

from pathlib import Path

from sewfmu.components.parameters import ParameterError, check_value, parameter_info
from sewfmu.components.registry import FMUS
from sewfmu.scenarios.cosim.instances import extracted_fmu
from sewfmu.scenarios.cosim.master import planned_steps
from sewfmu.scenarios.cosim.system import check_parameters
from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
from sewfmu.scenarios.format.parameter_table import slave_class
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import ScenarioError


def check_values(scenario: Scenario, paths: dict | None = None) -> None:
    """Raise ScenarioError naming the first value a run of `scenario` would refuse; `paths`:
    FMU name -> file, when the caller has them."""
    paths = paths or fmus_for(scenario)
    check_parameters(scenario, {inst.name: extracted_fmu(Path(paths[inst.fmu]))[1]
                                for inst in scenario.instances.values()})
    for inst in scenario.instances.values():
        if inst.fmu not in FMUS or inst.fmu in scenario.fmu_files:
            continue
        cls = slave_class(inst.fmu)
        infos = {i.name: i for i in parameter_info(cls.params_class)} if cls.params_class else {}
        for key, value in inst.parameters.items():
            if key in infos:
                try:
                    check_value(infos[key], value)
                except ParameterError as err:     # worded as the FMU's initialization says it
                    target = f"{inst.name}.{key}"     # named where it was given
                    raise ScenarioError(f"{scenario.origin_of(target)} {target}: {inst.name} "
                                        f"({inst.fmu}) refuses it: {err}") from None
    if scenario.study is None:
        planned_steps(scenario)         # the run's size: a step of 1e-12 s is refused here too
