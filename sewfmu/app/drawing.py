"""The page's pictures as Plotly figures: the recorded series of the last revolution against the
crank angle (runs overlaid, a cursor at the animation's angle), the mechanism at one angle from
the numbers `Run.mechanism()` gives, and a sweep's key figure against its parameters."""
from __future__ import annotations

import plotly.graph_objects as go
from plotly.subplots import make_subplots

COLORS = ("#4477aa", "#ee6677", "#228833", "#ccbb44", "#66ccee", "#aa3377", "#bbbbbb")
TRACKED = "#ff0000"
MARGIN = dict(l=50, r=10, t=30, b=40)


def series_figure(shown: list[tuple[str, dict]], columns: list[str], cursor_deg: float | None):
    """One panel per chosen column, each run (label, variant) a line in it, against the crank
    angle of the last revolution."""
    columns = columns or []
    if not shown:
        return _empty(go.Figure(), "run the scenario, or tick runs,<br>to plot what they recorded")
    if not any(variant["series"] for _, variant in shown):
        return _empty(go.Figure(), "a study is computed from the values, not run:<br>no series "
                                   "to plot (its key figures are above)")
    fig = make_subplots(rows=max(1, len(columns)), cols=1, shared_xaxes=True,
                        vertical_spacing=0.06)
    for row, column in enumerate(columns, start=1):
        for k, (label, variant) in enumerate(shown):
            series = variant["series"]
            if column not in series:
                continue
            fig.add_trace(go.Scatter(x=series["crank_deg"], y=series[column], mode="lines",
                                     name=label, legendgroup=label, showlegend=row == 1,
                                     line=dict(color=COLORS[k % len(COLORS)], width=1.6)),
                          row=row, col=1)
        unit = next((v["units"].get(column, "") for _, v in shown), "")
        fig.update_yaxes(title_text=f"{column} [{unit}]" if unit else column, row=row, col=1,
                         title_font=dict(size=11))
    fig.update_xaxes(title_text="crank angle [deg], last revolution", range=[0, 360],
                     row=max(1, len(columns)), col=1)
    if cursor_deg is not None:
        fig.add_vline(x=cursor_deg, line=dict(color=TRACKED, width=1, dash="dot"))
    fig.update_layout(height=170 + 190 * max(1, len(columns)), margin=MARGIN,
                      legend=dict(orientation="h", y=1.02, yanchor="bottom", x=0),
                      uirevision="series")
    return fig


def mechanism_figure(drawing: dict | None, frame: int, label: str = "",
                     empty: str = "run the scenario<br>to see its mechanism move"):
    """The mechanism at one frame: its bars, its pivots, the tracked point in red and its path."""
    fig = go.Figure()
    if not drawing:
        return _empty(fig, empty)
    frame = max(0, min(frame, len(drawing["crank_deg"]) - 1))
    at = {name: xy[frame] for name, xy in drawing["points"].items()}
    tracked = drawing["tracked"]
    path = drawing["points"][tracked]
    fig.add_trace(go.Scatter(x=[p[0] for p in path] + [path[0][0]],
                             y=[p[1] for p in path] + [path[0][1]], mode="lines",
                             line=dict(color="#dddddd", width=1), hoverinfo="skip",
                             showlegend=False))
    for chain in drawing["chains"]:
        fig.add_trace(go.Scatter(x=[at[n][0] for n in chain], y=[at[n][1] for n in chain],
                                 mode="lines+markers", line=dict(color="#404040", width=3),
                                 marker=dict(size=6), text=chain, hoverinfo="text",
                                 showlegend=False))
    fig.add_trace(go.Scatter(x=[at[tracked][0]], y=[at[tracked][1]], mode="markers",
                             marker=dict(color=TRACKED, size=11), name=tracked,
                             hovertemplate=f"{tracked} (recorded): %{{x:.3f}}, %{{y:.3f}} mm"
                                           f"<extra></extra>", showlegend=False))
    angle, time = drawing["crank_deg"][frame], drawing["time"][frame]
    fig.update_layout(
        height=360, margin=MARGIN, uirevision="mechanism", plot_bgcolor="white",
        title=dict(text=f"{label}  φ = {angle:5.1f}°  t = {time:.4f} s", font=dict(size=12)),
        xaxis=dict(range=list(drawing["xlim"]), title="x [mm]", showgrid=False, zeroline=False),
        yaxis=dict(range=list(drawing["ylim"]), showgrid=False, zeroline=False,
                   **({"scaleanchor": "x", "scaleratio": 1} if drawing.get("to_scale") else {})))
    return fig


def sweep_figure(rows: list[dict], swept: list[str], figure: str | None, units: dict):
    """A key figure against one swept parameter (a line), or two (coloured points)."""
    fig = go.Figure()
    if not rows:
        return _empty(fig, "choose a value and its range, then Run sweep:<br>the points "
                           "appear here as they finish")
    ok = [r for r in rows if r.get("status") == "ok" and isinstance(r.get(figure), (int, float))]
    unit = units.get(figure, "")
    name = f"{figure} [{unit}]" if unit else (figure or "")
    if figure and swept and len(swept) == 1:
        ok.sort(key=lambda r: r[swept[0]])
        fig.add_trace(go.Scatter(x=[r[swept[0]] for r in ok], y=[r[figure] for r in ok],
                                 mode="lines+markers", name=figure))
        fig.update_yaxes(title_text=name)
    elif figure and len(swept) >= 2:
        fig.add_trace(go.Scatter(x=[r[swept[0]] for r in ok], y=[r[swept[1]] for r in ok],
                                 mode="markers", marker=dict(
                                     size=14, color=[r[figure] for r in ok],
                                     colorscale="Viridis", showscale=True,
                                     colorbar=dict(title=dict(text=name, side="right")))))
        fig.update_yaxes(title_text=_axis(swept[1], units))
    if swept:
        fig.update_xaxes(title_text=_axis(swept[0], units))
    fig.update_layout(height=360, margin=MARGIN, uirevision="sweep")
    return fig


def _empty(fig, text: str):
    """A figure with nothing to draw yet: what to do instead of empty axes."""
    fig.update_layout(height=200, margin=MARGIN, xaxis=dict(visible=False),
                      yaxis=dict(visible=False), plot_bgcolor="white",
                      annotations=[dict(text=text, showarrow=False, x=0.5, y=0.5, xref="paper",
                                        yref="paper", font=dict(size=13, color="#666"))])
    return fig


def _axis(name: str, units: dict) -> str:
    return f"{name} [{units[name]}]" if units.get(name) else name
