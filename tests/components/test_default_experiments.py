"""Every sewfmu FMU run alone in fmpy's simulate_fmu with its defaults (DefaultExperiment, start
values) does what docs/fmi.md says it does: it ends at its stop time, the shaft turns once, the
punch follows the slider down and stops short of the fabric with physical spring forces (no
contact: run alone its extrapolated slider would press on to 190 N), the carriage moves."""
import math

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

NAMES = ["CarriageDrive", "CarriageModal", "Fabric", "FeedLinkage", "MainShaft", "PunchBody",
         "PunchContact", "PunchLinkage", "TakeupLinkage"]


@pytest.fixture(scope="module")
def defaults(fmu_paths):
    """name -> (DefaultExperiment, simulate_fmu's result with nothing given)."""
    return {name: (read_model_description(str(fmu_paths[name])).defaultExperiment,
                   simulate_fmu(str(fmu_paths[name])))
            for name in NAMES}


@pytest.mark.parametrize("name", NAMES)
def test_each_default_experiment_runs_to_its_stop_time(defaults, name):
    experiment, r = defaults[name]
    assert r["time"][-1] == pytest.approx(float(experiment.stopTime), rel=1e-9)
    for column in r.dtype.names:
        assert np.all(np.isfinite(r[column].astype(float))), column


def test_the_shaft_turns_once(defaults):
    _, r = defaults["MainShaft"]
    assert r["phi"][-1] == pytest.approx(2 * math.pi, rel=1e-6)


@pytest.mark.parametrize("name", ["PunchContact", "PunchBody"])
def test_the_punch_follows_the_slider_down_and_stops_short_of_the_fabric(defaults, name):
    # docs/fmi.md: 13.5 ms, down to about 0.2 mm above the fabric, before it lands
    experiment, r = defaults[name]
    assert float(experiment.stopTime) == pytest.approx(0.0135)
    assert r["y"][0] == pytest.approx(4.5e-3)
    assert 0.0 < r["y"][-1] < 0.5e-3 and np.all(r["y"] > 0.0)
    # the spring forces stay those of the mechanism (tens of newtons), not the 190 N an
    # extrapolated slider would press with by 20 ms
    assert np.max(np.abs(r["F1"])) < 50.0 and np.max(np.abs(r["F3"])) < 80.0
    if name == "PunchContact":
        assert not np.any(r["contact"]) and np.all(r["F2"] == 0.0)


def test_the_fabric_ends_before_the_punch_lands_on_it(defaults):
    _, r = defaults["Fabric"]
    assert not np.any(r["contact"]) and np.all(r["F2"] == 0.0)


def test_the_carriage_moves(defaults):
    _, drive = defaults["CarriageDrive"]
    _, modal = defaults["CarriageModal"]
    assert drive["x"][-1] > 0.0                     # three stitches stepped
    assert np.max(np.abs(modal["U2"])) > 0.0        # the response to the opening jerk
