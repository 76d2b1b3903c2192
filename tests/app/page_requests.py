"""A click on the page as the browser posts it to Dash (/_dash-update-component), built from the
page's own /_dash-dependencies, so that a test can send it through Flask's test client or over
real HTTP with headers of its choosing."""
import json

VALUE = '{"name":["ALL"],"type":"value"}'     # the value inputs' pattern id, as Dash lists it


def click(dependencies: list, button: str, typed: dict, state: dict) -> bytes:
    """The JSON body of a click on `button` (its n_clicks 1): the value inputs `typed`
    ({name: text}), the other states from `state` by id (None where not given)."""
    dep = next(d for d in dependencies if any(i["id"] == button for i in d["inputs"]))
    outputs = [dict(zip(("id", "property"), o.rsplit(".", 1)))
               for o in dep["output"].strip(".").split("...")]
    inputs = [{"id": i["id"], "property": i["property"], "value": 1 if i["id"] == button else None}
              for i in dep["inputs"]]
    states = []
    for s in dep["state"]:
        if s["id"] == VALUE:
            states.append([{"id": {"name": n, "type": "value"}, "property": s["property"],
                            "value": t if s["property"] == "value" else
                            {"name": n, "type": "value"}} for n, t in typed.items()])
        else:
            states.append({"id": s["id"], "property": s["property"],
                           "value": state.get(s["id"])})
    return json.dumps({"output": dep["output"], "outputs": outputs, "inputs": inputs,
                       "changedPropIds": [f"{button}.n_clicks"], "state": states}).encode()


def answered(data: bytes) -> dict:
    """{component id: {property: value}} of Dash's answer, the side updates (set_props) too."""
    body = json.loads(data)
    out = dict(body.get("response", {}))
    for key, props in (body.get("sideUpdate") or {}).items():
        out.setdefault(key, {}).update(props)
    return out
