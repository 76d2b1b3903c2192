"""A callback of several outputs answers by name (callbacks.Answer): the outputs it names are set,
every other is left as the page has it, and a name that is not one of its outputs is an error,
not an output silently dropped; every output named is a component of the page's layout."""
import json

import pytest

from tests.app.page_requests import answered, click

pytest.importorskip("dash", reason="the extra app (pip install -e '.[app]') is not installed")

import dash  # noqa: E402

from sewfmu.app import callbacks  # noqa: E402
from sewfmu.app.serve import Page, create  # noqa: E402

ME = {"Host": "127.0.0.1:8050", "Origin": "http://127.0.0.1:8050",
      "Content-Type": "application/json"}
ANSWERS = [callbacks.VALUES, callbacks.RUN, callbacks.PLAY, callbacks.SWEEP, callbacks.SWEEP_PLOT]


def test_an_answer_sets_what_it_names_and_leaves_the_rest():
    answer = callbacks.RUN(alert="choose a scenario", progress=0)
    assert list(answer) == list(callbacks.RUN.outputs)
    assert answer["alert"] == "choose a scenario" and answer["progress"] == 0
    assert all(v is dash.no_update for k, v in answer.items() if k not in ("alert", "progress"))


def test_a_name_that_is_not_an_output_is_an_error():
    with pytest.raises(KeyError, match="alret"):
        callbacks.RUN(alret="choose a scenario")


def _ids(component) -> set:
    """The ids of a layout's components, walked through their children."""
    found = set()
    stack = [component]
    while stack:
        c = stack.pop()
        if isinstance(c, (list, tuple)):
            stack.extend(c)
        elif hasattr(c, "to_plotly_json"):
            if isinstance(getattr(c, "id", None), str):     # not the pattern ids (dicts)
                found.add(c.id)
            stack.append(getattr(c, "children", None))
    return found


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    page = Page({"punch_drive": "punch_drive"}, tmp_path_factory.mktemp("runs"))
    app = create(page)
    yield page, app
    page.jobs.shutdown()


def test_every_output_named_is_a_component_of_the_page(page):
    ids = _ids(page[1].layout)
    for answer in ANSWERS:
        missing = {o.component_id for o in answer.outputs.values()} - ids
        assert not missing, missing


def test_a_refused_click_changes_only_the_alert_on_the_page(page):
    """Through Dash itself: the outputs an answer does not name are not in its response."""
    client = page[1].server.test_client()
    dependencies = json.loads(client.get("/_dash-dependencies", headers=ME).data)
    body = click(dependencies, "run", {}, {"scenario": None, "runs": []})
    got = answered(client.post("/_dash-update-component", data=body, headers=ME).data)
    assert got == {"alert": {"children": "choose a scenario"}}
    body = click(dependencies, "sweep-run", {}, {"scenario": "punch_drive", "sweep-param": None})
    got = answered(client.post("/_dash-update-component", data=body, headers=ME).data)
    assert got["sweep-alert"] == {"children": "sweep: choose a parameter to sweep"}
    assert "sweep-rows" not in got           # the points of the last sweep stay on its plot
