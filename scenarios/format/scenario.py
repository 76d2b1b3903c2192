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

from sewfmu.components.parameters import (
    ParameterError,
    did_you_mean,
    with_values,
)
from sewfmu.components.registry import FMI_VERSIONS, FMUS
from sewfmu.components.units import UnitError
from sewfmu.scenarios.format.declared_units import parameter_bounds, parameter_units
from sewfmu.scenarios.format.experiment import EXPERIMENT_KEYS, FMU_KINDS
from sewfmu.scenarios.format.fmu_file import declared_bounds, model_description
from sewfmu.scenarios.format.master_settings import ACCELERATIONS, MASTER_NAMES, SettingError, settings_for
from sewfmu.scenarios.format.values import (
    DECIMAL,
    ScenarioError,
    check_scenario_name,
    positive,
    positive_in,
    real,
    short,
)
from sewfmu.scenarios.mechanisms import Mechanism, RoleError, mechanism

# seconds a shaft revolution may take before a run of revolutions blames the speed rather
# than the step for its number of steps (2π·1e-6 rad/s: no sewing machine turns so slowly)
SLOWEST_TURN = 1e6


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
    fmus: str = "python"              # which build of sewfmu's FMUs it runs: FMU_KINDS
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
    # "instance.parameter" or "experiment.key" -> (where its value was given: "--set", "set",
    # "--grid (grid=)", the file; the text it was given as, where it carried a unit): a refusal
    # names the option the user typed, and offers no unit to a value given with one
    given: dict[str, tuple[str, str | None]] = field(default_factory=dict, init=False,
                                                     repr=False, compare=False)

    def __setattr__(self, key: str, value: Any) -> None:
        if key == "name":               # it names files and folders: never a path
            check_scenario_name(value)
        super().__setattr__(key, value)

    def origin_of(self, target: str) -> str:
        """Where the value of `target` was given, as a message begins with it: the option
        ("--set", "set", "--grid (grid=)"), or the scenario's file ("path/x.toml:")."""
        origin = self.given.get(target, ("", None))[0]
        return origin if origin and not origin.startswith(self.source) else f"{self.source}:"

    def with_unit(self, target: str) -> str | None:
        """The text `target`'s value was given as where it carried a unit ("955 rpm"), else
        None."""
        return self.given.get(target, ("", None))[1]

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
            raise ScenarioError(self._refused(self.shaft, ShaftParams, err)) from None
        end = MainShaft(params).time_of_angle(2 * math.pi * self.revolutions)
        if not math.isfinite(end):          # "5e-324 rad/s": no end a float can hold
            speed = f"{self.shaft}.omega0"
            raise ScenarioError(f"{self.origin_of(speed)} {speed} = {params.omega0!r} rad/s is "
                                f"so slow that {_turns(self.revolutions)} would never end "
                                f"(no time a float holds); give the shaft a speed")
        return end

    def _refused(self, inst: str, params_class, err) -> str:
        """A model's refusal of a parameter (components/parameters.py), worded as the run's
        check words it: where the value was given, and a value out of the declared range with
        the digits that set it apart from the bound and no unit offered for one given."""
        from sewfmu.components.parameters import parameter_info  # loaded with the model
        from sewfmu.scenarios.format.declared_range import out_of_range  # only for a refusal

        info = {i.name: i for i in parameter_info(params_class)}.get(err.name)
        value = self.instances[inst].parameters.get(err.name)
        target = f"{inst}.{err.name}"
        # the range's refusal only ("must be within"; a sign the model refuses says so itself)
        if info is not None and isinstance(value, (int, float)) and math.isfinite(value) \
                and "must be within" in str(err):
            low, high = info.bounds
            if (low is not None and value < low) or (high is not None and value > high):
                return out_of_range(self.origin_of(target), target, value, info.unit, low, high,
                                    f"{inst} ({self.instances[inst].fmu}) declares",
                                    self.with_unit(target))
        return f"{self.origin_of(target)} {target}: {err}"

    def even_steps(self) -> tuple[int, float]:
        """The run as whole, even communication steps: (n, h) with n·h the end time and h the
        longest step not above experiment.step. No step is a sliver, and a fixed-step host that
        takes n steps of h ends where the scenario does (on a whole revolution where it counts
        revolutions)."""
        end = self.end_time()
        ratio = end / self.step
        if not ratio < 1e18 and self.stop_time is None and self.shaft in self.instances \
                and end / self.revolutions > SLOWEST_TURN:
            # a revolution of days: the shaft's speed, not the step, is the slip
            speed = f"{self.shaft}.omega0"
            omega = self.instances[self.shaft].parameters.get("omega0")
            raise ScenarioError(f"{self.origin_of(speed)} {speed}"
                                f"{f' = {omega!r} rad/s' if omega is not None else ''} is so "
                                f"slow that {_turns(self.revolutions)} take {end:.3g} s, "
                                f"more than 1e18 steps of {self.step:g} s; give the shaft a "
                                f"speed")
        if not ratio < 1e18:                 # inf from a subnormal step: not a number of steps
            step = "experiment.step"
            raise ScenarioError(f"{self.origin_of(step)} {step} {self.step:g} s makes more "
                                f"than 1e18 steps of a {end:g} s run; take a longer step")
        n = max(1, math.ceil(ratio * (1.0 - 1e-12)))
        return n, end / n

    def last_revolution_start(self) -> float | None:
        """The time the last whole revolution of the counted shaft begins (None where the
        scenario has no MainShaft to count): from there on every step is recorded, whatever
        experiment.record_every thins out before, so that the key figures never depend on it."""
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
        value = real(value)             # Decimal, Fraction, numpy's longdouble: the float
        inst, dot, key = target.partition(".")
        if not dot or not key:
            raise ScenarioError(f"{origin} {target}: expected instance.parameter")
        if inst == "experiment":
            self._set_experiment(key, value, origin)
            self.given[target] = (origin, value if isinstance(value, str) else None)
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
        text = value if isinstance(value, str) and not DECIMAL.fullmatch(value.strip()) \
            else None
        if isinstance(value, str):          # a value with its unit: "110 deg", "955 rpm"
            value = self._in_declared_unit(inst, key, value, f"{origin} {target}")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ScenarioError(f"{origin} {target}: value must be a number, got {short(value)}")
        try:
            finite = math.isfinite(float(value))
        except OverflowError:               # an integer beyond any float
            finite = False
        if not finite:
            raise ScenarioError(f"{origin} {target}: parameter {key} must be a finite number "
                                f"within the range of a float (about ±1.8e308), got "
                                f"{short(value)}")
        if text is not None and isinstance(value, float):
            value = self._snapped(inst, key, value)      # "400 grad": 2π, one rounding above
        self.instances[inst].parameters[key] = value
        self.given[target] = (origin, text)

    def refuse_converted_beyond_range(self) -> None:
        """A value of sewfmu's FMUs given with a unit that converts beyond the declared range,
        refused as given ("19098.6 rpm"): for a caller that hands the numbers on and so would
        lose the unit the refusal must not offer (a sweep's points)."""
        from sewfmu.scenarios.format.declared_range import out_of_range  # only with a unit

        for target, (origin, text) in self.given.items():
            inst, _, key = target.partition(".")
            if text is None or inst not in self.instances or \
                    self.instances[inst].fmu not in FMUS or self.instances[inst].fmu in self.fmu_files:
                continue
            value = self.instances[inst].parameters.get(key)
            low, high = parameter_bounds(self.instances[inst].fmu).get(key, (None, None))
            if isinstance(value, (int, float)) and ((low is not None and value < low)
                                                    or (high is not None and value > high)):
                raise ScenarioError(out_of_range(
                    self.origin_of(target), target, value, parameter_units(
                        self.instances[inst].fmu).get(key, ""), low, high,
                    f"{inst} ({self.instances[inst].fmu}) declares", text))

    def _snapped(self, inst: str, key: str, value: float) -> float:
        """A value converted from its unit, the declared bound it lies within a rounding of
        (format/declared_range.py)."""
        from sewfmu.scenarios.format.declared_range import (  # only for a unit given
            bounds_of_own,
            snapped,
        )

        fmu = self.instances[inst].fmu
        if fmu in self.fmu_files:           # an FMU file's own range, or its declared type's
            md = model_description(self.fmu_files[fmu], "")
            variable = next((v for v in md.modelVariables if v.name == key), None)
            low, high = declared_bounds(variable) if variable is not None else (None, None)
        else:
            low, high = bounds_of_own(fmu, key) if fmu in FMUS else (None, None)
        return snapped(value, low, high)

    def _in_declared_unit(self, inst: str, key: str, text: str, where: str) -> float:
        """A value given with its unit, in the unit its FMU declares for the variable."""
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
                                    f"got {short(value)}")
            setattr(self, key, value)
            return
        if key == "tolerance":
            self.tolerance = positive(value, f"{origin} experiment.tolerance")
            self.tolerance_master = None          # given with --set: for whichever master runs
            return
        if key == "fmi":
            if isinstance(value, bool) or value not in FMI_VERSIONS:
                raise ScenarioError(f"{origin} experiment.fmi: the FMI version of the FMUs, 2 or "
                                    f"3, got {short(value)}")
            if self.instances and all(i.fmu in self.fmu_files for i in self.instances.values()):
                raise ScenarioError(f"{origin} experiment.fmi: chooses the FMI version of "
                                    f"sewfmu's own FMUs; {self.source} runs only FMU files of "
                                    f"its own, whatever their version")
            self.fmi = int(value)
            return
        if key == "fmus":
            if not isinstance(value, str) or value not in FMU_KINDS:
                raise ScenarioError(f"{origin} experiment.fmus: which build of sewfmu's FMUs "
                                    f"runs, {' or '.join(map(repr, FMU_KINDS))}, got "
                                    f"{short(value)}")
            if self.instances and all(i.fmu in self.fmu_files for i in self.instances.values()):
                raise ScenarioError(f"{origin} experiment.fmus: chooses the build of sewfmu's "
                                    f"own FMUs; {self.source} runs only FMU files of its own")
            self.fmus = str.__str__(value)
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
                                    f"{short(value)}")
            self.accept_error = value
            return
        if key == "record_every":
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ScenarioError(f"{origin} experiment.record_every: must be a whole number "
                                    f">= 1, got {short(value)}")
            self.record_every = value
            return
        if key == "shaft":
            if value not in self.instances or self.instances[value].fmu != "MainShaft":
                shafts = [n for n, i in self.instances.items() if i.fmu == "MainShaft"]
                raise ScenarioError(f"{origin} experiment.shaft: must name a MainShaft instance "
                                    f"({', '.join(shafts) or 'none here'}), got {short(value)}")
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


def _turns(revolutions: float) -> str:
    return f"{revolutions:g} revolution{'' if revolutions == 1 else 's'}"


def _declared_units(fmu_file: Path) -> dict[str, str]:
    """name -> unit of the parameters and inputs of an FMU file (from another tool)."""
    md = model_description(fmu_file, "")
    return {v.name: v.unit or "" for v in md.modelVariables
            if v.causality in ("parameter", "input")}
