"""The mechanisms' host side: one module per mechanism, each a subclass of base.Mechanism with
its one instance `MECHANISM`: the roles its scenarios bind, its key figures with their units, its
plots, its drawing, its studies, its monolithic solution, the regression cases of its FMUs.
animation.py writes the GIF of any mechanism that draws itself; sampling.py evaluates the
models over arrays of crank angles.

A scenario resolves its mechanism once, when it loads (`Scenario.mechanism`, by its `analysis`
name); the registry below is asked by name only there, and by what goes over every mechanism
(the regression references, the SSP import's guess, the list of studies). A new mechanism's
module in this folder is found without being listed anywhere.
"""
from __future__ import annotations

import functools
import importlib
import pkgutil

from sewfmu.components.parameters import did_you_mean
from sewfmu.scenarios.mechanisms.base import Mechanism, RoleError, Study

SHARED = ("base", "animation", "sampling")        # the modules every mechanism uses


@functools.cache
def _names() -> tuple[str, ...]:
    """The mechanisms' modules: a listing of the folder, nothing imported."""
    return tuple(info.name for info in pkgutil.iter_modules(__path__)
                 if not info.ispkg and info.name not in SHARED)


@functools.cache
def _mechanism_of(name: str) -> Mechanism:
    return importlib.import_module(f"{__name__}.{name}").MECHANISM


def mechanism(name: str) -> Mechanism:
    """One mechanism by its analysis name; only its own module is imported (a run of the punch
    drive does not load the carriage's, the feed's and the take-up's models)."""
    known = _names()
    if name not in known:
        raise RoleError(f"unknown analysis {name!r}{did_you_mean(name, known)} "
                        f"(known: {', '.join(known)})")
    return _mechanism_of(name)


def mechanisms() -> dict[str, Mechanism]:
    """Every mechanism by name."""
    return {name: _mechanism_of(name) for name in _names()}


def studies() -> dict[str, tuple[str, Study]]:
    """Every mechanism's studies: study name -> (analysis, study)."""
    return {name: (analysis, study) for analysis, m in mechanisms().items()
            for name, study in m.studies.items()}
