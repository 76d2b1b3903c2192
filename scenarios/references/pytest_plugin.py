"""sewfmu's pytest plugin (registered as an entry point: installed, pytest finds it): the fixture
`fmu_reference`, the same check as `sewfmu references --fmu` inside a user's own test suite.

    def test_my_punch(fmu_reference):
        fmu_reference("build/PunchContact.fmu", "refs/")

fails the test with one line per deviating variable (the variable, the first time it leaves the
tolerance, the two values). Without a folder, the FMU is checked against the reference it
carries (fmi-ls-ref; sewfmu's own FMUs also against sewfmu's shipped reference). Record a folder's
references with `sewfmu references --fmu FMU --refs DIR --regenerate`; docs/regression.md.
"""
from __future__ import annotations

import pytest

from sewfmu.scenarios.format.values import ScenarioError
from sewfmu.scenarios.references import reference_check


@pytest.fixture
def fmu_reference():
    def check(fmu, refs=None, rtol: float | None = None, atol: float | None = None) -> None:

        try:
            outcomes = reference_check.check(fmu, refs, rtol, atol)
        except ScenarioError as err:
            pytest.fail(str(err), pytrace=False)
        lines = [str(d) for outcome in outcomes for d in outcome.deviations]
        if lines:
            pytest.fail("\n".join([f"{len(lines)} variables deviate from their references:",
                                   *lines]), pytrace=False)
    return check
