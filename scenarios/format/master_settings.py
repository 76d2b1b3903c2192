"""Each master's settings, typed: the keys it reads from [experiment] besides the step, with their
defaults and the ranges it honours. The scenario format validates a file's values here, the
provenance and sewfmu's SSP annotation write what the master used (dataclasses.asdict), and the
algorithm (scenarios/cosim/algorithms/) reads them.

This module imports nothing of sewfmu's, so that the format and the algorithms can both use it.
"""
from __future__ import annotations

from dataclasses import dataclass, fields
from typing import ClassVar


class SettingError(ValueError):
    """A setting the master cannot honour; the message starts with the key."""


def _check_tolerance(settings) -> None:
    low, high = settings.TOLERANCES
    if not low <= settings.tolerance <= high:
        raise SettingError(f"experiment.tolerance = {settings.tolerance:g}: the "
                           f"{settings.master} master honours tolerances from {low:g} to "
                           f"{high:g}")


@dataclass(frozen=True)
class JacobiSettings:
    master: ClassVar[str] = "jacobi"


@dataclass(frozen=True)
class GaussSeidelSettings:
    master: ClassVar[str] = "gauss-seidel"


@dataclass(frozen=True)
class IterativeSettings:
    master: ClassVar[str] = "iterative"
    TOLERANCES: ClassVar[tuple[float, float]] = (1e-12, 1e-2)
    ACCELERATIONS: ClassVar[tuple[str, ...]] = ("aitken", "iqn-ils", "none")
    tolerance: float = 1e-6          # relative agreement of the exchanged values
    acceleration: str = "aitken"     # of the passes of a step

    def __post_init__(self):
        _check_tolerance(self)
        if self.acceleration not in self.ACCELERATIONS:
            raise SettingError(f"experiment.acceleration = {self.acceleration!r}: one of "
                               f"{', '.join(self.ACCELERATIONS)}")


@dataclass(frozen=True)
class AdaptiveSettings:
    master: ClassVar[str] = "adaptive"
    TOLERANCES: ClassVar[tuple[float, float]] = (1e-8, 1e-2)
    tolerance: float = 1e-5          # local error of the exchanged signals / their amplitude

    def __post_init__(self):
        _check_tolerance(self)


SETTINGS = {cls.master: cls for cls in (JacobiSettings, GaussSeidelSettings, IterativeSettings,
                                        AdaptiveSettings)}
MASTER_NAMES = tuple(SETTINGS)
ACCELERATIONS = IterativeSettings.ACCELERATIONS


def settings_for(master: str, given: dict):
    """The master's settings from the keys given (those it has no field for are ignored: a
    tolerance means nothing to Jacobi)."""
    cls = SETTINGS[master]
    return cls(**{f.name: given[f.name] for f in fields(cls) if given.get(f.name) is not None})


def default_tolerance(master: str) -> float | None:
    return getattr(SETTINGS[master], "tolerance", None)
