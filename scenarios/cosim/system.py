"""The scenario's instances connected: every connection checked (variables, types, units), every
parameter and input checked against the modelDescriptions, the instances in dependency order
with the feedback loops found, and the recorded columns planned.

Nothing here calls an FMU: the instances are made (not yet instantiated) by a factory, so that a
test can connect plain Python instances (tests/fake_fmu.py) the same way.
"""
from __future__ import annotations

import warnings
from pathlib import Path
from typing import Callable

import numpy as np

from sewfmu.components.parameters import did_you_mean
from sewfmu.scenarios.cosim.connection_units import conversion, convert_inputs
from sewfmu.scenarios.cosim.divergence import declared_bound
from sewfmu.scenarios.cosim.fmi_calls import LogCollector, kind_of
from sewfmu.scenarios.format.declared_range import out_of_range
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import ScenarioError


class InputLeftOpen(UserWarning):
    """An input of an SSP system that nothing sets: it keeps its start value."""


class System:
    """The connected instances of one scenario, in the order data flows through them."""

    def __init__(self, scenario: Scenario, make: Callable, log: LogCollector):
        """`make(instance declaration, log)` gives the Instance (cosim/instances.py)."""
        self.scenario = scenario
        by_name = {inst.name: make(inst, log) for inst in scenario.instances.values()}
        self._connect(by_name)
        check_parameters(scenario, {name: inst.md for name, inst in by_name.items()})
        check_inputs_given(scenario, list(by_name.values()))
        self.instances, self.in_loops = dependency_order(list(by_name.values()))
        # inputs and outputs settle in one pass along a chain; around a feedback loop each pass
        # carries a change one link further
        self.passes = 1 + len(self.in_loops)
        self.columns: list[str] = []
        self.plan: list = []
        self.units: dict[str, str] = {}

    def _connect(self, by_name: dict) -> None:
        sc = self.scenario
        converted: dict[str, dict[int, tuple[float, float]]] = {}
        for con in sc.connections:
            what = f"{sc.source}: connection {con}"
            src, dst = by_name[con.src], by_name[con.dst]
            out_var = src.variable(con.src_var, ("output",), what)
            in_var = dst.variable(con.dst_var, ("input",), what)
            if kind_of(out_var) != "Real" or kind_of(in_var) != "Real":
                raise ScenarioError(f"{what}: only Real connections are supported")
            # a variable without a unit says nothing about it (FMUs from elsewhere); two
            # declared units that differ are converted through the unit definitions, or refused
            scale = conversion(out_var, src.md, in_var, dst.md, what)
            if scale is not None:
                converted.setdefault(con.dst, {})[len(dst.inputs)] = scale
            src.want_output(con.src_var, what)
            dst.inputs.append((con.dst_var, src, con.src_var))
        for name, scales in converted.items():
            convert_inputs(by_name[name], scales)

    def settle_loops(self) -> None:
        """Carry changed outputs around the feedback loops until they settle (or `passes` are
        made): each instance on a loop takes its inputs again where a source's output moved."""
        for _ in range(self.passes - 1):
            for inst in self.in_loops:
                if inst.pull_changed_inputs():    # unchanged: the outputs read stand
                    inst.read_outputs()

    def plan_records(self) -> None:
        """Decide which outputs are read each step for the records (the scenario's `record`, or
        every output) and make the instances' buffers."""
        sc = self.scenario
        by_name = {inst.name: inst for inst in self.instances}
        if sc.record is None:
            wanted = [f"{inst.name}.{v.name}" for inst in self.instances
                      for v in inst.md.modelVariables if v.causality == "output"]
        else:
            wanted = list(sc.record)
        for col in wanted:
            name, dot, var = str(col).partition(".")
            if name not in by_name or not dot:
                raise ScenarioError(f"{sc.source}: record {col!r}: unknown instance")
            kind, idx = by_name[name].want_output(var, f"{sc.source}: record {col!r}")
            self.plan.append((by_name[name], kind, idx))
            self.units[col] = by_name[name].variables[var].unit or ""
        self.columns = wanted
        # every instance's Real outputs side by side in one array, each instance reading into
        # its part: the recorder copies a step's outputs at once (cosim/recorder.py)
        self.outputs = np.zeros(sum(len(inst.real_out) for inst in self.instances))
        at = 0
        for inst in self.instances:
            inst.out_at = at
            inst.prepare(self.outputs[at:at + len(inst.real_out)])
            at += len(inst.real_out)


def check_parameters(scenario: Scenario, descriptions: dict) -> None:
    """Every parameter the scenario sets exists in its FMU and fits its type and declared range:
    checked from the modelDescriptions alone (instance name -> description), before any FMU
    runs (a sweep checks every point so)."""
    fed = {(c.dst, c.dst_var): c for c in scenario.connections}
    for inst in scenario.instances.values():
        md = descriptions[inst.name]
        variables = {v.name: v for v in md.modelVariables}
        for key, value in inst.parameters.items():
            v = variables.get(key)
            source = fed.get((inst.name, key))
            if source is not None and v is not None and v.causality == "input" \
                    and not _from_ssp(scenario):
                # the connection sets it at every step: the value would be ignored
                raise ScenarioError(f"{scenario.source}: {inst.name}.{key} is an input fed by "
                                    f"the connection {source}: a value given to it would be "
                                    f"ignored; remove the connection to hold it at a value")
            # an input may be given a value too: it then holds it (unconnected)
            if v is None or v.causality not in ("parameter", "input"):
                names = sorted(n for n, x in variables.items() if x.causality == "parameter")
                raise ScenarioError(f"{scenario.source}: {inst.name}.{key}: {inst.name} "
                                    f"({md.modelName}) has no parameter {key!r}"
                                    f"{did_you_mean(key, names)} (has: {', '.join(names)})")
            if kind_of(v) == "Integer" and value != int(value):
                raise ScenarioError(f"{scenario.source}: {inst.name}.{key}: must be an integer, "
                                    f"got {value!r}")
            low, high = declared_bound(v.min), declared_bound(v.max)
            if (low is not None and value < low) or (high is not None and value > high):
                target = f"{inst.name}.{key}"
                raise ScenarioError(out_of_range(scenario.origin_of(target), target, value,
                                                 v.unit, low, high,
                                                 f"{inst.name} ({md.modelName}) declares",
                                                 scenario.with_unit(target)))


def check_inputs_given(scenario: Scenario, instances: list) -> None:
    """Every input of every instance is connected or given a value in the scenario: an input left
    at its start value runs the FMU on a number nobody chose. A system read from SSP (where the
    standard lets an input keep its start value) gets a warning instead."""
    for inst in instances:
        connected = {name for name, _, _ in inst.inputs}
        given = scenario.instances[inst.name].parameters
        for v in inst.md.modelVariables:
            if v.causality != "input" or v.name in connected or v.name in given:
                continue
            text = (f"{scenario.source}: input {inst.name}.{v.name} is neither connected nor "
                    f"given a value")
            if _from_ssp(scenario):
                warnings.warn(f"{text}: it keeps its start value {v.start}", InputLeftOpen,
                              stacklevel=2)
                continue
            raise ScenarioError(f"{text}: connect it (\"<instance>.<output> -> "
                                f"{inst.name}.{v.name}\") or give it a value in "
                                f"[instances.{inst.name}] parameters")


def _from_ssp(scenario: Scenario) -> bool:
    """A system read from SSP (whose inputs may keep their start values, as SSP allows); a TOML
    scenario's FMU files, whoever made them, follow the TOML's rule: every input given."""
    return bool(scenario.fmu_files) and Path(scenario.source).suffix.lower() in (".ssp", ".ssd")


def dependency_order(instances: list) -> tuple[list, list]:
    """Sources before the instances they feed (a cycle keeps the scenario's order within it),
    and the instances that lie on a feedback loop."""
    order, placed = [], set()
    remaining = list(instances)
    while remaining:
        ready = [i for i in remaining
                 if all(src.name in placed or src is i for _, src, _ in i.inputs)]
        if not ready:            # a feedback loop: break it at the first instance in file order
            ready = [remaining[0]]
        for i in ready:
            order.append(i)
            placed.add(i.name)
            remaining.remove(i)
    return order, [i for i in order if reaches(i, i)]


def reaches(start, target) -> bool:
    """Whether a signal from `target` comes back to `start` through the connections."""
    seen, todo = set(), [src for _, src, _ in start.inputs]
    while todo:
        inst = todo.pop()
        if inst is target:
            return True
        if inst.name not in seen:
            seen.add(inst.name)
            todo.extend(src for _, src, _ in inst.inputs)
    return False
