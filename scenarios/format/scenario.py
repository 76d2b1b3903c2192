"""The scenario file: a small TOML that names FMU instances, connections and the experiment.

    description = "..."
    analysis = "punch"                      # key figures and plots: scenarios/analyses/punch.py
    roles = { punch = "ram" }               # optional: which instance plays which of the
                                            # analysis's roles (others are found by FMU type)
    connections = ["shaft.phi -> linkage.phi", ...]
    record = ["punch.y", ...]               # optional; default: every output

    [experiment]
    revolutions = 10                        # or stop_time = 0.5 (s)
    shaft = "shaft"                         # optional: the MainShaft instance whose turns are
                                            # counted (default: the analysis's shaft)
    step = 2.5e-4                           # communication step (s)
    master = "jacobi"                       # or "gauss-seidel", "iterative", "adaptive"
    tolerance = 1e-5                        # iterative (default 1e-6), adaptive (1e-5)
    acceleration = "aitken"                 # iterative: or "iqn-ils", "none"
    record_every = 1                        # optional: keep every n-th point (long runs)
    fmi = 2                                 # optional: run sewfmu's FMI 3.0 FMUs with 3

    [instances.shaft]
    fmu = "MainShaft"
    parameters = { omega0 = 100.0 }

    [compare]                               # optional: overlaid runs
    parameter = "shaft.omega0"
    values = [100.0, 200.0, 300.0]

    [sweep.grid]                            # optional: `sewfmu sweep` (or [[sweep.points]])
    "shaft.omega0" = [100.0, 200.0, 300.0]
    "punch.F30" = [0.0, 5.0, 10.0]

Every key, with its meaning, default and an example: docs/scenarios.md (the experiment's keys:
scenarios/experiment.py). Every mistake is a ScenarioError that names the file and the key.
"""
from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from sewfmu.components.parameters import did_you_mean
from sewfmu.components.registry import FMI_VERSIONS, FMUS, parameter_units
from sewfmu.scenarios.format.experiment import EXPERIMENT_KEYS
from sewfmu.scenarios.format.master_settings import ACCELERATIONS, MASTER_NAMES, SettingError, settings_for
from sewfmu.scenarios.format.values import (
    ScenarioError,
    check_instance_name,
    label_of,
    positive,
    seconds,
    short,
)


@dataclass(frozen=True)
class Connection:
    src: str          # instance
    src_var: str
    dst: str
    dst_var: str

    def __str__(self) -> str:
        return f"{self.src}.{self.src_var} -> {self.dst}.{self.dst_var}"


@dataclass
class Instance:
    name: str
    fmu: str
    parameters: dict[str, Any] = field(default_factory=dict)


@dataclass
class Scenario:
    name: str
    source: str                     # where it was read from, for messages
    description: str
    analysis: str | None
    instances: dict[str, Instance]
    connections: list[Connection]
    record: list[str] | None
    step: float
    master: str
    stop_time: float | None
    revolutions: float | None
    shaft: str | None
    compare: dict[str, Any] | None
    sweep: dict[str, Any] | None = None
    record_every: int = 1             # record every n-th communication point (long runs)
    roles: dict[str, str] = field(default_factory=dict)   # the analysis's role -> instance
    tolerance: float | None = None          # iterative, adaptive masters; None: their default
    tolerance_master: str | None = None     # the master a file's tolerance was given for
    acceleration: str = "aitken"                          # iterative master
    fmi: int = 2                      # the FMI version of sewfmu's FMUs it runs (2 or 3)
    digest: str = ""                  # sha256 of the scenario file's text, as read
    # FMU type -> file, for a system read from SSP (scenarios/ssp_import.py): its own FMUs
    fmu_files: dict[str, Path] = field(default_factory=dict)

    def settings(self):
        """The typed settings of its master (scenarios/algorithm_settings.py): the file's
        tolerance and acceleration where given, else the master's defaults. A scenario file's
        tolerance belongs to the file's master: run with another master, that master's default
        applies."""
        given = {"acceleration": self.acceleration}
        if self.tolerance and self.tolerance_master in (None, self.master):
            given["tolerance"] = self.tolerance
        try:
            return settings_for(self.master, given)
        except SettingError as err:
            raise ScenarioError(f"{self.source}: {err}") from None

    def master_settings(self) -> dict[str, Any]:
        """The settings its master uses besides the step, by key (a tolerance or an
        acceleration it ignores is left out)."""
        return dataclasses.asdict(self.settings())

    def copy(self) -> "Scenario":
        return copy.deepcopy(self)

    def end_time(self) -> float:
        """The run's end: experiment.stop_time, or the time the shaft instance needs for
        experiment.revolutions with its parameters (its speed ramp included)."""
        if self.stop_time is not None:
            return self.stop_time
        from sewfmu.components.parameters import ParameterError, with_values
        from sewfmu.components.shaft import MainShaft, ShaftParams

        if self.shaft is None:        # revolutions set later (--set)
            self.shaft = self.default_shaft()
        if self.shaft not in self.instances:
            raise ScenarioError(f"{self.source}: experiment.revolutions needs the MainShaft "
                                f"instance whose turns are counted (experiment.shaft), or give "
                                f"experiment.stop_time")
        inst = self.instances[self.shaft]
        try:
            params = with_values(ShaftParams(), **inst.parameters)
        except ParameterError as err:
            raise ScenarioError(f"{self.source}: {self.shaft}: {err}") from None
        return MainShaft(params).time_of_angle(2 * math.pi * self.revolutions)

    def even_steps(self) -> tuple[int, float]:
        """The run as whole, even communication steps: (n, h) with n·h the end time and h the
        longest step not above experiment.step. No step is a sliver, and a fixed-step host that
        takes n steps of h ends where the scenario does (on a whole revolution where it counts
        revolutions)."""
        end = self.end_time()
        n = max(1, math.ceil(end / self.step * (1.0 - 1e-12)))
        return n, end / n

    def last_revolution_start(self) -> float | None:
        """The time the last whole revolution of the counted shaft begins (None where the
        scenario has no MainShaft to count): from there on every step is recorded, whatever
        experiment.record_every thins out before, so that the key figures never depend on it."""
        from sewfmu.components.parameters import ParameterError, with_values
        from sewfmu.components.shaft import MainShaft, ShaftParams

        shaft = self.shaft or self.default_shaft()
        if shaft not in self.instances or self.instances[shaft].fmu != "MainShaft":
            return None
        try:
            model = MainShaft(with_values(ShaftParams(), **self.instances[shaft].parameters))
        except ParameterError:
            return None
        turns = math.floor(model.state(self.end_time())[0] / (2 * math.pi) + 1e-9)
        return model.time_of_angle(2 * math.pi * (turns - 1)) if turns >= 1 else 0.0

    def default_shaft(self) -> str | None:
        """The MainShaft whose revolutions count when experiment.shaft names none: the
        analysis's shaft, or the only MainShaft."""
        shafts = [n for n, inst in self.instances.items() if inst.fmu == "MainShaft"]
        return self.roles.get("shaft") or (shafts[0] if len(shafts) == 1 else None)

    def set_value(self, target: str, value: Any, origin: str = "--set") -> None:
        """Apply `instance.parameter = value` (or `experiment.key = value`)."""
        inst, dot, key = target.partition(".")
        if not dot or not key:
            raise ScenarioError(f"{origin} {target}: expected instance.parameter")
        if inst == "experiment":
            self._set_experiment(key, value, origin)
            return
        if inst not in self.instances:
            raise ScenarioError(f"{origin} {target}: unknown instance {inst!r} in {self.source}"
                                f"{did_you_mean(inst, self.instances)} "
                                f"(instances: {', '.join(self.instances)})")
        fmu = self.instances[inst].fmu
        if fmu in FMUS and fmu not in self.fmu_files:   # an FMU from elsewhere: its own check
            known = parameter_units(fmu)
            if key not in known:
                raise ScenarioError(f"{origin} {target}: {inst} ({fmu}) has no parameter "
                                    f"{key!r}{did_you_mean(key, known)} "
                                    f"(has: {', '.join(known)})")
        if isinstance(value, str):          # a value with its unit: "110 deg", "955 rpm"
            value = self._in_declared_unit(inst, key, value, f"{origin} {target}")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ScenarioError(f"{origin} {target}: value must be a number, got {value!r}")
        try:
            finite = math.isfinite(float(value))
        except OverflowError:               # an integer beyond any float
            finite = False
        if not finite:
            raise ScenarioError(f"{origin} {target}: parameter {key} must be a finite number "
                                f"within the range of a float (about ±1.8e308), got "
                                f"{short(value)}")
        self.instances[inst].parameters[key] = value

    def _in_declared_unit(self, inst: str, key: str, text: str, where: str) -> float:
        """A value given with its unit, in the unit its FMU declares for the variable."""
        from sewfmu.components.units import UnitError, in_unit

        fmu = self.instances[inst].fmu
        units = (_declared_units(self.fmu_files[fmu]) if fmu in self.fmu_files
                 else parameter_units(fmu))
        if key not in units:
            raise ScenarioError(f"{where}: {inst} ({fmu}) has no parameter {key!r}"
                                f"{did_you_mean(key, units)}")
        try:
            return in_unit(text, units[key])
        except UnitError as err:
            raise ScenarioError(f"{where}: {err}") from None

    def _set_experiment(self, key: str, value: Any, origin: str) -> None:
        choices = {"master": MASTER_NAMES, "acceleration": ACCELERATIONS}
        if key in choices:
            if value not in choices[key]:
                raise ScenarioError(f"{origin} experiment.{key}: must be one of {choices[key]}, "
                                    f"got {value!r}")
            setattr(self, key, value)
            return
        if key == "tolerance":
            self.tolerance = positive(value, f"{origin} experiment.tolerance")
            self.tolerance_master = None          # given with --set: for whichever master runs
            return
        if key == "fmi":
            if isinstance(value, bool) or value not in FMI_VERSIONS:
                raise ScenarioError(f"{origin} experiment.fmi: the FMI version of the FMUs, 2 or "
                                    f"3, got {value!r}")
            self.fmi = int(value)
            return
        if key == "record_every":
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ScenarioError(f"{origin} experiment.record_every: must be a whole number "
                                    f">= 1, got {value!r}")
            self.record_every = value
            return
        if key == "shaft":
            if value not in self.instances or self.instances[value].fmu != "MainShaft":
                shafts = [n for n, i in self.instances.items() if i.fmu == "MainShaft"]
                raise ScenarioError(f"{origin} experiment.shaft: must name a MainShaft instance "
                                    f"({', '.join(shafts) or 'none here'}), got {value!r}")
            self.shaft = value
            return
        if key not in ("step", "stop_time", "revolutions"):
            raise ScenarioError(f"{origin} experiment.{key}: unknown experiment setting"
                                f"{did_you_mean(key, EXPERIMENT_KEYS)} "
                                f"({', '.join(EXPERIMENT_KEYS)})")
        where = f"{origin} experiment.{key}"
        number = seconds(value, where) if key in ("step", "stop_time") else positive(value, where)
        setattr(self, key, number)
        if key == "stop_time":
            self.revolutions = None
        elif key == "revolutions":
            self.stop_time = None


def _declared_units(fmu_file: Path) -> dict[str, str]:
    """name -> unit of the parameters and inputs of an FMU file (from another tool)."""
    from fmpy import read_model_description

    md = read_model_description(str(fmu_file))
    return {v.name: v.unit or "" for v in md.modelVariables
            if v.causality in ("parameter", "input")}


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
TOP_KEYS = ("description", "analysis", "roles", "connections", "record", "experiment",
            "instances", "compare", "sweep")
INSTANCE_KEYS = ("fmu", "parameters")
COMPARE_KEYS = ("parameter", "values")
SWEEP_KEYS = ("grid", "points")


def from_dict(data: dict, name: str, source: str) -> Scenario:
    known_top = TOP_KEYS
    for key in data:
        if key not in known_top:
            raise ScenarioError(f"{source}: unknown key {key!r}{did_you_mean(key, known_top)} "
                                f"(known: {', '.join(sorted(known_top))})")
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
        if spec["fmu"] not in FMUS:
            raise ScenarioError(f"{where}: unknown FMU {spec['fmu']!r}"
                                f"{did_you_mean(spec['fmu'], FMUS)} (known: {', '.join(FMUS)})")
        inst = Instance(inst_name, spec["fmu"], {})
        instances[inst_name] = inst
    scenario = Scenario(
        name=name, source=source, description=str(data.get("description", "")),
        analysis=data.get("analysis"), instances=instances, connections=[],
        record=data.get("record"), step=seconds(exp["step"], f"{source}: experiment.step"),
        master=master,
        stop_time=(seconds(exp["stop_time"], f"{source}: experiment.stop_time")
                   if "stop_time" in exp else None),
        revolutions=(positive(exp["revolutions"], f"{source}: experiment.revolutions")
                     if "revolutions" in exp else None),
        shaft=exp.get("shaft"), compare=data.get("compare"), sweep=data.get("sweep"))
    for key in ("record_every", "tolerance", "acceleration", "fmi"):
        if key in exp:
            scenario.set_value(f"experiment.{key}", exp[key], origin=f"{source}: experiment.{key}")
    if "tolerance" in exp:
        scenario.tolerance_master = master
    for inst_name, spec in data["instances"].items():
        for key, value in spec.get("parameters", {}).items():
            scenario.set_value(f"{inst_name}.{key}", value,
                               origin=f"{source}: instances.{inst_name}.parameters")
    scenario.roles = _bind_roles(data, instances, source)
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
    _check_record(scenario.record, source)
    if scenario.compare is not None:
        _check_compare(scenario, source)
    if scenario.sweep is not None:
        _check_sweep(scenario.sweep, source)
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


def _check_record(record: Any, source: str) -> None:
    if record is None:
        return
    if not isinstance(record, list) or not all(isinstance(r, str) for r in record):
        raise ScenarioError(f"{source}: record must be a list of \"instance.variable\" strings")
    twice = sorted({r for r in record if record.count(r) > 1})
    if twice:
        raise ScenarioError(f"{source}: record lists {twice[0]!r} more than once")


def _check_compare(scenario: Scenario, source: str) -> None:
    """[compare] parameter = "instance.parameter" (or "experiment.key"), values = [distinct]."""
    cmp = scenario.compare
    if not isinstance(cmp, dict) or not isinstance(cmp.get("parameter"), str) \
            or not isinstance(cmp.get("values"), list) or not cmp["values"]:
        raise ScenarioError(f"{source}: [compare] needs parameter = \"instance.parameter\" and "
                            f"a non-empty list values = [...]")
    unknown = set(cmp) - set(COMPARE_KEYS)
    if unknown:
        raise ScenarioError(f"{source}: unknown key compare.{sorted(unknown)[0]} "
                            f"(known: parameter, values)")
    labels = [label_of(cmp["parameter"], v) for v in cmp["values"]]
    twice = sorted({label for label in labels if labels.count(label) > 1})
    if twice:
        raise ScenarioError(f"{source}: compare.values gives {twice[0]} more than once")
    probe = scenario.copy()
    for value in cmp["values"]:
        probe.set_value(cmp["parameter"], value, origin=f"{source}: compare")


def _bind_roles(data: dict, instances: dict[str, Instance], source: str) -> dict[str, str]:
    """The analysis's roles bound to instances (see scenarios/analyses), or {} without one."""
    from sewfmu.scenarios.analyses import RoleError, bind

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
        return bind(analysis, {name: inst.fmu for name, inst in instances.items()}, given)
    except RoleError as err:
        raise ScenarioError(f"{source}: {err}") from None


def _check_sweep(sweep: Any, source: str) -> None:
    """[sweep] grid = { "instance.parameter" = [values] }, or [[sweep.points]] tables."""
    if not isinstance(sweep, dict) or set(sweep) - set(SWEEP_KEYS):
        raise ScenarioError(f"{source}: [sweep] takes grid = {{ \"instance.parameter\" = [...] }} "
                            f"or [[sweep.points]]")
    grid = sweep.get("grid", {})
    if not isinstance(grid, dict) or not all(isinstance(v, list) and v for v in grid.values()):
        raise ScenarioError(f"{source}: sweep.grid: each parameter needs a non-empty list of values")
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
