"""The pictures of design studies: an optimization's convergence, a fit against its data, the
ranked sensitivity indices of each figure. Written atomically (files/outputs.py)."""
from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np

from sewfmu.scenarios.files.matplotlib_home import pyplot
from sewfmu.scenarios.files.outputs import write_atomic


def _save(fig, path: Path) -> None:
    write_atomic(path, lambda f: fig.savefig(f, dpi=100, format="png"), binary=True)
    pyplot().close(fig)


def convergence(path: Path, name: str, goal, constraints, table, margins,
                units: dict) -> None:
    """The goal's figure at each evaluation in order, the best feasible so far, the points that
    miss a constraint (hollow) or failed (crosses on the axis); one panel per constraint."""
    plt = pyplot()
    figures = [goal.targets[0][0]] + [c.figure for c in constraints]
    fig, axes = plt.subplots(len(figures), 1, sharex=True, figsize=(8, 2.2 + 2.0 * len(figures)),
                             squeeze=False)
    n = np.arange(1, len(table) + 1)
    ok = table["status"] == "ok"
    meets = np.array([all(m is not None and m >= -1e-6 for m in row) for row in margins],
                     dtype=bool) if len(table) else np.zeros(0, bool)
    ax = axes[0][0]
    values = table[figures[0]]
    ax.plot(n[ok & meets], values[ok & meets], "o", ms=4, color="tab:blue", label="evaluation")
    if constraints:
        ax.plot(n[ok & ~meets], values[ok & ~meets], "o", ms=4, mfc="none", color="tab:orange",
                label="misses a constraint")
    objective = np.where(ok & meets & np.isfinite(table["objective"]), table["objective"], np.inf)
    best = np.minimum.accumulate(objective) if len(objective) else objective
    index = [int(np.flatnonzero(objective == b)[0]) if math.isfinite(b) else -1 for b in best]
    line = [values[i] if i >= 0 else np.nan for i in index]
    ax.step(n, line, where="post", color="k", lw=1.2, label="best so far")
    if goal.sense == "target":
        ax.axhline(goal.targets[0][1], color="tab:green", ls="--", lw=1, label="target")
    failed = ~ok | ~np.isfinite(values)
    if failed.any():
        ax.plot(n[failed], np.zeros(failed.sum()), "x", color="tab:red",
                transform=ax.get_xaxis_transform(), clip_on=False, label="no value (failed)")
    ax.set_ylabel(_labelled(figures[0], units))
    ax.legend(fontsize=7, loc="best")
    for ax, c in zip((a[0] for a in axes[1:]), constraints):
        ax.plot(n[ok], table[c.figure][ok], "o", ms=3, color="tab:purple")
        ax.axhline(c.value, color="tab:red", ls="--", lw=1, label=str(c))
        ax.set_ylabel(_labelled(c.figure, units))
        ax.legend(fontsize=7, loc="best")
    for a in axes[:, 0]:
        a.grid(alpha=0.3)
    axes[-1][0].set_xlabel("evaluation")
    what = ", ".join(f"{k} {v}" for k, v in goal.describe().items())
    fig.suptitle("\n".join(textwrap.wrap(f"{name}: {what}", 90)), fontsize=10)
    fig.tight_layout()
    _save(fig, path)


def _labelled(name: str, units: dict) -> str:
    unit = units.get(name, "")
    return f"{name} [{unit}]" if unit and unit != "1" else name


def fit_plot(path: Path, name: str, times, data: dict, model_time, model: dict,
             units: dict) -> None:
    """Each column: the data as points, the model at the estimates as a line, the residuals."""
    plt = pyplot()
    columns = list(data)
    fig, axes = plt.subplots(2 * len(columns), 1, sharex=True,
                             figsize=(8, 3.2 * len(columns) + 0.6), squeeze=False,
                             gridspec_kw={"height_ratios": [3, 1] * len(columns)})
    for k, column in enumerate(columns):
        ax, ax_r = axes[2 * k][0], axes[2 * k + 1][0]
        unit = f" [{units.get(column)}]" if units.get(column) else ""
        ax.plot(times, data[column], ".", ms=2.5, color="0.4", label="data")
        ax.plot(model_time, model[column], "-", lw=1.2, color="tab:red", label="fit")
        ax.set_ylabel(column + unit)
        ax.legend(fontsize=7, loc="best")
        at_data = np.interp(times, model_time, model[column])
        ax_r.plot(times, data[column] - at_data, ".", ms=2, color="tab:blue")
        ax_r.axhline(0.0, color="k", lw=0.8)
        ax_r.set_ylabel("residual" + unit, fontsize=8)
        for a in (ax, ax_r):
            a.grid(alpha=0.3)
    axes[-1][0].set_xlabel("time [s]")
    fig.suptitle(f"{name}: data and the fitted model", fontsize=10)
    fig.tight_layout()
    _save(fig, path)


def sensitivity_bars(path: Path, figure: str, unit: str, method: str, rows: list[dict]) -> None:
    """The parameters ranked by their index (Sobol: ST beside S1; Morris: mu* beside sigma),
    with the confidence intervals as error bars."""
    plt = pyplot()
    first, second = ("ST", "S1") if method == "sobol" else ("mu_star", "sigma")
    names = [r["parameter"] for r in rows][::-1]
    y = np.arange(len(names))
    fig, ax = plt.subplots(figsize=(7, 1.4 + 0.45 * len(names)))
    h = 0.38
    ax.barh(y + h / 2, [r[first] for r in rows][::-1], h,
            xerr=[r[f"{first}_conf"] for r in rows][::-1], color="tab:blue",
            label=first, capsize=3)
    second_err = [r.get(f"{second}_conf", 0.0) for r in rows][::-1]
    ax.barh(y - h / 2, [r[second] for r in rows][::-1], h, xerr=second_err, color="tab:orange",
            label=second, capsize=3)
    ax.set_yticks(y, names)
    ax.axvline(0.0, color="k", lw=0.8)
    scale = f" [{unit}]" if method == "morris" and unit else ""
    ax.set_xlabel(f"{'Sobol index' if method == 'sobol' else 'elementary effect'}{scale}")
    ax.set_title(f"{figure}: what matters ({method})", fontsize=10)
    ax.legend(fontsize=8, loc="lower right")
    ax.grid(alpha=0.3, axis="x")
    fig.tight_layout()
    _save(fig, path)
