"""The page's parts, top to bottom: the scenario and its values, Run with its progress and its
alert, the key figures, the plots and the mechanism, the table of runs, the sweep panel. The
hooks tests use: each value's input is named (and aria-labelled, assets/page.js) `instance.
parameter`; each key figure's element carries data-figure; the plots data-view="plot", the
mechanism data-view="animation"."""
from __future__ import annotations

from dash import dcc, html

from sewfmu.app.values import inputs_of

POLL_MS = 500            # how often a running job's progress is asked for
TICK_MS = 250            # the animation's frame time when playing
FRAME_DEG = 10           # the animation's frames: every 10° of the last revolution


def page(choices: list[str], first: dict) -> html.Div:
    """The page, the first scenario's values in it (callbacks.values_of_choice, by the names of
    callbacks.VALUES), so that it shows them without a round trip."""
    cells, defaults, description = first["values"], first["defaults"], first["description"]
    numeric = first["sweep_choices"]
    return html.Div(className="page", children=[
        dcc.Location(id="url", refresh=False),
        html.Header([html.H1("sewfmu"), html.Span("set a mechanism's values, run, watch it "
                                                  "move, compare runs", className="lede")]),
        html.Section(className="panel", children=[
            html.Label("scenario", htmlFor="scenario", className="label"),
            dcc.Dropdown(id="scenario", options=[{"label": c, "value": c} for c in choices],
                         value=choices[0] if choices else None, clearable=False),
            html.Div(description, id="description", className="meaning"),
            html.Details(open=True, children=[
                html.Summary("values (a number in the unit shown, or with its unit: "
                             "\"955 rpm\")"),
                html.Div(cells, id="values", className="values")]),
            dcc.Store(id="defaults", data=defaults),
            html.Div(className="actions", children=[
                html.Button("Run", id="run", className="primary"),
                html.Button("Cancel", id="cancel"),
                html.Progress(id="progress", max=1, value=0),
                html.Span(id="status", className="status", role="status")]),
            html.Div(id="alert", role="alert", className="alert"),
        ]),
        dcc.Store(id="job"), dcc.Store(id="runs", data=[]), dcc.Store(id="ticked", data=[]),
        dcc.Interval(id="poll", interval=POLL_MS, disabled=True),
        html.Section(className="panel", children=[
            html.H2("key figures", id="figures-title"),
            html.Div(figures(None), id="figures", className="figures")]),
        html.Div(className="views", children=[
            html.Section(className="panel", **{"data-view": "plot"}, children=[
                html.H2("recorded series"),
                dcc.Dropdown(id="series", multi=True, placeholder="choose series to plot"),
                dcc.Graph(id="plot", config={"displaylogo": False},
                          className="graph")]),
            html.Section(className="panel", **{"data-view": "animation"}, children=[
                html.H2("the mechanism moving"),
                dcc.Graph(id="mechanism", config={"displaylogo": False},
                          className="graph"),
                html.Div(className="actions", children=[
                    html.Button("Play", id="play"),
                    html.Div(className="slider", children=dcc.Slider(
                        id="angle", min=0, max=360 - FRAME_DEG, step=FRAME_DEG, value=0,
                        marks={d: f"{d}°" for d in range(0, 360, 90)}, updatemode="drag",
                        allow_direct_input=False))]),
                dcc.Interval(id="tick", interval=TICK_MS, disabled=True)])]),
        html.Section(className="panel", children=[
            html.H2("runs"),
            html.P("tick runs to overlay them on the plots; the last ticked one moves",
                   className="meaning"),
            html.Div(html.P("no runs yet", className="meaning"), id="table",
                     className="table")]),
        sweep_panel(numeric),
    ])


def value_inputs(source: str) -> tuple[list, dict]:
    """The inputs of a scenario's values, and their texts as the scenario has them."""
    rows = inputs_of(source)
    cells = []
    for row in rows:
        hint = " ".join(p for p in (row["unit"] and f"[{row['unit']}]", row["range"]) if p)
        # three components a value, not five: the page's script does work for each component
        # at every update (a run's progress among them)
        cells.append(html.Div(className="value", **{"data-param": row["name"]}, children=[
            html.Label(f"{row['name']} {hint}".strip(), title=row["meaning"]),
            dcc.Input(id={"type": "value", "name": row["name"]}, name=row["name"], type="text",
                      value=row["value"], debounce=False, autoComplete="off",
                      className="input")]))
    return cells, {row["name"]: row["value"] for row in rows}


def figures(entry: dict | None) -> list:
    """A run's key figures: each its name and, in the element with data-figure, the number then
    the unit."""
    if not entry:
        return [html.P("run the scenario to see its key figures", className="meaning")]
    out = []
    for name, value in entry["figures"].items():
        unit = entry["units"].get(name, "")
        text = "–" if value is None else (f"{value:.6g}" if isinstance(value, float)
                                          else str(value))
        if unit not in ("", "1"):
            text += f" {unit}"
        out.append(html.Div(className="figure", children=[
            html.Span(name, className="figure-name"),
            html.Span(text, className="figure-value", **{"data-figure": name})]))
    return out


def runs_table(runs: list[dict], ticked: list[str]) -> html.Table:
    names = list(dict.fromkeys(k for r in runs for k in r["figures"]))
    head = html.Tr([html.Th(h) for h in ("", "run", "changed", *names, "files")])
    body = []
    for r in runs:
        changed = ", ".join(f"{k} = {v}" for k, v in r["changed"].items()) or "as the scenario"
        links = [html.A(n, href=f"/runs/{r['id']}/{n}", target="_blank", className="file")
                 for n in r["files"]]
        body.append(html.Tr(**{"data-run": r["key"]}, children=[
            html.Td(dcc.Checklist(id={"type": "tick", "key": r["key"]},
                                  options=[{"label": "", "value": r["key"]}],
                                  value=[r["key"]] if r["key"] in ticked else [])),
            html.Td(r["label"]), html.Td(changed, className="changed"),
            *[html.Td(_cell(r, n)) for n in names],
            html.Td([*links, html.Code(r["command"], className="command")])]))
    return html.Table([html.Thead(head), html.Tbody(body)])


def _cell(run: dict, name: str) -> str:
    value = run["figures"].get(name)
    return "" if value is None else (f"{value:.4g}" if isinstance(value, float) else str(value))


def sweep_panel(numeric: list[str]) -> html.Section:
    def param(n: str, optional: bool):
        return html.Div(className="sweep-row", children=[
            dcc.Dropdown(id=f"sweep-param{n}", options=numeric, placeholder="parameter" + (" (optional)"
                                                                           if optional else ""),
                         className="sweep-param"),
            dcc.Input(id=f"sweep-from{n}", name=f"sweep.from{n}", type="text",
                      placeholder="from", className="input short"),
            dcc.Input(id=f"sweep-to{n}", name=f"sweep.to{n}", type="text", placeholder="to",
                      className="input short"),
            dcc.Input(id=f"sweep-n{n}", name=f"sweep.points{n}", type="text", value="5",
                      className="input short")])
    return html.Section(className="panel", id="sweep", children=[
        html.H2("sweep"),
        html.P("one or two values over a range (in their declared units), the other values as "
               "above; points appear as they finish", className="meaning"),
        param("", False), param("2", True),
        html.Div(className="actions", children=[
            dcc.Dropdown(id="sweep-figure", placeholder="key figure to plot",
                         className="sweep-param"),
            html.Button("Run sweep", id="sweep-run", className="primary"),
            html.Button("Cancel sweep", id="sweep-cancel"),
            html.Progress(id="sweep-progress", max=1, value=0),
            html.Span(id="sweep-status", className="status", role="status")]),
        html.Div(id="sweep-alert", role="alert", className="alert"),
        dcc.Store(id="sweep-job"), dcc.Store(id="sweep-rows"),
        dcc.Interval(id="sweep-poll", interval=POLL_MS * 2, disabled=True),
        html.Div(**{"data-view": "sweep"}, children=dcc.Graph(
            id="sweep-plot", config={"displaylogo": False},
            className="graph"))])
