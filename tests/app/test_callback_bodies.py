"""A POST to the page's callback route (/_dash-update-component) that is not one of its
callbacks as dash-renderer sends it is 400 with one line, and Dash never sees it
(sewfmu/app/callback_body.py): `{}`, `null`, `[]`, a number, a string, JSON nested 100000 deep,
no inputs, inputs as a string, `[null]`, an integer changedPropIds, NaN... each answered 500
with a KeyError or a RecursionError's traceback on the server's terminal before. Every
callback's own request passes, and no mutation of one (any part replaced by any JSON value)
gets a 500. Through Flask's test client: fast."""
import copy
import json
import random

import pytest

from tests.app.page_requests import answered, click

pytest.importorskip("dash", reason="the extra app (pip install -e '.[app]') is not installed")

from sewfmu.app.callback_body import MAX_DEPTH, PROPERTY_VALUES  # noqa: E402
from sewfmu.app.guard import HEADERS  # noqa: E402
from sewfmu.app.serve import Page, create  # noqa: E402

ME = {"Host": "127.0.0.1:8050", "Origin": "http://127.0.0.1:8050",
      "Content-Type": "application/json"}
UPDATE = "/_dash-update-component"
STATE = {"scenario": "punch_drive", "runs": [], "defaults": {}, "sweep-param": "shaft.omega0",
         "sweep-from": "100", "sweep-to": "200", "sweep-n": "2"}


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    """The page, its jobs never started (a job's start is recorded instead)."""
    page = Page({"punch_drive": "punch_drive"}, tmp_path_factory.mktemp("runs"))
    started = []
    page.jobs.start = lambda kind, request, folder=None: started.append(kind) or "0" * 16
    client = create(page).server.test_client()
    dependencies = json.loads(client.get("/_dash-dependencies", headers=ME).data)
    yield client, dependencies, started
    page.jobs.shutdown()


def _request_of(dep: dict) -> dict:
    """The request dash-renderer sends for a callback `dep` (/_dash-dependencies' entry): its
    first input changed, a pattern's (ALL) components none."""
    def items(specs):
        return [[] if s["id"].startswith("{") else
                {"id": s["id"], "property": s["property"], "value": None} for s in specs]
    parts = dep["output"][2:-2].split("...") if dep["output"].startswith("..") \
        else [dep["output"]]
    outputs = [dict(zip(("id", "property"), p.rsplit(".", 1))) for p in parts]
    first = dep["inputs"][0]
    return {"output": dep["output"],
            "outputs": outputs if dep["output"].startswith("..") else outputs[0],
            "inputs": items(dep["inputs"]), "state": items(dep["state"]),
            "changedPropIds": [] if first["id"].startswith("{")
            else [f"{first['id']}.{first['property']}"]}


def _post(client, data: bytes, headers=ME):
    return client.post(UPDATE, data=data, headers=headers)


def _run(dependencies) -> dict:
    return json.loads(click(dependencies, "run", {"experiment.revolutions": "1"}, STATE))


def _valued(run: dict, text: str) -> bytes:
    """The Run click with its runs store's data (any JSON, for Dash) written as `text`."""
    run = copy.deepcopy(run)
    store = next(s for s in run["state"] if isinstance(s, dict) and s["id"] == "runs")
    store["value"] = "@value@"
    return json.dumps(run).replace('"@value@"', text).encode()


def _malformed(run: dict) -> dict[str, bytes]:
    deep = 100_000
    return {"{}": b"{}", "null": b"null", "[]": b"[]", "123": b"123", "a string": b'"x"',
            "nested 100000 deep": b"[" * deep + b"]" * deep,
            "objects 100000 deep": b'{"a":' * deep + b"1" + b"}" * deep,
            "no outputs nor inputs": json.dumps({"output": run["output"]}).encode(),
            "no inputs": json.dumps({k: v for k, v in run.items() if k != "inputs"}).encode(),
            "inputs a string": json.dumps({**run, "inputs": "x"}).encode(),
            "inputs [null]": json.dumps({**run, "inputs": [None]}).encode(),
            "inputs [null] * 3": json.dumps({**run, "inputs": [None] * 3}).encode(),
            "changedPropIds a number": json.dumps({**run, "changedPropIds": 5}).encode(),
            "changedPropIds not an input": json.dumps({**run, "changedPropIds":
                                                       ["{bad.n_clicks"]}).encode(),
            "NaN": b'{"output": NaN}', "-Infinity": _valued(run, "-Infinity"),
            "n_clicks a list": json.dumps(run).replace('"value": 1', '"value": [1]', 1)
            .encode(),
            "n_clicks true": json.dumps(run).replace('"value": 1', '"value": true', 1).encode(),
            "an unknown output": json.dumps({**run, "output": "nothing.here"}).encode(),
            "outputs of another callback": json.dumps({**run, "outputs": [
                {"id": "plot", "property": "figure"}]}).encode(),
            "a state of another id": json.dumps({**run, "state": [
                {**run["state"][0], "id": "runs"}, *run["state"][1:]]}).encode(),
            "a value input of another pattern": json.dumps({**run, "state": [
                run["state"][0], [{"id": {"other": "x"}, "property": "value", "value": "1"}],
                *run["state"][2:]]}).encode(),
            "5000 digits": _valued(run, "9" * 5000),
            "not UTF-8": b'{"output": "\xff"}', "empty": b"", "truncated": json.dumps(run)
            .encode()[:-5],
            "a value nested too deeply": _valued(run, "[" * MAX_DEPTH + "]" * MAX_DEPTH)}


@pytest.mark.slow
def test_the_page_s_own_requests_pass(page):
    client, dependencies, _ = page
    for dep in dependencies:
        answer = _post(client, json.dumps(_request_of(dep)).encode())
        assert answer.status_code in (200, 204), (dep["output"], answer.data[:200])
    answer = _post(client, json.dumps(_run(dependencies)).encode())
    assert answer.status_code == 200 and answered(answer.data)["job"]["data"] == "0" * 16


def test_a_value_nested_to_the_limit_passes_and_one_deeper_does_not(page):
    """The request is 3 levels (object, state, one state) around a value: MAX_DEPTH in all."""
    client, dependencies, _ = page
    for levels, code in ((MAX_DEPTH - 3, 200), (MAX_DEPTH - 2, 400)):
        answer = _post(client, _valued(_run(dependencies), "[" * levels + "]" * levels))
        assert answer.status_code == code, levels


def test_each_malformed_body_is_400_in_one_line_and_no_traceback(page, capfd):
    client, dependencies, started = page
    before = len(started)
    for name, data in _malformed(_run(dependencies)).items():
        answer = _post(client, data)
        assert answer.status_code == 400, (name, answer.status_code, answer.data[:200])
        assert answer.data.startswith(b"refused: ") and answer.data.count(b"\n") == 1, name
        assert len(answer.data) < 300, name
        for key, value in HEADERS:
            assert answer.headers.get(key) == value, (name, key)
    for content_type in ("text/plain", "application/x-www-form-urlencoded", ""):
        answer = _post(client, json.dumps(_run(dependencies)).encode(),
                       {**ME, "Content-Type": content_type})
        assert answer.status_code == 400 and b"application/json" in answer.data
    assert len(started) == before                      # no job started by any of them
    err = capfd.readouterr().err
    assert "Traceback" not in err and "Error" not in err, err[-2000:]


def _paths(value, path=()):
    yield path
    if isinstance(value, dict):
        for key, item in value.items():
            yield from _paths(item, (*path, key))
    elif isinstance(value, list):
        for i, item in enumerate(value):
            yield from _paths(item, (*path, i))


def _the_callbacks_value(request, path) -> bool:
    """The path lies in a typed value or a store's data (any JSON: the callbacks' to check,
    sewfmu/app/callbacks.py), not in the request's shape or a Dash property's value."""
    for k, key in enumerate(path):
        if key == "value":
            item = request
            for step in path[:k]:
                item = item[step]
            return item.get("property") not in PROPERTY_VALUES
    return False


def _replaced(value, path, new):
    if not path:
        return new
    value = copy.deepcopy(value)
    inner = value
    for key in path[:-1]:
        inner = inner[key]
    inner[path[-1]] = new
    return value


JSON = [None, 0, -1, 1.5, 1e308, "", "x", "1" * 300, True, [], {}, [None], [[]], {"id": "x"},
        {"id": {"name": "x", "type": "value"}, "property": "value"}, ["x", 1], {"a": {"b": []}}]


def test_no_mutation_of_a_request_is_a_500_or_a_bug(page, capfd):
    """Any part of any callback's request (its shape, a Dash property's value; not a typed
    value nor a store's data, which the callbacks check) replaced by any of a set of JSON
    values: 200 or 400 (not this page's request), never 500, never the alert's "a bug in
    sewfmu". 600 mutations, about a second."""
    client, dependencies, _ = page
    requests = [_request_of(dep) for dep in dependencies] + [
        json.loads(click(dependencies, button, {"experiment.revolutions": "1"}, STATE))
        for button in ("run", "cancel", "sweep-run", "sweep-cancel", "play")]
    chosen = random.Random(45)
    codes = {}
    for _ in range(600):
        request = chosen.choice(requests)
        path = chosen.choice([p for p in _paths(request)
                              if not _the_callbacks_value(request, p)])
        mutated = _replaced(request, path, chosen.choice(JSON))
        answer = _post(client, json.dumps(mutated).encode())
        codes[answer.status_code] = codes.get(answer.status_code, 0) + 1
        assert answer.status_code in (200, 204, 400), (path, mutated, answer.data[:300])
        assert b"a bug in sewfmu" not in answer.data, (path, mutated, answer.data[:600])
    assert codes.get(400, 0) > 100 and codes.get(200, 0) > 0, codes    # both kinds were tried
    assert "Traceback" not in capfd.readouterr().err
