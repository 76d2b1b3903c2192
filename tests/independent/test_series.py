"""The recorded series against the independent solution at the recorded crank angles: a phase
offset inside a linkage leaves every extremum-type figure unchanged (a swing, an extent, a
peak), so the positions themselves are compared here (tests/independent/, no sewfmu code)."""
import numpy as np

import sewfmu
from tests.independent import feed, takeup


def test_take_up_eye_follows_the_independent_path_at_every_recorded_angle():
    s = sewfmu.run("takeup").series[-200:]
    E, V, _ = takeup.path(list(s["shaft.phi"]))
    assert np.allclose(s["takeup.E_z"], E[:, 0], rtol=0, atol=1e-9)
    assert np.allclose(s["takeup.E_x"], E[:, 1], rtol=0, atol=1e-9)
    assert np.allclose(s["takeup.E_vz"], V[:, 0], rtol=1e-7, atol=1e-9)


def test_feed_dog_follows_the_independent_path_at_every_recorded_angle():
    s = sewfmu.run("feed").series[-200:]
    model = feed.Feed()
    phis = list(s["shaft.phi"])
    m = np.array([model.joints(q, phi)["M"] for q, phi in zip(model.sweep(phis), phis)])
    assert np.allclose(s["feed.M_x"], m[:, 0], rtol=0, atol=1e-9)
    assert np.allclose(s["feed.M_y"], m[:, 1], rtol=0, atol=1e-9)
