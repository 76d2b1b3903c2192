"""A study scenario (`study = "carriage_resonance"` in its file): its analysis's study computed
for the design its instances' parameters set (with --set, a sweep's values, the API's set=), not
co-simulated; its headline figures are its key figures, as a run's are (summary.json, sweeps)."""
from __future__ import annotations

from pathlib import Path

from sewfmu.scenarios.files.outputs import replacing
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import ScenarioError, check_scenario_name
from sewfmu.scenarios.mechanisms.base import Study
from sewfmu.scenarios.runs.results import write_json


def study_of(scenario: Scenario) -> Study:
    return scenario.mechanism.studies[scenario.study]


def given_of(scenario: Scenario, study: Study) -> dict[str, dict]:
    """The design the study is computed for: {role: the values the scenario gives its
    instance's parameters} (the FMU's defaults for the rest)."""
    return {role: dict(scenario.instances[scenario.roles[role]].parameters)
            for role in study.roles if role in scenario.roles}


def study_summary(scenario: Scenario) -> tuple[dict, dict]:
    """(the whole study, its summary: the headline figures and their units)."""
    study = study_of(scenario)
    try:
        data = study.compute(given_of(scenario, study))
    except ValueError as err:         # a design that cannot be assembled, a value out of range
        raise ScenarioError(f"{scenario.name}: {' '.join(str(err).split())}") from None
    headline = study.headline(data)
    return data, {"scenario": scenario.name, "study": scenario.study, **headline,
                  "units": dict(study.units)}


def run_study(scenario: Scenario, out_dir: Path | None, plot: bool = False,
              report: bool = False) -> tuple[dict, dict]:
    """Compute a study scenario and, with out_dir, write study.json (everything), summary.json
    (the headline figures) and, with plot, NAME.png; with report, report.html."""

    study = study_of(scenario)
    data, summary = study_summary(scenario)
    check_scenario_name(scenario.name)      # NAME.png: never a path out of out_dir
    if out_dir is None:
        return data, summary
    with replacing(out_dir) as staging:
        write_json(data, staging / "study.json")
        write_json(summary, staging / "summary.json")
        picture = staging / f"{scenario.name}.png"
        if plot or report:
            study.plot(data, picture)
        if report:
            from sewfmu.scenarios.runs.report import study_report  # only with --report

            study_report(staging / "report.html", scenario.study, study,
                         {k: v for k, v in summary.items() if k in study.units}, picture)
    return data, summary
