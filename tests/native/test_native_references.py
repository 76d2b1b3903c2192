"""Every regression reference is reproduced by the native FMUs: sewfmu's shipped references
(scenarios/references/regression_references/, recorded from the Python FMUs) and the reference
each FMU carries (fmi-ls-ref), checked as `sewfmu references --fmu` checks any FMU."""
import pytest

from sewfmu.components.registry import FMUS
from sewfmu.scenarios.references.reference_check import check


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(FMUS))
def test_the_native_fmu_reproduces_every_reference(native_fmu, name):
    # FMI 2.0: the shipped reference and the carried one (FMI 3.0's carried references are
    # held by tests/native/test_native_fmus.py)
    fmi = 2
    outcomes = check(native_fmu(name, fmi))
    assert len(outcomes) == 2, [o.reference for o in outcomes]
    for outcome in outcomes:
        assert not outcome.deviations, (name, fmi, outcome.deviations)
