"""A value the page's Run or sweep would have a process refuse is refused before any process
starts (docs/app.md: "a bad value is its one line ... and nothing runs"): every point of a sweep
is checked as a run checks its values (sewfmu.check: the declared range, what the FMU refuses,
the run's size; sewfmu/app/values.check_points, asked by the table of jobs), and a Run's
experiment size by sewfmu.check itself. Before, a sweep from 0 or to 2001 rad/s of shaft.omega0
(declared (0, 2000]) started a job that ended in "error", and a Run of 1e9 revolutions started
a process that stopped with "more than the 1e+08 a run may take". Through Flask's test client:
fast, no job's process started."""
import json

import pytest

from tests.app.page_requests import answered, click

pytest.importorskip("dash", reason="the extra app (pip install -e '.[app]') is not installed")

from sewfmu.app.serve import Page, create  # noqa: E402
from sewfmu.app.values import check_points  # noqa: E402

ME = {"Host": "127.0.0.1:8050", "Origin": "http://127.0.0.1:8050",
      "Content-Type": "application/json"}
UPDATE = "/_dash-update-component"
SWEEP = {"scenario": "punch_drive", "defaults": {}, "sweep-param": "shaft.omega0",
         "sweep-from": "100", "sweep-to": "200", "sweep-n": "3"}


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    page = Page({"punch_drive": "punch_drive"}, tmp_path_factory.mktemp("runs"))
    client = create(page).server.test_client()
    dependencies = json.loads(client.get("/_dash-dependencies", headers=ME).data)
    yield page, client, dependencies
    page.jobs.shutdown()


def _click(page, button, typed, state, alert):
    _, client, dependencies = page
    answer = client.post(UPDATE, data=click(dependencies, button, typed, state), headers=ME)
    assert answer.status_code == 200, answer.data[:300]
    got = answered(answer.data)
    assert got["job" if button == "run" else "sweep-job"]["data"] is None
    assert page[0].jobs._jobs == {}            # no job, so no process of one
    line = got[alert]["children"]
    assert line and "\n" not in line
    return line


@pytest.mark.parametrize("fields, named", [
    ({"sweep-from": "0"}, "shaft.omega0 = 0"), ({"sweep-to": "2001"}, "shaft.omega0 = 2001"),
    ({"sweep-from": "-5", "sweep-to": "5"}, "shaft.omega0 = -5"),
    ({"sweep-from": "1999", "sweep-to": "2000.5", "sweep-n": "4"}, "shaft.omega0 = 2000.5"),
    ({"sweep-param2": "experiment.revolutions", "sweep-from2": "1", "sweep-to2": "1e9",
      "sweep-n2": "2"}, "experiment.revolutions = 1e+09"),
    ({"sweep-param2": "experiment.step", "sweep-from2": "1e-12", "sweep-to2": "1e-4",
      "sweep-n2": "2"}, "experiment.step = 1e-12")])
def test_a_sweep_with_a_bad_point_starts_nothing_and_names_it(page, fields, named):
    line = _click(page, "sweep-run", {}, {**SWEEP, **fields}, "sweep-alert")
    assert line.startswith(f"sweep point {named}") or f", {named}" in line, line


@pytest.mark.parametrize("typed, says", [
    ({"experiment.revolutions": "1e9"}, "may take"), ({"experiment.step": "1e-12"}, "may take"),
    ({"experiment.revolutions": "200000"}, "may take"),
    ({"experiment.step": "1"}, "longer than the run")])
def test_a_run_too_large_starts_nothing(page, typed, says):
    line = _click(page, "run", typed, {"scenario": "punch_drive", "runs": [], "defaults": {}},
                  "alert")
    assert says in line, line


def test_every_point_is_checked_not_only_the_ends():
    """A grid whose ends are good and whose middle is not (the sweep's own values, as a
    second parameter's list may give): the middle point is named."""
    with pytest.raises(Exception, match="shaft.omega0 = 3000"):
        check_points("punch_drive", {}, {"shaft.omega0": [100.0, 3000.0, 200.0]})
    check_points("punch_drive", {"experiment.revolutions": "2"},
                 {"shaft.omega0": [100.0, 1999.0], "experiment.step": [1e-4, 2.5e-4]})
