"""A scenario: FMU instances with their parameters, the connections between them, what to record,
and the experiment with its clock (end time, even steps, the last revolution). A TOML file
becomes one through format/parse.py; the file's keys are docs/scenarios.md's."""
from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from sewfmu.components.parameters import did_you_mean
from sewfmu.components.registry import FMI_VERSIONS, FMUS
from sewfmu.scenarios.format.declared_units import parameter_units
from sewfmu.scenarios.format.experiment import EXPERIMENT_KEYS
from sewfmu.scenarios.format.fmu_file import model_description
from sewfmu.scenarios.format.master_settings import ACCELERATIONS, MASTER_NAMES, SettingError, settings_for
from sewfmu.scenarios.format.values import ScenarioError, plain, positive, positive_in, short
from sewfmu.scenarios.mechanisms import Mechanism, RoleError, mechanism


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
    accuracy: float | str = 0.05      # the relative coupling error its key figures may carry;
                                      # "off": not estimated
    accept_error: bool = False        # a run beyond its accuracy succeeds all the same
    step_timeout: float | None = None     # s of wall time a communication step may take
    digest: str = ""                  # sha256 of the scenario file's text, as read
    # FMU type -> file, for a system read from SSP (scenarios/format/ssp_import.py): its own FMUs
    fmu_files: dict[str, Path] = field(default_factory=dict)
    # a study of its analysis: computed from its instances' parameters, not co-simulated
    study: str | None = None
    # the mechanism its analysis names (scenarios/mechanisms), resolved once, here
    mechanism: Mechanism | None = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self):
        if self.analysis is None:
            return
        if not isinstance(self.analysis, str):
            raise ScenarioError(f"{self.source}: analysis must be a name, got {short(self.analysis)}")
        try:
            self.mechanism = mechanism(self.analysis)
        except RoleError as err:
            raise ScenarioError(f"{self.source}: {err}") from None

    def figure_units(self) -> dict[str, str]:
        """The units of its key figures, or of its study's headline figures ({} without an
        analysis)."""
        return self.mechanism.figure_units(self.study) if self.mechanism else {}

    def settings(self):
        """The typed settings of its master (scenarios/format/master_settings.py): the file's
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
        from sewfmu.components.parameters import (  # loaded on first use (start-up time)
            ParameterError,
            with_values,
        )
        from sewfmu.components.shaft import MainShaft, ShaftParams  # loaded on first use (start-up time)

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
        ratio = end / self.step
        if not ratio < 1e18:                 # inf from a subnormal step: not a number of steps
            raise ScenarioError(f"{self.source}: experiment.step {self.step:g} s makes more than "
                                f"1e18 steps of a {end:g} s run; take a longer step")
        n = max(1, math.ceil(ratio * (1.0 - 1e-12)))
        return n, end / n

    def last_revolution_start(self) -> float | None:
        """The time the last whole revolution of the counted shaft begins (None where the
        scenario has no MainShaft to count): from there on every step is recorded, whatever
        experiment.record_every thins out before, so that the key figures never depend on it."""
        from sewfmu.components.parameters import (  # loaded on first use (start-up time)
            ParameterError,
            with_values,
        )
        from sewfmu.components.shaft import MainShaft, ShaftParams  # loaded on first use (start-up time)

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
        value = plain(value)
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
        from sewfmu.components.units import UnitError  # loaded on first use (start-up time)
        from sewfmu.scenarios.format.quantities import in_declared_unit  # pint: on first use

        fmu = self.instances[inst].fmu
        units = (_declared_units(self.fmu_files[fmu]) if fmu in self.fmu_files
                 else parameter_units(fmu))
        if key not in units:
            raise ScenarioError(f"{where}: {inst} ({fmu}) has no parameter {key!r}"
                                f"{did_you_mean(key, units)}")
        try:
            return in_declared_unit(text, units[key], f"{inst}.{key}")
        except UnitError as err:
            # the message names the parameter itself ("punch.c2 = '30 N': ..."): where, before it
            origin = where.removesuffix(f"{inst}.{key}").strip()
            raise ScenarioError(f"{origin} {err}" if origin else str(err)) from None

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
            if self.instances and all(i.fmu in self.fmu_files for i in self.instances.values()):
                raise ScenarioError(f"{origin} experiment.fmi: chooses the FMI version of "
                                    f"sewfmu's own FMUs; {self.source} runs only FMU files of "
                                    f"its own, whatever their version")
            self.fmi = int(value)
            return
        if key == "accuracy":
            # "off": no estimate, no coarser run (a benchmark against a plain loop, a run whose
            # figures are not read)
            self.accuracy = "off" if value == "off" else \
                positive(value, f"{origin} experiment.accuracy (a positive number, or \"off\")")
            return
        if key == "step_timeout":
            # "off": no limit (a file's limit lifted with --set)
            self.step_timeout = None if value == "off" else positive_in(
                value, "s", f"{origin} experiment.step_timeout")
            return
        if key == "accept_error":
            if not isinstance(value, bool):
                raise ScenarioError(f"{origin} experiment.accept_error: true or false, got "
                                    f"{value!r}")
            self.accept_error = value
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
        number = positive_in(value, "s" if key in ("step", "stop_time") else "rev", where)
        setattr(self, key, number)
        if key == "stop_time":
            self.revolutions = None
        elif key == "revolutions":
            self.stop_time = None


def _declared_units(fmu_file: Path) -> dict[str, str]:
    """name -> unit of the parameters and inputs of an FMU file (from another tool)."""
    md = model_description(fmu_file, "")
    return {v.name: v.unit or "" for v in md.modelVariables
            if v.causality in ("parameter", "input")}
