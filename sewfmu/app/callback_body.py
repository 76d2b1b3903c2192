"""What a POST to Dash's callback route (/_dash-update-component) must be before Dash reads it:
JSON of at most MAX_DEPTH levels (no NaN), naming one of the page's callbacks, with the inputs,
states and outputs that callback declares, in its order (a list where an input is a pattern of
many), and only its inputs as the ones that changed. Dash itself reads the body as it comes:
`{}`, `null` or inputs given as a string answered 500 with a KeyError or a TypeError on the
server's terminal, and JSON nested 100000 deep a RecursionError. The Guard (guard.py) answers
anything else 400 with `refusal`'s one line; the page's own requests always pass.

The page's own requests: the payload dash-renderer builds (output, outputs, inputs,
changedPropIds, state). Dash's own properties hold what Dash gives them (n_clicks a count, a
location's search a string: PROPERTY_VALUES); a value typed or a store's data may be any JSON,
which the callbacks check."""
from __future__ import annotations

import json

ROUTE = "/_dash-update-component"
MAX_DEPTH = 32          # the page's deepest is about 8 (a run's key figures in the runs store)
_SCALAR = (str, int, float, bool)


def _count(value) -> bool:
    return value is None or (isinstance(value, int) and not isinstance(value, bool)
                             and value >= 0)


# what Dash's own properties hold (a click count, an interval's ticks, an address's parts, a
# switch): any other value is no browser's; a value's or a store's content is the callbacks'
PROPERTY_VALUES = {"n_clicks": (_count, "a count or null"),
                   "n_intervals": (_count, "a count or null"),
                   "search": (lambda v: v is None or isinstance(v, str), "a string or null"),
                   "pathname": (lambda v: v is None or isinstance(v, str), "a string or null"),
                   "hash": (lambda v: v is None or isinstance(v, str), "a string or null"),
                   "disabled": (lambda v: v is None or isinstance(v, bool), "true, false or null")}


class Malformed(ValueError):
    """A body that is not one of the page's callbacks (its one line)."""


def refusal(data: bytes, content_type: str, callbacks: dict) -> str | None:
    """The one line that refuses `data` as a request of one of `callbacks` (Dash's callback_map:
    output -> {inputs, state, ...}), or None for a body Dash may read."""
    try:
        check(data, content_type, callbacks)
    except Malformed as err:
        return f"refused: {err}"
    return None


def check(data: bytes, content_type: str, callbacks: dict) -> dict:
    """The body read as JSON and checked as the module says, or Malformed."""
    if content_type.split(";")[0].strip().lower() != "application/json":
        raise Malformed("a callback's body is JSON, sent as Content-Type: application/json")
    body = _json(data)
    if not isinstance(body, dict):
        raise Malformed(f"a callback's body is a JSON object, got {_kind(body)}")
    output = body.get("output")
    spec = callbacks.get(output) if isinstance(output, str) else None
    if spec is None:
        raise Malformed(f"no callback of this page has the output {_short(output)}")
    inputs = _items(body.get("inputs"), spec["inputs"], "inputs")
    _items(body.get("state", []), spec.get("state", []), "state")
    if not spec.get("no_output"):
        _outputs(body.get("outputs"), output)
    changed = body.get("changedPropIds", [])
    names = {f"{_id_text(i['id'])}.{i['property']}" for item in inputs
             for i in (item if isinstance(item, list) else [item])}
    if not isinstance(changed, list) or not all(isinstance(c, str) and c in names
                                                for c in changed):
        raise Malformed("changedPropIds: a list of the callback's inputs (ID.PROPERTY)")
    return body


def _json(data: bytes):
    """JSON as browsers write it: UTF-8, no NaN or Infinity, at most MAX_DEPTH levels."""
    def no_constant(name):
        raise ValueError(f"{name} is not JSON")
    try:
        body = json.loads(data, parse_constant=no_constant)
    except RecursionError:          # deeper than Python's recursion: far past MAX_DEPTH
        raise Malformed(f"JSON nested more than {MAX_DEPTH} levels deep") from None
    except ValueError as err:       # JSONDecodeError, UnicodeDecodeError, 5000-digit numbers
        raise Malformed(f"the body is not JSON ({_short(err, 120)})") from None
    todo = [(body, 1)]
    while todo:                     # without recursion: its depth is the question
        value, level = todo.pop()
        if level > MAX_DEPTH:
            raise Malformed(f"JSON nested more than {MAX_DEPTH} levels deep")
        if isinstance(value, dict):
            todo.extend((v, level + 1) for v in value.values())
        elif isinstance(value, list):
            todo.extend((v, level + 1) for v in value)
    return body


def _items(given, specs: list, what: str) -> list:
    """A callback's inputs or states as sent: one per declared, each {id, property, value} with
    the declared id and property; a pattern's (an id with ALL) a list of them."""
    if not isinstance(given, list) or len(given) != len(specs):
        raise Malformed(f"{what}: a list of {len(specs)} for this callback, got "
                        f"{_short(given)}")
    for item, spec in zip(given, specs):
        if spec["id"].startswith("{"):          # a pattern: its id a JSON object
            pattern = json.loads(spec["id"])
            for one in item if isinstance(item, list) else [item]:
                _item(one, spec, what)
                if not _matches(one["id"], pattern):
                    raise Malformed(f"{what}: {_short(one['id'])} is not an id of the pattern "
                                    f"{spec['id']}")
        else:
            _item(item, spec, what)
            if item["id"] != spec["id"]:
                raise Malformed(f"{what}: expected {spec['id']}.{spec['property']}, got "
                                f"{_short(item['id'])}")
    return given


def _item(item, spec: dict, what: str) -> None:
    if not isinstance(item, dict) or item.get("property") != spec["property"] or \
            not isinstance(item.get("id"), (str, dict)):
        raise Malformed(f"{what}: expected {{id, property: {spec['property']!r}, value}}, got "
                        f"{_short(item)}")
    holds, wanted = PROPERTY_VALUES.get(spec["property"], (None, ""))
    if holds is not None and not holds(item.get("value")):
        raise Malformed(f"{what}: {spec['property']} is {wanted}, got {_short(item['value'])}")


def _matches(given, pattern: dict) -> bool:
    """A component's id (a dict) is one of a pattern's (ALL, MATCH: any scalar there)."""
    return isinstance(given, dict) and given.keys() == pattern.keys() and all(
        isinstance(given[k], _SCALAR) if isinstance(v, list) else given[k] == v
        for k, v in pattern.items())


def _outputs(given, output: str) -> None:
    """outputs as dash-renderer sends them: one {id, property} for a single output, a list of
    them, in order, for several (`..a.x...b.y..`); a pattern's a list of its components'."""
    parts = output[2:-2].split("...") if output.startswith("..") else [output]
    listed = given if output.startswith("..") else [given]
    if not isinstance(listed, list) or len(listed) != len(parts):
        raise Malformed(f"outputs: the {len(parts)} outputs of {_short(output)}, got "
                        f"{_short(given)}")
    for item, part in zip(listed, parts):
        name, _, prop = part.rpartition(".")
        pattern = name.startswith("{")
        for one in item if isinstance(item, list) and pattern else [item]:
            ok = isinstance(one, dict) and isinstance(one.get("property"), str) and \
                one["property"].split("@")[0] == prop.split("@")[0] and \
                (_matches(one.get("id"), json.loads(name)) if pattern else one.get("id") == name)
            if not ok:
                raise Malformed(f"outputs: expected {part}, got {_short(one)}")


def _id_text(id_) -> str:
    """A component's id as Dash writes it in changedPropIds (dash._utils.stringify_id)."""
    if isinstance(id_, dict):
        return "{" + ",".join(f"{json.dumps(k)}:{json.dumps(id_[k])}" for k in sorted(id_)) + "}"
    return id_


def _kind(value) -> str:
    return {dict: "an object", list: "an array", str: "a string", bool: "true or false",
            type(None): "null"}.get(type(value), "a number")


def _short(value, most: int = 60) -> str:
    """A value sent (JSON) or an error, on one line of at most `most` characters."""
    text = str(value) if isinstance(value, BaseException) else json.dumps(value)
    text = " ".join(text[:4 * most].split())
    return text if len(text) <= most else text[:most - 1] + "…"
