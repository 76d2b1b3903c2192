"""What the page does when a user acts: load a scenario's values, check them and start a run (or
refuse it with the alert's one line), follow and cancel it, keep it in the tab's table of runs,
draw the runs, move the mechanism, run a sweep. Every callback reads the jobs of the ids its tab
holds (dcc.Store, in the tab); nothing is kept per page on the server.

A callback with several outputs names them (Dash's dict outputs): its `Answer` lists them once,
and each return sets the ones it names and leaves every other as the page has it."""
from __future__ import annotations

import math
import sys
import time
import traceback
from urllib.parse import unquote

import dash
import numpy as np
from dash import ALL, Input, Output, State, ctx

import sewfmu
from sewfmu.app.drawing import mechanism_figure, series_figure, sweep_figure
from sewfmu.app.files import present
from sewfmu.app.layout import FRAME_DEG, POLL_MS, figures, runs_table, value_inputs
from sewfmu.app.values import checked, readable, value_of

MAX_POINTS = 400          # a sweep's points from the page (a larger one: `sewfmu sweep`)
# s a progress request waits for the job to end: its end reaches the page at once, not at the
# next poll (kept under the poll's interval, so that requests do not pile up)
SETTLING = 0.8 * POLL_MS / 1000


class Answer:
    """A callback's outputs by name. `answer(name=value, ...)` is what the callback returns: the
    outputs named set, every other left as the page has it (dash.no_update)."""

    def __init__(self, **outputs: Output):
        self.outputs = outputs     # a plain dict: Dash reads a dict's subclass as one output

    def __call__(self, **values) -> dict:
        unknown = values.keys() - self.outputs.keys()
        if unknown:             # a misspelt name would otherwise be dropped without a word
            raise KeyError(f"not an output of this callback: {', '.join(sorted(unknown))}")
        return {name: values.get(name, dash.no_update) for name in self.outputs}


# a scenario chosen: its value inputs, their texts as it has them, and what a sweep may vary
VALUES = Answer(values=Output("values", "children"), defaults=Output("defaults", "data"),
                description=Output("description", "children"),
                sweep_choices=Output("sweep-param", "options"),
                sweep_choices2=Output("sweep-param2", "options"))
# Run, Cancel and the progress poll: the job, its progress, and, once it is done, the runs store,
# the newest run's figures, the series to plot and the table of runs
RUN = Answer(job=Output("job", "data"), poll_off=Output("poll", "disabled"),
             progress=Output("progress", "value"), status=Output("status", "children"),
             alert=Output("alert", "children"), runs=Output("runs", "data"),
             figures=Output("figures", "children"),
             figures_title=Output("figures-title", "children"),
             series_choices=Output("series", "options"), series=Output("series", "value"),
             table=Output("table", "children"))
PLAY = Answer(stopped=Output("tick", "disabled"), button=Output("play", "children"))
# the sweep's Run, Cancel and poll: its job, its progress, and its points so far (sweep-rows)
SWEEP = Answer(job=Output("sweep-job", "data"), poll_off=Output("sweep-poll", "disabled"),
               progress=Output("sweep-progress", "value"),
               status=Output("sweep-status", "children"),
               alert=Output("sweep-alert", "children"), rows=Output("sweep-rows", "data"))
SWEEP_PLOT = Answer(figure=Output("sweep-plot", "figure"),
                    choices=Output("sweep-figure", "options"),
                    chosen=Output("sweep-figure", "value"))


def register(app, page) -> None:
    """page: the app's state (choices, jobs, the results folder, the sweep's scheduler)."""
    _register_values(app, page)
    _register_run(app, page)
    _register_drawing(app, page)
    _register_sweep(app, page)


def _value_states() -> dict:
    """The states every Run reads: the scenario, its value inputs' texts and names, its defaults
    (a new dict each time: Dash adds a callback's inputs into the dict of its states)."""
    return dict(label=State("scenario", "value"),
                texts=State({"type": "value", "name": ALL}, "value"),
                ids=State({"type": "value", "name": ALL}, "id"),
                defaults=State("defaults", "data"))


def _register_values(app, page) -> None:
    """The scenario named in the address, and the values of the one chosen."""

    @app.callback(Output("scenario", "value"), Input("url", "search"), State("scenario", "value"))
    def choose_from_address(search, current):
        wanted = dict(p.split("=", 1) for p in (search or "").lstrip("?").split("&") if "=" in p)
        name = unquote(wanted.get("scenario", ""))
        # the same scenario again would draw its inputs anew, over what was typed meanwhile
        return name if name in page.choices and name != current else dash.no_update

    @app.callback(output=VALUES.outputs, inputs=dict(label=Input("scenario", "value")),
                  prevent_initial_call=True)
    def show_values(label):
        return values_of_choice(page, label)


def _register_run(app, page) -> None:
    """Run, Cancel and the poll that follows a run to its end."""

    # a finished run's figures and table row come with the answer that says it is done (not
    # one round trip later, through the runs store): the page shows them a tenth of a second sooner
    @app.callback(output=RUN.outputs,
                  inputs=dict(run=Input("run", "n_clicks"), cancel=Input("cancel", "n_clicks"),
                              poll=Input("poll", "n_intervals")),
                  state=dict(**_value_states(), job_id=State("job", "data"),
                             runs=State("runs", "data"), chosen=State("series", "value"),
                             ticked=State("ticked", "data")),
                  prevent_initial_call=True)
    def run_cancel_follow(run, cancel, poll, label, texts, ids, defaults, job_id, runs, chosen,
                          ticked):
        which = ctx.triggered_id                # the clicks' counts say nothing more
        if which == "run":
            return _start_run(page, job_id, label, texts, ids, defaults)
        job = page.jobs.get(job_id)
        if job is None:
            return RUN(job=None, poll_off=True, progress=0, status="")
        if which == "cancel":
            page.jobs.cancel(job_id)
            return RUN(job=None, poll_off=True, progress=0, status="cancelled", alert="")
        if which == "poll":     # answered as soon as the job ends, not at the next poll
            job.settled.wait(SETTLING)
        if job.status == "running":
            return RUN(poll_off=False, progress=job.fraction,
                       status=f"running… {100 * job.fraction:.0f} %")
        if job.status == "done":
            took = (job.finished or time.monotonic()) - job.started
            runs = runs + page.entries(job, runs)
            return RUN(job=None, poll_off=True, progress=1, status=f"done in {took:.1f} s",
                       alert="", runs=runs, **_shown_runs(page, runs, chosen, ticked))
        return RUN(job=None, poll_off=True, progress=0, status=job.status,
                   alert=job.error or "")


def _start_run(page, job_id, label, texts, ids, defaults) -> dict:
    """A click on Run: the values checked and the run started, or the alert's one line why not
    (the job, the figures and the table as they are)."""
    if page.jobs.get(job_id) is not None and page.jobs.get(job_id).status == "running":
        return RUN(alert="a run is going: wait for it, or Cancel it")
    if not isinstance(label, str) or label not in page.choices:
        return RUN(alert="choose a scenario")
    try:
        changed = page.check(label, _typed(ids, texts), defaults)
        new = page.jobs.start("run", page.request(label, changed))
    except sewfmu.Error as err:
        return RUN(job=None, poll_off=True, progress=0, status="", alert=_one_line(err))
    return RUN(job=new, poll_off=False, progress=0, status="running…", alert="")


def _register_drawing(app, page) -> None:
    """The runs ticked in the table, their series plotted, the last one's mechanism moving."""

    @app.callback(Output("ticked", "data"), Input({"type": "tick", "key": ALL}, "value"),
                  prevent_initial_call=True)
    def tick(values):
        return [key for value in values for key in value or []]

    @app.callback(Output("plot", "figure"), Input("ticked", "data"), Input("series", "value"),
                  Input("angle", "value"), State("runs", "data"))
    def plot(ticked, columns, angle, runs):
        shown = [(r["label"], page.variant(r)) for r in runs or [] if r["key"] in (ticked or [])]
        return series_figure(shown, columns or [], angle if shown else None)

    @app.callback(Output("mechanism", "figure"), Input("ticked", "data"), Input("angle", "value"),
                  State("runs", "data"))
    def mechanism(ticked, angle, runs):
        shown = [r for r in runs or [] if r["key"] in (ticked or [])]
        if not shown:
            return mechanism_figure(None, 0)
        run = shown[-1]
        return mechanism_figure(page.variant(run)["mechanism"],
                                round((angle or 0) / FRAME_DEG), run["label"],
                                empty="no drawing of this mechanism")

    @app.callback(output=PLAY.outputs,
                  inputs=dict(clicks=Input("play", "n_clicks")),
                  state=dict(stopped=State("tick", "disabled")), prevent_initial_call=True)
    def play(clicks, stopped):
        return PLAY(stopped=False, button="Pause") if stopped else \
            PLAY(stopped=True, button="Play")

    @app.callback(Output("angle", "value"), Input("tick", "n_intervals"), State("angle", "value"),
                  prevent_initial_call=True)
    def step(_n, angle):
        return ((angle or 0) + FRAME_DEG) % 360


def _axis(n: str = "") -> dict:
    """The sweep panel's fields of one parameter to sweep (n: "" the first, "2" the second)."""
    return dict(name=State(f"sweep-param{n}", "value"), lo=State(f"sweep-from{n}", "value"),
                hi=State(f"sweep-to{n}", "value"), n=State(f"sweep-n{n}", "value"))


def _register_sweep(app, page) -> None:
    """The sweep panel: its Run, Cancel and poll, and its plot of the points so far."""

    @app.callback(output=SWEEP.outputs,
                  inputs=dict(run=Input("sweep-run", "n_clicks"),
                              cancel=Input("sweep-cancel", "n_clicks"),
                              poll=Input("sweep-poll", "n_intervals")),
                  state=dict(**_value_states(), first=_axis(), second=_axis("2"),
                             job_id=State("sweep-job", "data")),
                  prevent_initial_call=True)
    def sweep(run, cancel, poll, label, texts, ids, defaults, first, second, job_id):
        which = ctx.triggered_id                # the clicks' counts say nothing more
        if which == "sweep-run":
            return _start_sweep(page, job_id, label, texts, ids, defaults, first, second)
        job = page.jobs.get(job_id)
        if job is None:
            return SWEEP(job=None, poll_off=True, progress=0, status="")
        if which == "sweep-cancel":
            page.jobs.cancel(job_id)
            return SWEEP(job=None, poll_off=True, progress=job.fraction,
                         status=f"cancelled after {len(job.points)} points", alert="")
        if job.status == "running":
            return SWEEP(poll_off=False, progress=job.fraction,
                         status=f"{len(job.points)} of {job.total} points",
                         rows={"rows": list(job.points), "swept": list(job.request["grid"]),
                               "units": {}})
        if job.status == "done":
            result = job.result
            failed = sum(r.get("status") != "ok" for r in result["rows"])
            return SWEEP(job=None, poll_off=True, progress=1,
                         status=f"{len(result['rows'])} points, {failed} failed", alert="",
                         rows={"rows": result["rows"], "swept": result["swept"],
                               "units": result["units"]})
        return SWEEP(job=None, poll_off=True, progress=0, status=job.status,
                     alert=job.error or "")

    @app.callback(output=SWEEP_PLOT.outputs,
                  inputs=dict(data=Input("sweep-rows", "data"),
                              figure=Input("sweep-figure", "value")))
    def sweep_plot(data, figure):
        data = data or {"rows": [], "swept": [], "units": {}}
        skip = {"index", "key", "status", "error", "wall_time_s", "stop_time", *data["swept"]}
        names = list(dict.fromkeys(k for r in data["rows"] for k, v in r.items()
                                   if k not in skip and isinstance(v, (int, float))))
        figure = figure if figure in names else (names[0] if names else None)
        return SWEEP_PLOT(figure=sweep_figure(data["rows"], data["swept"], figure,
                                              data["units"]),
                          choices=names, chosen=figure)


def _start_sweep(page, job_id, label, texts, ids, defaults, first: dict, second: dict) -> dict:
    """A click on the sweep's Run: the values and the grid checked and the sweep started, or the
    sweep's alert's one line why not (its job and its points as they are)."""
    if page.jobs.get(job_id) is not None and page.jobs.get(job_id).status == "running":
        return SWEEP(alert="a sweep is going: wait for it, or Cancel it")
    try:
        changed = page.check(label, _typed(ids, texts), defaults)
        grid = _grid(page, label, first, second)
        request = {**page.request(label, changed), "grid": grid,
                   "scheduler": page.scheduler, "workers": page.workers,
                   "points": [0] * math.prod(len(v) for v in grid.values())}
        new = page.jobs.start("sweep", request)
    except sewfmu.Error as err:
        return SWEEP(job=None, poll_off=True, progress=0, status="", alert=_one_line(err))
    return SWEEP(job=new, poll_off=False, progress=0, status="running…", alert="",
                 rows={"rows": [], "swept": list(grid), "units": {}})


def _grid(page, label: str, first: dict, second: dict) -> dict[str, list[float]]:
    """A sweep's values by parameter: the first one's, and the second's if one is chosen."""
    if not first["name"]:
        raise sewfmu.ScenarioError("sweep: choose a parameter to sweep")
    grid = {first["name"]: _range(page, label, **first)}
    if second["name"]:
        if second["name"] == first["name"]:
            raise sewfmu.ScenarioError(f"sweep: {first['name']} is chosen twice")
        grid[second["name"]] = _range(page, label, **second)
    if math.prod(len(v) for v in grid.values()) > MAX_POINTS:
        raise sewfmu.ScenarioError(f"sweep: at most {MAX_POINTS} points in all")
    return grid


def _shown_runs(page, runs: list, chosen: list | None, ticked: list | None) -> dict:
    """The newest run's key figures (and its title), the series it recorded to choose from (those
    chosen kept where it has them), and the table of runs, the newest ticked: RUN's names."""
    newest = runs[-1]
    names = [n for n in page.variant(newest)["series"] if n not in ("crank_deg", "time")]
    chosen = [c for c in chosen or [] if c in names] or _default_series(names)
    ticked = set(ticked or []) | {newest["key"]}
    for run in runs:      # report.html is made when first asked for
        run["files"] = list(dict.fromkeys([*present(page.root, run["id"]), "report.html"]))
    return dict(figures=figures(newest), figures_title=f"key figures of {newest['label']}",
                series_choices=[{"label": f"{n} [{newest['units'].get(n, '')}]", "value": n}
                                for n in names],
                series=chosen, table=runs_table(runs, list(ticked)))


def values_of_choice(page, label: str) -> dict:
    """A scenario's inputs, their texts as it has them, its description, and the values a
    sweep can take (the numbers), by VALUES's names (the layout reads them too)."""
    if not isinstance(label, str) or label not in page.choices:
        return VALUES(values=[], defaults={}, description="", sweep_choices=[],
                      sweep_choices2=[])
    source = page.choices[label]
    cells, defaults = value_inputs(source)
    numeric = [n for n, v in defaults.items() if isinstance(value_of(v), (int, float))]
    return VALUES(values=cells, defaults=defaults, description=sewfmu.load(source).description,
                  sweep_choices=numeric, sweep_choices2=numeric)


# the outputs a mechanism's pages plot first: the punch's height and force, the feed dog's and
# the eye's paths, the table and the guide's tip
FIRST = ("y", "F2", "M_x", "M_y", "E_z", "E_x", "x", "U2")


def _default_series(names: list[str]) -> list[str]:
    """Two series to start with: the mechanism's own, else the first past the shaft's."""
    known = sorted((n for n in names if n.rpartition(".")[2] in FIRST),
                   key=lambda n: FIRST.index(n.rpartition(".")[2]))
    rest = [n for n in names if not n.startswith("shaft.")]
    return (known or rest or names)[:2]


def _typed(ids, texts) -> dict:
    """{name: text} of the value inputs, from what the page sent (a request not from the page
    may send anything: one line, not a 500)."""
    try:
        return {str(i["name"]): t for i, t in zip(ids, texts)}
    except (KeyError, TypeError):
        raise sewfmu.ScenarioError("the values sent are not the page's inputs: reload the "
                                   "page") from None


def _range(page, label: str, name, lo, hi, n) -> list[float]:
    """A sweep's values: n numbers from lo to hi, each end checked as a typed value is."""
    if not isinstance(name, str):
        raise sewfmu.ScenarioError(f"sweep: choose a parameter to sweep, got {name!r:.80}")
    lo, hi, n = (readable(f"sweep {name} {end}", text)
                 for end, text in (("from", lo), ("to", hi), ("points", n)))
    try:
        a, b, count = float(lo), float(hi), int(n)
    except (TypeError, ValueError):
        raise sewfmu.ScenarioError(f"sweep {name}: from and to are numbers in its declared "
                                   f"unit, points a whole number, got {lo!r}, {hi!r}, "
                                   f"{n!r}") from None
    if not 1 <= count <= 200:
        raise sewfmu.ScenarioError(f"sweep {name}: points from 1 to 200, got {count}")
    for end in (a, b):
        checked(sewfmu.load, page.choices[label], {name: end})
    return [float(v) for v in np.linspace(a, b, count)]


def failed(err: Exception) -> None:
    """Dash's on_error: a callback that raised (a bug in sewfmu: a value the page cannot read
    is refused with its one line before this) says so in its panel's alert, its traceback on the
    server's terminal, rather than answering 500 and leaving the page as it was."""
    traceback.print_exception(err, file=sys.stderr)
    which = ctx.triggered_id if isinstance(ctx.triggered_id, str) else ""
    alert = "sweep-alert" if which.startswith("sweep") else "alert"
    dash.set_props(alert, {"children": _one_line(f"the page failed ({type(err).__name__}: "
                                                 f"{err}): a bug in sewfmu")})


def _one_line(err: Exception, most: int = 400) -> str:
    """A refusal as the page shows it: one line, a value of a megabyte cut short."""
    text = " ".join(str(err).split())
    return text if len(text) <= most else text[:most - 1] + "…"
