"""A scenario file's tables (TOML, already read) to a Scenario, checked: the keys it knows, the
instances and their FMUs, connections with one source each, record, [compare], [sweep], roles."""
from __future__ import annotations

from pathlib import Path
from typing import Any

from sewfmu.components.parameters import did_you_mean
from sewfmu.components.registry import FMUS
from sewfmu.scenarios.format.experiment import EXPERIMENT_KEYS
from sewfmu.scenarios.format.fmu_file import check_parameter, fmu_path, is_fmu_file, read_fmu
from sewfmu.scenarios.format.master_settings import MASTER_NAMES
from sewfmu.scenarios.format.scenario import Connection, Instance, Scenario
from sewfmu.scenarios.format.value_lists import check_units_agree, grid_values, values_in_text
from sewfmu.scenarios.format.values import (
    ScenarioError,
    check_instance_name,
    label_of,
    positive_in,
    seconds,
    short,
)
from sewfmu.scenarios.mechanisms import RoleError, mechanism


def _table(data: dict, key: str, where: str, required: bool = True) -> dict:
    value = data.get(key)
    if value is None:
        if required:
            raise ScenarioError(f"{where}: missing [{key}]")
        return {}
    if not isinstance(value, dict):
        raise ScenarioError(f"{where}: {key} must be a table")
    return value


# the keys of a scenario file besides the experiment's (docs/scenarios.md describes each)
TOP_KEYS = ("description", "analysis", "study", "roles", "connections", "record", "experiment",
            "instances", "compare", "sweep")
INSTANCE_KEYS = ("fmu", "parameters")
COMPARE_KEYS = ("parameter", "values")
SWEEP_KEYS = ("grid", "points")


MAX_DESCRIPTION = 2000


def from_dict(data: dict, name: str, source: str) -> Scenario:
    known_top = TOP_KEYS
    for key in data:
        if key not in known_top:
            raise ScenarioError(f"{source}: unknown key {key!r}{did_you_mean(key, known_top)} "
                                f"(known: {', '.join(sorted(known_top))})")
    description = data.get("description", "")
    if not isinstance(description, str) or len(description) > MAX_DESCRIPTION:
        raise ScenarioError(f"{source}: description must be a text of at most "
                            f"{MAX_DESCRIPTION} characters (it titles plots and reports)")
    exp = _table(data, "experiment", source)
    known_exp = EXPERIMENT_KEYS
    for key in exp:
        if key not in known_exp:
            raise ScenarioError(f"{source}: unknown key experiment.{key}"
                                f"{did_you_mean(key, known_exp)} "
                                f"(known: {', '.join(sorted(known_exp))})")
    if ("revolutions" in exp) == ("stop_time" in exp):
        raise ScenarioError(f"{source}: [experiment] needs exactly one of revolutions, stop_time")
    master = exp.get("master", "jacobi")
    if master not in MASTER_NAMES:
        raise ScenarioError(f"{source}: experiment.master must be one of {MASTER_NAMES}, got {master!r}")
    if "step" not in exp:
        raise ScenarioError(f"{source}: missing experiment.step")

    if not isinstance(data.get("description", ""), str):
        raise ScenarioError(f"{source}: description must be a string")
    if "shaft" in exp and "stop_time" in exp:
        raise ScenarioError(f"{source}: experiment.shaft names the shaft whose revolutions are "
                            f"counted; with stop_time it has no use: remove one of them")
    instances = {}
    files, described = {}, {}           # FMU files named in it: text -> path; instance -> md
    for inst_name, spec in _table(data, "instances", source).items():
        where = f"{source}: instances.{inst_name}"
        try:
            check_instance_name(inst_name)
        except ValueError as err:
            raise ScenarioError(f"{where}: {err}") from None
        if not isinstance(spec, dict) or not isinstance(spec.get("fmu"), str):
            raise ScenarioError(f"{where}: needs fmu = \"<FMU name>\"")
        for key in spec:
            if key not in INSTANCE_KEYS:
                raise ScenarioError(f"{where}: unknown key {key!r}"
                                    f"{did_you_mean(key, INSTANCE_KEYS)} (fmu, parameters)")
        params = spec.get("parameters", {})
        if not isinstance(params, dict):
            raise ScenarioError(f"{where}.parameters must be a table")
        if is_fmu_file(spec["fmu"]):     # any FMU, by its path from the scenario file's folder
            files[spec["fmu"]] = fmu_path(spec["fmu"], Path(source).parent, where)
            described[inst_name] = read_fmu(files[spec["fmu"]], where)
        elif spec["fmu"] not in FMUS:
            raise ScenarioError(f"{where}: unknown FMU {spec['fmu']!r}"
                                f"{did_you_mean(spec['fmu'], FMUS)} (known: {', '.join(FMUS)}; "
                                f"or the path of an .fmu file)")
        inst = Instance(inst_name, spec["fmu"], {})
        instances[inst_name] = inst
    scenario = Scenario(
        name=name, source=source, description=description,
        analysis=data.get("analysis"), instances=instances, connections=[],
        record=data.get("record"), step=seconds(exp["step"], f"{source}: experiment.step"),
        master=master,
        stop_time=(seconds(exp["stop_time"], f"{source}: experiment.stop_time")
                   if "stop_time" in exp else None),
        revolutions=(positive_in(exp["revolutions"], "rev", f"{source}: experiment.revolutions")
                     if "revolutions" in exp else None),
        shaft=exp.get("shaft"), compare=data.get("compare"), sweep=data.get("sweep"))
    scenario.fmu_files = files          # set_value reads their declared units
    # every other experiment key the file gives, as `--set experiment.KEY` takes it
    for key in EXPERIMENT_KEYS:
        if key in exp and key not in ("step", "master", "stop_time", "revolutions", "shaft"):
            scenario.set_value(f"experiment.{key}", exp[key], origin=f"{source}:")
    if "tolerance" in exp:
        scenario.tolerance_master = master
    for inst_name, spec in data["instances"].items():
        for key, value in spec.get("parameters", {}).items():
            scenario.set_value(f"{inst_name}.{key}", value,
                               origin=f"{source}: instances.{inst_name}.parameters")
            if inst_name in described:  # sewfmu's own FMUs are checked by set_value
                check_parameter(described[inst_name], key,
                                scenario.instances[inst_name].parameters[key],
                                f"{source}: instances.{inst_name}.parameters.{key}")
    scenario.roles = _bind_roles(data, instances, source)
    scenario.study = _study_of(data, source)
    if scenario.revolutions is not None:
        if scenario.shaft is None:
            scenario.shaft = scenario.default_shaft()
        if scenario.shaft not in instances:
            raise ScenarioError(f"{source}: experiment.shaft must name the MainShaft instance "
                                f"whose revolutions are counted, got {scenario.shaft!r}")
        if instances[scenario.shaft].fmu != "MainShaft":
            raise ScenarioError(f"{source}: experiment.shaft names {scenario.shaft!r}, an instance "
                                f"of {instances[scenario.shaft].fmu}: revolutions are counted on a "
                                f"MainShaft instance")
    connections = data.get("connections", [])
    if not isinstance(connections, list):
        raise ScenarioError(f"{source}: connections must be a list of \"a.x -> b.y\" strings")
    scenario.connections = [_parse_connection(text, instances, source) for text in connections]
    check_one_source(scenario.connections, source)
    check_record(scenario.record, source)
    if scenario.compare is not None:
        check_compare(scenario, source)
    if scenario.sweep is not None:
        check_sweep(scenario.sweep, source)
    return scenario


def check_one_source(connections: list[Connection], source: str) -> None:
    """FMI inputs take one value: a second source into an input would silently win."""
    sources: dict[tuple[str, str], Connection] = {}
    for con in connections:
        other = sources.get((con.dst, con.dst_var))
        if other is not None:
            raise ScenarioError(f"{source}: connections: input {con.dst}.{con.dst_var} has two "
                                f"sources, {other.src}.{other.src_var} and "
                                f"{con.src}.{con.src_var}; an input takes one")
        sources[(con.dst, con.dst_var)] = con


def check_record(record: Any, source: str) -> None:
    """A record list: "instance.variable" strings, each once (the run checks that they exist)."""
    if record is None:
        return
    if not isinstance(record, list) or not all(isinstance(r, str) for r in record):
        raise ScenarioError(f"{source}: record must be a list of \"instance.variable\" strings")
    twice = sorted({r for r in record if record.count(r) > 1})
    if twice:
        raise ScenarioError(f"{source}: record lists {twice[0]!r} more than once")


def check_compare(scenario: Scenario, source: str) -> None:
    """[compare] parameter = "instance.parameter" (or "experiment.key"), values = [distinct],
    or values as a text list ("955, 1910 rpm": a unit after the last applies to all)."""
    cmp = scenario.compare
    if isinstance(cmp, dict) and isinstance(cmp.get("values"), str):
        cmp["values"] = values_in_text(cmp["values"], f"{source}: compare.values")
    if not isinstance(cmp, dict) or not isinstance(cmp.get("parameter"), str) \
            or not isinstance(cmp.get("values"), list) or not cmp["values"]:
        raise ScenarioError(f"{source}: [compare] needs parameter = \"instance.parameter\" and "
                            f"a non-empty list values = [...] (or a text list \"955, 1910 "
                            f"rpm\")")
    unknown = set(cmp) - set(COMPARE_KEYS)
    if unknown:
        raise ScenarioError(f"{source}: unknown key compare.{sorted(unknown)[0]} "
                            f"(known: parameter, values)")
    check_units_agree(cmp["values"], f"{source}: compare.values")
    labels = [label_of(cmp["parameter"], v) for v in cmp["values"]]
    twice = sorted({label for label in labels if labels.count(label) > 1})
    if twice:
        raise ScenarioError(f"{source}: compare.values gives {twice[0]} more than once")
    probe = scenario.copy()
    for value in cmp["values"]:
        probe.set_value(cmp["parameter"], value, origin=f"{source}: compare")


def _bind_roles(data: dict, instances: dict[str, Instance], source: str) -> dict[str, str]:
    """The analysis's roles bound to instances (scenarios/mechanisms), or {} without one."""
    analysis, given = data.get("analysis"), data.get("roles", {})
    if analysis is None:
        if given:
            raise ScenarioError(f"{source}: roles without an analysis")
        return {}
    if not isinstance(analysis, str):
        raise ScenarioError(f"{source}: analysis must be a name, got {analysis!r}")
    if not isinstance(given, dict) or not all(isinstance(v, str) for v in given.values()):
        raise ScenarioError(f"{source}: roles must be a table of role = \"instance\"")
    try:
        return mechanism(analysis).bind({name: inst.fmu for name, inst in instances.items()},
                                        given)
    except RoleError as err:
        raise ScenarioError(f"{source}: {err}") from None


def check_sweep(sweep: Any, source: str) -> None:
    """[sweep] grid = { "instance.parameter" = [values] }, or [[sweep.points]] tables."""
    if not isinstance(sweep, dict) or set(sweep) - set(SWEEP_KEYS):
        raise ScenarioError(f"{source}: [sweep] takes grid = {{ \"instance.parameter\" = [...] }} "
                            f"or [[sweep.points]]")
    grid = sweep.get("grid", {})
    if not isinstance(grid, dict) or not all(isinstance(v, (list, str)) and v
                                             for v in grid.values()):
        raise ScenarioError(f"{source}: sweep.grid: each parameter needs a non-empty list of "
                            f"values, or a text like \"100, 200, 300 rpm\"")
    for name, values in grid.items():   # "100, 200 rpm": the list it is (value_lists.py)
        grid[name] = grid_values(values, f"{source}: sweep.grid.{name}")
    points = sweep.get("points", [])
    if not isinstance(points, list) or not all(isinstance(p, dict) and p for p in points):
        raise ScenarioError(f"{source}: sweep.points must be tables of instance.parameter = value")


def _parse_connection(text: Any, instances: dict, source: str) -> Connection:
    where = f"{source}: connection {text!r}"
    if not isinstance(text, str) or "->" not in text:
        raise ScenarioError(f"{where}: expected \"instance.output -> instance.input\"")
    left, right = (part.strip() for part in text.split("->", 1))
    ends = []
    for end in (left, right):
        inst, dot, var = end.partition(".")
        if not dot or not var:
            raise ScenarioError(f"{where}: {end!r} is not instance.variable")
        if inst not in instances:
            raise ScenarioError(f"{where}: unknown instance {inst!r}"
                                f"{did_you_mean(inst, instances)}")
        ends.append((inst, var))
    return Connection(ends[0][0], ends[0][1], ends[1][0], ends[1][1])


def _study_of(data: dict, source: str) -> str | None:
    """A study of the scenario's analysis (computed from its instances' parameters, not
    co-simulated: scenarios/mechanisms), or None."""
    study = data.get("study")
    if study is None:
        return None
    analysis = data.get("analysis")
    known = list(mechanism(analysis).studies) if isinstance(analysis, str) else []
    if not isinstance(study, str) or study not in known:
        raise ScenarioError(f"{source}: study must name a study of the analysis "
                            f"{analysis!r}, got {short(study)}{did_you_mean(str(study), known)} "
                            f"(known: {', '.join(known) or 'none'})")
    if data.get("compare"):
        raise ScenarioError(f"{source}: a study compares its designs itself: [compare] has no "
                            f"use in it (a [sweep] has)")
    return study
