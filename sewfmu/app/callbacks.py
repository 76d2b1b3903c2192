"""What the page does when a user acts: load a scenario's values, check them and start a run (or
refuse it with the alert's one line), follow and cancel it, keep it in the tab's table of runs,
draw the runs, move the mechanism, run a sweep. Every callback reads the jobs of the ids its tab
holds (dcc.Store, in the tab); nothing is kept per page on the server."""
from __future__ import annotations

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

NOT = dash.no_update
MAX_POINTS = 400          # a sweep's points from the page (a larger one: `sewfmu sweep`)
# s a progress request waits for the job to end: its end reaches the page at once, not at the
# next poll (kept under the poll's interval, so that requests do not pile up)
SETTLING = 0.8 * POLL_MS / 1000


def register(app, page) -> None:
    """page: the app's state (choices, jobs, the results folder, the sweep's scheduler)."""

    @app.callback(Output("scenario", "value"), Input("url", "search"), State("scenario", "value"))
    def choose_from_address(search, current):
        wanted = dict(p.split("=", 1) for p in (search or "").lstrip("?").split("&") if "=" in p)
        name = unquote(wanted.get("scenario", ""))
        # the same scenario again would draw its inputs anew, over what was typed meanwhile
        return name if name in page.choices and name != current else NOT

    @app.callback(Output("values", "children"), Output("defaults", "data"),
                  Output("description", "children"), Output("sweep-param", "options"),
                  Output("sweep-param2", "options"), Input("scenario", "value"),
                  prevent_initial_call=True)
    def show_values(label):
        return values_of_choice(page, label)

    # a finished run's figures and table row come with the answer that says it is done (not
    # one round trip later, through the runs store): the page shows them a tenth of a second sooner
    @app.callback(Output("job", "data"), Output("poll", "disabled"), Output("progress", "value"),
                  Output("status", "children"), Output("alert", "children"),
                  Output("runs", "data"), Output("figures", "children"),
                  Output("figures-title", "children"), Output("series", "options"),
                  Output("series", "value"), Output("table", "children"),
                  Input("run", "n_clicks"), Input("cancel", "n_clicks"),
                  Input("poll", "n_intervals"),
                  State("scenario", "value"), State({"type": "value", "name": ALL}, "value"),
                  State({"type": "value", "name": ALL}, "id"), State("defaults", "data"),
                  State("job", "data"), State("runs", "data"), State("series", "value"),
                  State("ticked", "data"), prevent_initial_call=True)
    def run_cancel_follow(_run, _cancel, _tick, label, texts, ids, defaults, job_id, runs,
                          chosen, ticked):
        unshown = (NOT,) * 5                # the figures and the table as they are
        which = ctx.triggered_id
        if which == "run":
            if page.jobs.get(job_id) is not None and page.jobs.get(job_id).status == "running":
                return (NOT, NOT, NOT, NOT, "a run is going: wait for it, or Cancel it", NOT,
                        *unshown)
            if not isinstance(label, str) or label not in page.choices:
                return NOT, NOT, NOT, NOT, "choose a scenario", NOT, *unshown
            try:
                changed = page.check(label, _typed(ids, texts), defaults)
                new = page.jobs.start("run", page.request(label, changed))
            except sewfmu.Error as err:
                return None, True, 0, "", _one_line(err), NOT, *unshown
            return new, False, 0, "running…", "", NOT, *unshown
        job = page.jobs.get(job_id)
        if job is None:
            return None, True, 0, "", NOT, NOT, *unshown
        if which == "cancel":
            page.jobs.cancel(job_id)
            return None, True, 0, "cancelled", "", NOT, *unshown
        if which == "poll":     # answered as soon as the job ends, not at the next poll
            job.settled.wait(SETTLING)
        if job.status == "running":
            return (NOT, False, job.fraction, f"running… {100 * job.fraction:.0f} %", NOT, NOT,
                    *unshown)
        if job.status == "done":
            took = (job.finished or time.monotonic()) - job.started
            runs = runs + page.entries(job, runs)
            return (None, True, 1, f"done in {took:.1f} s", "", runs,
                    *_shown_runs(page, runs, chosen, ticked))
        return None, True, 0, job.status, job.error or "", NOT, *unshown

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

    @app.callback(Output("tick", "disabled"), Output("play", "children"),
                  Input("play", "n_clicks"), State("tick", "disabled"),
                  prevent_initial_call=True)
    def play(_clicks, stopped):
        return (False, "Pause") if stopped else (True, "Play")

    @app.callback(Output("angle", "value"), Input("tick", "n_intervals"), State("angle", "value"),
                  prevent_initial_call=True)
    def step(_n, angle):
        return ((angle or 0) + FRAME_DEG) % 360

    @app.callback(Output("sweep-job", "data"), Output("sweep-poll", "disabled"),
                  Output("sweep-progress", "value"), Output("sweep-status", "children"),
                  Output("sweep-alert", "children"), Output("sweep-rows", "data"),
                  Input("sweep-run", "n_clicks"), Input("sweep-cancel", "n_clicks"),
                  Input("sweep-poll", "n_intervals"),
                  State("scenario", "value"), State({"type": "value", "name": ALL}, "value"),
                  State({"type": "value", "name": ALL}, "id"), State("defaults", "data"),
                  State("sweep-param", "value"), State("sweep-from", "value"),
                  State("sweep-to", "value"), State("sweep-n", "value"),
                  State("sweep-param2", "value"), State("sweep-from2", "value"),
                  State("sweep-to2", "value"), State("sweep-n2", "value"),
                  State("sweep-job", "data"), prevent_initial_call=True)
    def sweep(_run, _cancel, _tick, label, texts, ids, defaults, p1, lo1, hi1, n1, p2, lo2, hi2,
              n2, job_id):
        which = ctx.triggered_id
        if which == "sweep-run":
            if page.jobs.get(job_id) is not None and page.jobs.get(job_id).status == "running":
                return NOT, NOT, NOT, NOT, "a sweep is going: wait for it, or Cancel it", NOT
            try:
                changed = page.check(label, _typed(ids, texts), defaults)
                grid = {p1: _range(page, label, p1, lo1, hi1, n1)} if p1 else {}
                if not grid:
                    raise sewfmu.ScenarioError("sweep: choose a parameter to sweep")
                if p2:
                    if p2 == p1:
                        raise sewfmu.ScenarioError(f"sweep: {p1} is chosen twice")
                    grid[p2] = _range(page, label, p2, lo2, hi2, n2)
                if len(grid[p1]) * len(grid.get(p2, [0])) > MAX_POINTS:
                    raise sewfmu.ScenarioError(f"sweep: at most {MAX_POINTS} points in all")
                request = {**page.request(label, changed), "grid": grid,
                           "scheduler": page.scheduler, "workers": page.workers,
                           "points": [0] * int(np.prod([len(v) for v in grid.values()]))}
                new = page.jobs.start("sweep", request)
            except sewfmu.Error as err:
                return None, True, 0, "", _one_line(err), NOT
            return new, False, 0, "running…", "", {"rows": [], "swept": list(grid),
                                                   "units": {}}
        job = page.jobs.get(job_id)
        if job is None:
            return None, True, 0, "", NOT, NOT
        if which == "sweep-cancel":
            page.jobs.cancel(job_id)
            return None, True, job.fraction, f"cancelled after {len(job.points)} points", "", NOT
        swept = list(job.request["grid"])
        if job.status == "running":
            return (NOT, False, job.fraction, f"{len(job.points)} of {job.total} points",
                    NOT, {"rows": list(job.points), "swept": swept, "units": {}})
        if job.status == "done":
            result = job.result
            failed = sum(r.get("status") != "ok" for r in result["rows"])
            return (None, True, 1, f"{len(result['rows'])} points, {failed} failed", "",
                    {"rows": result["rows"], "swept": result["swept"], "units": result["units"]})
        return None, True, 0, job.status, job.error or "", NOT

    @app.callback(Output("sweep-plot", "figure"), Output("sweep-figure", "options"),
                  Output("sweep-figure", "value"), Input("sweep-rows", "data"),
                  Input("sweep-figure", "value"))
    def sweep_plot(data, figure):
        data = data or {"rows": [], "swept": [], "units": {}}
        skip = {"index", "key", "status", "error", "wall_time_s", "stop_time", *data["swept"]}
        names = list(dict.fromkeys(k for r in data["rows"] for k, v in r.items()
                                   if k not in skip and isinstance(v, (int, float))))
        figure = figure if figure in names else (names[0] if names else None)
        return sweep_figure(data["rows"], data["swept"], figure, data["units"]), \
            names, figure


def _shown_runs(page, runs: list, chosen: list | None, ticked: list | None) -> tuple:
    """The newest run's key figures (and its title), the series it recorded to choose from (those
    chosen kept where it has them), and the table of runs, the newest ticked."""
    newest = runs[-1]
    names = [n for n in page.variant(newest)["series"] if n not in ("crank_deg", "time")]
    chosen = [c for c in chosen or [] if c in names] or _default_series(names)
    ticked = set(ticked or []) | {newest["key"]}
    for run in runs:      # report.html is made when first asked for
        run["files"] = list(dict.fromkeys([*present(page.root, run["id"]), "report.html"]))
    return (figures(newest), f"key figures of {newest['label']}",
            [{"label": f"{n} [{newest['units'].get(n, '')}]", "value": n} for n in names],
            chosen, runs_table(runs, list(ticked)))


def values_of_choice(page, label: str) -> tuple:
    """A scenario's inputs, their texts as it has them, its description, and the values a
    sweep can take (the numbers)."""
    if not isinstance(label, str) or label not in page.choices:
        return [], {}, "", [], []
    source = page.choices[label]
    cells, defaults = value_inputs(source)
    numeric = [n for n, v in defaults.items() if isinstance(value_of(v), (int, float))]
    return cells, defaults, sewfmu.load(source).description, numeric, numeric


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
