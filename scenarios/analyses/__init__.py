"""The analyses: key figures, plots and studies, one module per mechanism.

An analysis names the roles it needs, each played by an instance of one FMU type (the punch
analysis: a shaft, a linkage and a punch). A scenario binds its instances to the roles in its
`roles` table, or leaves a role to be found by FMU type where exactly one instance has it; so
instance names are the user's choice. The modules themselves (numpy, matplotlib) are imported
when first used.
"""
from __future__ import annotations

import importlib
import math
from types import ModuleType

# analysis -> role -> the FMU type that plays it
ROLES: dict[str, dict[str, str]] = {
    "punch": {"shaft": "MainShaft", "linkage": "PunchLinkage", "punch": "PunchContact"},
    "punch_split": {"shaft": "MainShaft", "linkage": "PunchLinkage", "body": "PunchBody",
                    "fabric": "Fabric"},
    "carriage": {"shaft": "MainShaft", "drive": "CarriageDrive", "carriage": "CarriageModal"},
    "feed": {"shaft": "MainShaft", "feed": "FeedLinkage"},
    "takeup": {"shaft": "MainShaft", "takeup": "TakeupLinkage"},
}


class RoleError(ValueError):
    """An analysis that cannot be bound to a scenario's instances."""


def bind(analysis: str, fmu_of: dict[str, str], given: dict[str, str]) -> dict[str, str]:
    """role -> instance name for `analysis`: the `given` bindings, checked against the
    instances' FMU types (`fmu_of`: instance -> FMU), the others found by FMU type."""
    if analysis not in ROLES:
        raise RoleError(f"unknown analysis {analysis!r} (known: {', '.join(ROLES)})")
    wanted = ROLES[analysis]
    unknown = [role for role in given if role not in wanted]
    if unknown:
        raise RoleError(f"roles.{unknown[0]}: the {analysis} analysis has no role "
                        f"{unknown[0]!r} (its roles: {', '.join(wanted)})")
    bound = {}
    for role, fmu in wanted.items():
        if role in given:
            name = given[role]
            if name not in fmu_of:
                raise RoleError(f"roles.{role}: no instance {name!r} "
                                f"(instances: {', '.join(fmu_of)})")
            if fmu_of[name] != fmu:
                raise RoleError(f"roles.{role}: {name!r} is an instance of {fmu_of[name]}, but "
                                f"the {role} of the {analysis} analysis is a {fmu}")
            bound[role] = name
            continue
        candidates = [name for name, kind in fmu_of.items() if kind == fmu]
        if len(candidates) != 1:
            found = (f"instances {', '.join(repr(c) for c in candidates)} are all {fmu}"
                     if candidates else f"no instance is a {fmu}")
            raise RoleError(f"the {analysis} analysis needs its {role} ({fmu}): {found}; "
                            f"name it in the scenario's roles table")
        bound[role] = candidates[0]
    return bound


def module(analysis: str) -> ModuleType:
    """The module of an analysis (summary_of_run, plot, FIGURES, its studies)."""
    if analysis not in ROLES:
        raise RoleError(f"unknown analysis {analysis!r} (known: {', '.join(ROLES)})")
    return importlib.import_module(f"{__name__}.{analysis}")


def column(result, role: str, variable: str):
    """The recorded column of the instance that plays `role` in the result's scenario."""
    return result[f"{result.scenario.roles[role]}.{variable}"]


def parameters(result, role: str) -> dict:
    """The parameter values the scenario gave the instance that plays `role`."""
    return result.scenario.instances[result.scenario.roles[role]].parameters


class RunTooShort(ValueError):
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
