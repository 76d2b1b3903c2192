"""The analyses: one module per mechanism, each declaring what sewfmu knows of it in one
`MECHANISM` descriptor: the roles its scenarios bind, its key figures with their units, the
animation that draws it, whether the monolithic solution solves it, its studies, the regression
cases of its FMUs. Everything that
lists mechanisms (scenario binding, summaries, sweeps, reports, animations, studies, the SSP
import's guess of an analysis) reads the descriptors found here; a new mechanism's module in
this folder is found without being listed anywhere.

An analysis names the roles it needs, each played by an instance of one FMU type (the punch
analysis: a shaft, a linkage and a punch). A scenario binds its instances to the roles in its
`roles` table, or leaves a role to be found by FMU type where exactly one instance has it; so
instance names are the user's choice.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

from sewfmu.errors import Error, ScenarioError


@dataclass(frozen=True)
class Study:
    """An evaluation of a model over parameter sets (not a co-simulation): `compute(given)`
    returns the whole study for the design `given` sets ({role: {parameter: value}}, the
    scenario's values of the instances that play `roles`; {} is the defaults), `plot(study,
    path)` draws it, `headline(study)` its headline figures, numbers whose units are `units`."""
    description: str
    compute: Callable[[dict], dict]
    plot: Callable[[dict, object], None]
    headline: Callable[[dict], dict]
    units: dict[str, str] = field(default_factory=dict)
    roles: tuple[str, ...] = ()


@dataclass(frozen=True)
class RegressionCase:
    """How one FMU runs alone for its regression reference (scenarios/references/regression.py): until
    `stop` at communication steps of `step`, its inputs `inputs(t)` (name -> array over the
    time grid t; None for an FMU without inputs), compared within `rel_tol`. The inputs come
    from the models of what drives the FMU in a machine, so that it works where it works hard."""
    stop: float
    step: float
    inputs: Callable[[object], dict] | None = None
    rel_tol: float = 1e-9


def shaft_at(omega: float) -> Callable[[object], dict]:
    """The inputs a linkage takes from a shaft turning at a constant omega [rad/s]."""
    import numpy as np  # numpy: not at `import sewfmu`

    return lambda t: {"phi": omega * t, "omega": np.full_like(t, omega),
                      "epsilon": np.zeros_like(t)}


class Mechanism:
    """One mechanism's host side, behind one interface (the shape of scipy's OdeSolver: the base
    holds what every mechanism shares, each subclass declares only its own). A module of this
    package holds one subclass and its one instance, `MECHANISM`; the scenario resolves it once,
    when it loads (`Scenario.mechanism`), and everything else asks the scenario."""
    name: str = ""                          # the scenario's `analysis`
    roles: dict[str, str] = {}              # role -> the FMU type that plays it
    figures: dict[str, str] = {}            # key figure -> unit (summary.json, sweeps, reports)
    # its figures are read from positions the FMUs give exactly at each communication point (a
    # linkage's kinematics): no coupling error to estimate (runs/accuracy.py)
    kinematic: bool = False
    studies: dict[str, Study] = {}
    # FMU type -> its regression case, for the FMUs this mechanism brings (the shared MainShaft's
    # is scenarios/references/regression.py's)
    regression: dict[str, RegressionCase] = {}
    # its drawing (`Scene(result)`: points, chains, draw) for the GIF and the page, or None
    Scene: type | None = None

    def summary_of_run(self, result) -> dict:
        """The key figures of a run (its last whole revolution)."""
        raise NotImplementedError

    def plot(self, curves, path, title: str) -> None:
        """The run's figure: `curves` are (label, result) pairs drawn over each other."""
        raise NotImplementedError

    def monolithic_figures(self, scenario, rtol: float | None = None) -> tuple[dict, float]:
        """The key figures of the same physics solved as one ODE, and the seconds it took."""
        raise NotImplementedError(f"the {self.name} mechanism has no monolithic solution")

    @property
    def monolithic(self) -> bool:
        """Whether it is solved as one ODE (`sewfmu compare`, the report)."""
        return type(self).monolithic_figures is not Mechanism.monolithic_figures

    @property
    def animated(self) -> bool:
        return self.Scene is not None

    def figure_units(self, study: str | None = None) -> dict[str, str]:
        """The units of its key figures, or of its study's headline figures."""
        return dict(self.studies[study].units if study else self.figures)

    def bind(self, fmu_of: dict[str, str], given: dict[str, str]) -> dict[str, str]:
        """role -> instance name: the `given` bindings, checked against the instances' FMU
        types (`fmu_of`: instance -> FMU), the others found by FMU type."""
        unknown = [role for role in given if role not in self.roles]
        if unknown:
            raise RoleError(f"roles.{unknown[0]}: the {self.name} analysis has no role "
                            f"{unknown[0]!r} (its roles: {', '.join(self.roles)})")
        bound = {}
        for role, fmu in self.roles.items():
            if role in given:
                name = given[role]
                if name not in fmu_of:
                    raise RoleError(f"roles.{role}: no instance {name!r} "
                                    f"(instances: {', '.join(fmu_of)})")
                if fmu_of[name] != fmu:
                    raise RoleError(f"roles.{role}: {name!r} is an instance of {fmu_of[name]}, "
                                    f"but the {role} of the {self.name} analysis is a {fmu}")
                bound[role] = name
                continue
            candidates = [name for name, kind in fmu_of.items() if kind == fmu]
            if len(candidates) != 1:
                found = (f"instances {', '.join(repr(c) for c in candidates)} are all {fmu}"
                         if candidates else f"no instance is a {fmu}")
                raise RoleError(f"the {self.name} analysis needs its {role} ({fmu}): {found}; "
                                f"name it in the scenario's roles table")
            bound[role] = candidates[0]
        return bound

    # one instance per mechanism: a copied or pickled scenario (a sweep's worker) holds the same
    def __deepcopy__(self, memo):
        return self

    def __reduce__(self):
        return "MECHANISM"            # pickled as the module's own instance, by reference

    def __repr__(self) -> str:
        return f"<mechanism {self.name}>"


# what a summary says of the run itself rather than of the mechanism
RUN_KEYS = ("scenario", "master", "step", "stop_time", "provenance", "units", "runs", "compare",
            "coupling_error", "study")


def figures_of(summary: dict) -> dict:
    """A summary's key figures, with the master's counts and the wall time: what `sewfmu run`
    prints, a sweep's row holds and a cross-check compares."""
    return {k: v for k, v in summary.items() if k not in RUN_KEYS}


class RoleError(Error, ValueError):
    """A mechanism that cannot be bound to a scenario's instances."""


class MissingRecord(ScenarioError, KeyError):
    """A figure or a picture needs a column the run did not record (a ScenarioError: the
    scenario's `record` left it out)."""

    def __str__(self) -> str:
        return self.args[0]


def column(result, role: str, variable: str):
    """The recorded column of the instance that plays `role` in the result's scenario."""
    name = f"{result.scenario.roles[role]}.{variable}"
    try:
        return result[name]
    except KeyError:
        raise MissingRecord(f"{result.scenario.name}: this needs {name}, which the run did not "
                            f"record (add it to the scenario's record list, or leave record out "
                            f"to record every output)") from None


def parameters(result, role: str) -> dict:
    """The parameter values the scenario gave the instance that plays `role`."""
    return result.scenario.instances[result.scenario.roles[role]].parameters


class RunTooShort(Error, ValueError):
    """A run that does not hold one whole revolution of the shaft to read figures from."""


def whole_revolution(phi_end: float) -> tuple[float, float]:
    """The crank angles (start, end) of the last whole revolution up to phi_end: from one
    setup position (φ a multiple of 2π, where every run starts) to the next. A run that ends
    between two (a stop time that is not a whole number of turns) is read up to the last one
    it passed, so that angles within the revolution mean what they mean in the paper."""
    turns = math.floor(phi_end / (2 * math.pi) + 1e-9)
    if turns < 1:
        raise RunTooShort(f"the run turns the shaft {phi_end / (2 * math.pi):.4g} revolutions: "
                          f"its key figures are read from the last whole revolution; run at "
                          f"least one (experiment.revolutions = 1 or a longer stop_time)")
    end = 2 * math.pi * turns
    return end - 2 * math.pi, end


def last_revolution(result):
    """Mask of the samples in the shaft's last whole revolution (one stitch): the window every
    analysis reads its key figures from."""
    phi = column(result, "shaft", "phi")
    start, end = whole_revolution(float(phi[-1]))
    return (phi >= start - 1e-9) & (phi <= end + 1e-9)
