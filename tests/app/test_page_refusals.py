"""The page itself (sewfmu/app/serve.py's app, through Flask's test client: fast) refuses what
another site asks of it, and answers every value it cannot read with the alert's one line,
never a 500: a Run posted from another site starts no job; a 5000-digit number, an offset unit
(10 degC), or anything else the value parser raises on (ValueError, OverflowError, pint's
errors) is the alert that names the value. Over real HTTP: tests/app/test_server_security.py."""
import json

import pytest

import sewfmu
from tests.app.page_requests import answered, click

pytest.importorskip("dash", reason="the extra app (pip install -e '.[app]') is not installed")

from sewfmu.app.serve import Page, create  # noqa: E402

ME = {"Host": "127.0.0.1:8050", "Origin": "http://127.0.0.1:8050",
      "Content-Type": "application/json"}
UPDATE = "/_dash-update-component"


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    page = Page({"punch_drive": "punch_drive"}, tmp_path_factory.mktemp("runs"))
    client = create(page).server.test_client()
    dependencies = json.loads(client.get("/_dash-dependencies", headers=ME).data)
    yield page, client, dependencies
    page.jobs.shutdown()


def _run(page, typed, headers=ME):
    """A click on Run with the values `typed`: (HTTP status, Dash's answer or None)."""
    _, client, dependencies = page
    body = click(dependencies, "run", typed, {"scenario": "punch_drive", "runs": [],
                                              "defaults": {}})
    answer = client.post(UPDATE, data=body, headers=headers)
    return answer.status_code, answered(answer.data) if answer.status_code == 200 else None


def _sweep(page, **fields):
    _, client, dependencies = page
    state = {"scenario": "punch_drive", "defaults": {}, "sweep-param": "shaft.omega0",
             "sweep-from": "100", "sweep-to": "200", "sweep-n": "3"}
    body = click(dependencies, "sweep-run", {}, {**state, **fields})
    answer = client.post(UPDATE, data=body, headers=ME)
    assert answer.status_code == 200, answer.data[:300]
    return answered(answer.data)


ROUTES = [("GET", "/"), ("GET", "/_dash-layout"), ("GET", "/_dash-dependencies"),
          ("GET", "/assets/page.js"), ("GET", "/runs/0123456789abcdef/summary.json"),
          ("GET", "/nothing/here"), ("POST", UPDATE)]


def test_every_route_refuses_a_host_it_was_not_started_for(page):
    _, client, _ = page
    for method, path in ROUTES:
        refused = client.open(path, method=method, headers={**ME, "Host": "evil.example:8050"})
        assert refused.status_code == 403, path
        assert refused.data.startswith(b"refused:") and b"evil.example" in refused.data
        answered_ = client.open(path, method=method, headers={**ME, "Host": "localhost:8050"})
        assert answered_.status_code != 403, path


@pytest.mark.parametrize("foreign", [{"Origin": "http://evil.example"},
                                     {"Origin": "http://evil.example:8050"},
                                     {"Origin": None, "Referer": "http://evil.example/a.html"}])
def test_a_run_posted_from_another_site_starts_no_job_and_one_from_the_page_does(page,
                                                                                 foreign):
    jobs = page[0].jobs
    before = set(jobs._jobs)
    headers = {k: v for k, v in {**ME, **foreign}.items() if v is not None}
    status, _ = _run(page, {"experiment.revolutions": "1"}, headers)
    assert status == 403 and set(jobs._jobs) == before
    status, answer = _run(page, {"experiment.revolutions": "1"})    # the same, from the page
    assert status == 200 and answer["alert"]["children"] == ""
    started = answer["job"]["data"]
    assert set(jobs._jobs) == before | {started}
    jobs.cancel(started)


@pytest.mark.parametrize("text", ["1" * 5000, "1" * 5000 + " rpm", "0x" + "f" * 5000,
                                  "1" * 4301, "9" * 200 + " rpm", "10 degC", "-40 degF",
                                  "1e999 rpm", "fast", "[1, 2]", "\x00", "300 rad/s/s"])
def test_a_value_the_page_cannot_read_is_the_alert_s_one_line_not_a_500(page, text):
    before = set(page[0].jobs._jobs)
    status, answer = _run(page, {"shaft.omega0": text})
    assert status == 200
    alert = answer["alert"]["children"]
    assert alert and "\n" not in alert and len(alert) <= 400 and "shaft.omega0" in alert
    assert answer["job"]["data"] is None and set(page[0].jobs._jobs) == before


@pytest.mark.parametrize("raised", [ValueError("Exceeds the limit (4300 digits) for integer "
                                               "string conversion"),
                                    OverflowError("int too large to convert to float"),
                                    ZeroDivisionError("division by zero"), KeyError("degC"),
                                    RecursionError("maximum recursion depth exceeded")])
def test_whatever_the_value_parser_raises_is_the_alert_naming_the_value(page, monkeypatch,
                                                                        raised):
    """The value parser is another module's (scenarios/format): whatever it raises on a text,
    not only a sewfmu.Error, is the value's one line on the page."""
    real = sewfmu.check

    def check(source, set=None):
        if "1234.5 rpm" in (set or {}).values():
            raise raised
        return real(source, set=set)
    monkeypatch.setattr(sewfmu, "check", check)
    status, answer = _run(page, {"experiment.revolutions": "2", "shaft.omega0": "1234.5 rpm"})
    assert status == 200
    alert = answer["alert"]["children"]
    assert "shaft.omega0 = '1234.5 rpm'" in alert and "experiment.revolutions" not in alert
    assert "not a value sewfmu can read" in alert and "\n" not in alert


@pytest.mark.parametrize("fields, named", [
    ({"sweep-from": "1" * 5000}, "sweep shaft.omega0 from"),
    ({"sweep-n": "9" * 5000}, "sweep shaft.omega0 points"),
    ({"sweep-to": "1e999"}, "shaft.omega0"), ({"sweep-n": "1e3"}, "points"),
    ({"sweep-param": ["shaft.omega0"]}, "choose a parameter"),
    ({"defaults": ["not", "a", "table"], "sweep-from": "x"}, "from and to are numbers")])
def test_a_sweep_s_value_it_cannot_read_is_the_sweep_s_alert(page, fields, named):
    answer = _sweep(page, **fields)
    alert = answer["sweep-alert"]["children"]
    assert named in alert and "\n" not in alert and answer["sweep-job"]["data"] is None


def test_a_callback_that_raises_is_an_alert_and_its_traceback_not_a_500(page, monkeypatch,
                                                                        capfd):
    """A bug (here: the jobs table failing) still answers the click, in the alert."""
    def broken(*_args, **_kwargs):
        raise RuntimeError("the table of jobs broke")
    monkeypatch.setattr(page[0].jobs, "start", broken)
    status, answer = _run(page, {"experiment.revolutions": "1"})
    assert status == 200
    assert "the table of jobs broke" in answer["alert"]["children"]
    assert "a bug in sewfmu" in answer["alert"]["children"]
    assert "RuntimeError" in capfd.readouterr().err
