"""A Scenario built or changed in Python (`Scenario(...)`, `Instance(...)`, `sc.step = ...`),
checked as a scenario file is when it is read, before it runs: what a file cannot hold (an
Instance whose fmu is None, a string among the connections, a step of None, an instance named
"/tmp/x") would otherwise surface as Python's AttributeError or KeyError deep inside a run, or
as a name that becomes a path. Each refusal is one ScenarioError line naming the field."""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from sewfmu.components.registry import FMI_VERSIONS, FMUS
from sewfmu.scenarios.format.experiment import FMU_KINDS
from sewfmu.scenarios.format.fmu_file import is_fmu_file
from sewfmu.scenarios.format.master_settings import MASTER_NAMES
from sewfmu.scenarios.format.parse import check_compare, check_one_source, check_record, check_sweep
from sewfmu.scenarios.format.scenario import Connection, Instance, Scenario
from sewfmu.scenarios.format.values import (
    ScenarioError,
    check_instance_name,
    check_scenario_name,
    exact,
    positive,
    positive_in,
    short,
)


def checked_copy(scenario: Scenario) -> Scenario:
    """A copy of `scenario`, every field checked, a time given with its unit ("0.25 ms") made
    seconds; the scenario given is never changed."""
    check_scenario_name(scenario.name)
    if not isinstance(scenario.source, str):
        raise ScenarioError(f"{scenario.name}: Scenario.source is the text naming where it "
                            f"came from, got {short(scenario.source)}")
    try:
        sc = scenario.copy()
    except Exception as err:            # noqa: BLE001 - a user's object that cannot be copied
        raise ScenarioError(f"{scenario.name}: copying it raised {type(err).__name__}: "
                            f"{' '.join(str(err).split())[:200]}") from None
    where = f"{sc.name}: Scenario"
    _check_instances(sc, where)
    _check_connections(sc, where)
    check_record(sc.record, where)
    _check_experiment(sc, where)
    if sc.compare is not None:
        check_compare(sc, where)
    if sc.sweep is not None:
        check_sweep(sc.sweep, where)
    return sc


def _check_instances(sc: Scenario, where: str) -> None:
    if not isinstance(sc.instances, Mapping) or not sc.instances:
        raise ScenarioError(f"{where}.instances: expected a dict of name -> Instance, got "
                            f"{short(sc.instances)}")
    for name, inst in sc.instances.items():
        try:
            check_instance_name(name)
        except ValueError as err:
            raise ScenarioError(f"{where}.instances: {err}") from None
        if not isinstance(inst, Instance):
            raise ScenarioError(f"{where}.instances[{name!r}]: expected an Instance(name, fmu, "
                                f"parameters), got {short(inst)}")
        if inst.name != name:
            raise ScenarioError(f"{where}.instances[{name!r}]: the Instance is named "
                                f"{short(inst.name)}; an instance is filed under its own name")
        if not isinstance(inst.fmu, str) or (inst.fmu not in FMUS and not is_fmu_file(inst.fmu)
                                             and inst.fmu not in sc.fmu_files):
            raise ScenarioError(f"{where}: instance {name}: fmu must name one of sewfmu's FMUs "
                                f"({', '.join(FMUS)}), an .fmu file or a type in "
                                f"Scenario.fmu_files, got {short(inst.fmu)}")
        if not isinstance(inst.parameters, dict) or \
                not all(isinstance(k, str) for k in inst.parameters):
            raise ScenarioError(f"{where}: instance {name}: parameters must be a dict of "
                                f"'parameter': value, got {short(inst.parameters)}")
        for key, value in list(inst.parameters.items()):
            try:
                value = exact(value)        # a float subclass's own methods never run later
            except Exception as err:        # noqa: BLE001 - a user's object that fails
                raise ScenarioError(f"{where}: {name}.{key}: reading it raised "
                                    f"{type(err).__name__}") from None
            if not isinstance(value, (bool, int, float, str)):
                raise ScenarioError(f"{where}: {name}.{key}: a value is a number, true or "
                                    f"false, or a text with its unit, got {short(value)}")
            inst.parameters[key] = value


def _check_connections(sc: Scenario, where: str) -> None:
    if not isinstance(sc.connections, list):
        raise ScenarioError(f"{where}.connections: expected a list of Connection(src, src_var, "
                            f"dst, dst_var), got {short(sc.connections)}")
    for con in sc.connections:
        if not isinstance(con, Connection):
            raise ScenarioError(f"{where}.connections: expected Connection(src, src_var, dst, "
                                f"dst_var) objects, got {short(con)}")
        for inst, var in ((con.src, con.src_var), (con.dst, con.dst_var)):
            if not isinstance(var, str) or not var:
                raise ScenarioError(f"{where}.connections: {short(var)} is no variable name")
            if not isinstance(inst, str) or inst not in sc.instances:
                raise ScenarioError(f"{where}.connections: {short(inst)} is no instance of "
                                    f"the scenario (instances: {', '.join(sc.instances)})")
    check_one_source(sc.connections, where)


def _check_experiment(sc: Scenario, where: str) -> None:
    if (sc.stop_time is None) == (sc.revolutions is None):
        raise ScenarioError(f"{where}: exactly one of stop_time and revolutions is given (the "
                            f"other None), got stop_time={short(sc.stop_time)}, "
                            f"revolutions={short(sc.revolutions)}")
    if not (type(sc.step) in (int, float) and sc.step == 0):    # 0: an SSP that gives none,
        sc.step = positive_in(_text_or_number(sc.step), "s", f"{where}.step")  # asked for later
    if sc.stop_time is not None:
        sc.stop_time = positive_in(_text_or_number(sc.stop_time), "s", f"{where}.stop_time")
    else:
        sc.revolutions = positive_in(_text_or_number(sc.revolutions), "rev",
                                     f"{where}.revolutions")
    if sc.master not in MASTER_NAMES if isinstance(sc.master, str) else True:
        raise ScenarioError(f"{where}.master: one of {', '.join(MASTER_NAMES)}, got "
                            f"{short(sc.master)}")
    if isinstance(sc.fmi, bool) or sc.fmi not in FMI_VERSIONS:
        raise ScenarioError(f"{where}.fmi: the FMI version of sewfmu's FMUs, 2 or 3, got "
                            f"{short(sc.fmi)}")
    if not isinstance(sc.fmus, str) or sc.fmus not in FMU_KINDS:
        raise ScenarioError(f"{where}.fmus: which build of sewfmu's FMUs runs, "
                            f"{' or '.join(map(repr, FMU_KINDS))}, got {short(sc.fmus)}")
    sc.fmus = str.__str__(sc.fmus)
    if isinstance(sc.record_every, bool) or not isinstance(sc.record_every, int) \
            or sc.record_every < 1:
        raise ScenarioError(f"{where}.record_every: a whole number >= 1, got "
                            f"{short(sc.record_every)}")
    if sc.tolerance is not None:
        sc.tolerance = positive(sc.tolerance, f"{where}.tolerance")
    if sc.accuracy != "off":
        sc.accuracy = positive(sc.accuracy, f"{where}.accuracy (a positive number, or \"off\")")
    if not isinstance(sc.accept_error, bool):
        raise ScenarioError(f"{where}.accept_error: True or False, got {short(sc.accept_error)}")
    if sc.step_timeout is not None:
        sc.step_timeout = positive_in(_text_or_number(sc.step_timeout), "s",
                                      f"{where}.step_timeout")
    if sc.shaft is not None and (not isinstance(sc.shaft, str) or sc.shaft not in sc.instances
                                 or sc.instances[sc.shaft].fmu != "MainShaft"):
        raise ScenarioError(f"{where}.shaft: the MainShaft instance whose turns are counted, "
                            f"or None, got {short(sc.shaft)}")


def _text_or_number(value: Any) -> Any:
    """A str subclass as the plain text it holds (its own methods are not called)."""
    return str.__str__(value) if isinstance(value, str) else value
