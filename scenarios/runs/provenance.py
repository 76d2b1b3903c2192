"""What produced a run, as summary.json's "provenance": the scenario and its hash, every
parameter value each instance ran with, the master, sewfmu's version and each FMU's, with its
file and its build (python or native: experiment.fmus)."""
from __future__ import annotations

from pathlib import Path

from sewfmu._version import __version__ as VERSION
from sewfmu.scenarios.cosim.instances import extracted_fmu
from sewfmu.scenarios.fmu_build.native_current import build_of
from sewfmu.scenarios.format.experiment import experiment_of
from sewfmu.scenarios.format.scenario import Scenario


def provenance(scenario: Scenario, fmu_paths: dict[str, Path]) -> dict:
    """What produced a run: the scenario (file and its hash), every parameter value each instance
    ran with (defaults included; `set` marks the scenario's own values), the master and step,
    sewfmu's version and each FMU's version with the hash of the code it carries."""
    described = {fmu: extracted_fmu(Path(path))[1] for fmu, path in fmu_paths.items()}
    instances = {}
    for name, inst in scenario.instances.items():
        declared = [v for v in described[inst.fmu].modelVariables if v.causality == "parameter"]
        instances[name] = {"fmu": inst.fmu, "parameters": {
            v.name: {"value": inst.parameters.get(v.name, _number(v.start)), "unit": v.unit or "1",
                     "set": v.name in inst.parameters}
            for v in declared}}
    return {"scenario": {"name": scenario.name, "source": scenario.source,
                         "sha256": scenario.digest or None},
            "instances": instances, "master": scenario.master, "step": scenario.step,
            **scenario.master_settings(), "experiment": experiment_of(scenario),
            "end_time": scenario.end_time(), "sewfmu": VERSION,
            "fmus": {fmu: md.version for fmu, md in sorted(described.items())},
            "fmi": {fmu: md.fmiVersion for fmu, md in sorted(described.items())},
            "fmu_files": {fmu: str(Path(path).resolve()) for fmu, path in sorted(fmu_paths.items())},
            "fmu_builds": {fmu: build_of(Path(path)) for fmu, path in sorted(fmu_paths.items())}}


def _number(text: str) -> float | int:
    """A start value of the modelDescription as the number it is."""
    value = float(text)
    return int(value) if value.is_integer() and "." not in text and "e" not in text.lower() \
        else value
