"""Which references an FMU is checked against, and the check: shared by `sewfmu references
--fmu` and the pytest fixture `fmu_reference` (scenarios/references/pytest_plugin.py).

- with a references folder (`refs`): the reference recorded there for the FMU's model;
- without: for one of sewfmu's own FMUs, the reference sewfmu ships (its regression case, the
  baseline a changed model is caught against), and the reference the FMU carries (fmi-ls-ref);
  for any other FMU, the one it carries.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from sewfmu.scenarios.format.fmu_file import model_description
from sewfmu.scenarios.format.values import ScenarioError
from sewfmu.scenarios.references import fmu_reference, regression
from sewfmu.scenarios.references.fmu_reference import Deviation, Reference
from sewfmu.scenarios.references.reference_files import plain_name


@dataclass
class Outcome:
    fmu: Path
    reference: Reference
    got: dict
    deviations: list[Deviation]


def tolerance(value, name: str) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or \
            not math.isfinite(value) or value < 0:
        raise ScenarioError(f"{name} must be a number >= 0, got {value!r}")
    return float(value)


def describe(fmu: Path):
    """The FMU's model description, or one line saying why the file is not an FMU."""
    fmu = Path(fmu)
    if not fmu.is_file():
        raise ScenarioError(f"{fmu}: no such FMU file")
    md = model_description(fmu, "", validate=False)
    if md.coSimulation is None:
        raise ScenarioError(f"{fmu}: {md.modelName} has no co-simulation interface")
    return md


def is_sewfmus(md) -> bool:
    """One of sewfmu's FMUs (its author, as both FMI layers write it, and a model sewfmu has a
    regression case for)."""
    return getattr(md, "author", None) == "sewfmu" and md.modelName in regression.cases()


def references_of(fmu: Path, refs: Path | None = None) -> list[Reference]:
    md = describe(fmu)
    if refs is not None:
        # the modelName names the files read from refs: a plain name, or `../..` would read
        # another folder's files as this FMU's reference
        plain_name(md.modelName, fmu)
        found = fmu_reference.read_cross_check(Path(refs), md.modelName)
        if found is None:
            raise ScenarioError(f"{fmu}: no reference for {md.modelName} in {refs} (record one "
                                f"with `sewfmu references --fmu {fmu} --refs {refs} "
                                f"--regenerate`)")
        return [found]
    found = []
    shipped = fmu_reference.read_cross_check(regression.REFERENCE_DIR, md.modelName) \
        if is_sewfmus(md) else None
    if shipped is not None:
        found.append(shipped)
    carried = fmu_reference.read_carried(Path(fmu))
    if carried is not None:
        found.append(carried)
    if not found:
        raise ScenarioError(f"{fmu}: {md.modelName} carries no reference (fmi-ls-ref) and is "
                            f"not one of sewfmu's: give --refs DIR (record one there with "
                            f"--regenerate)")
    return found


def check(fmu: Path, refs: Path | None = None, rtol: float | None = None,
          atol: float | None = None) -> list[Outcome]:
    rtol, atol = tolerance(rtol, "--rtol"), tolerance(atol, "--atol")
    outcomes = []
    for reference in references_of(Path(fmu), refs):
        got, deviations = fmu_reference.run_and_compare(
            Path(fmu), reference, rtol, fmu_reference.DEFAULT_ATOL if atol is None else atol)
        outcomes.append(Outcome(Path(fmu), reference, got, deviations))
    return outcomes


def record(fmu: Path, refs: Path) -> Path:
    """Record the FMU's reference into refs: its DefaultExperiment, or for one of sewfmu's FMUs
    its regression case (inputs that make it work hard)."""
    md = describe(fmu)
    shipped = regression.REFERENCE_DIR.resolve()
    if Path(refs).resolve() == shipped or shipped in Path(refs).resolve().parents:
        raise ScenarioError(f"--refs {refs}: that is sewfmu's own references folder; record "
                            f"into a folder of yours (sewfmu's are rewritten by `sewfmu "
                            f"references --regenerate` alone)")
    experiment = regression.experiment_of(regression.cases()[md.modelName]) \
        if is_sewfmus(md) else None
    return fmu_reference.record(Path(fmu), Path(refs), experiment, model=md.modelName)
