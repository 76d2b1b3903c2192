"""The feed mechanism: key figures, drawings, and the paper's lever-ratio study.

Mansurova and Umarova study the swing of the feed-bar lever φ5(φ1) as the ratio l5/l4 changes
(3.5 … 7.0, recommending 5.0 … 6.5) and as the ratio of the two branches' rod lengths changes
(0.7 … 1.7). Here l4 is varied at fixed l5 for the first, and rod 2 (l2) at fixed rod 8 (l8) for
the second, every other parameter at its default. A configuration that cannot be assembled is
reported as such, with the crank angle where it fails, and the study goes on.
"""
from __future__ import annotations

import math
import textwrap
from typing import Mapping

import numpy as np

from sewfmu.components.feed import FeedLinkage, FeedParams
from sewfmu.components.kinematics import AssemblyError
from sewfmu.components.parameters import with_values
from sewfmu.scenarios.files.matplotlib_home import pyplot
from sewfmu.scenarios.mechanisms.animation import angle_label, reach
from sewfmu.scenarios.mechanisms.base import (
    Mechanism,
    RegressionCase,
    Study,
    column,
    last_revolution,
    parameters,
    shaft_at,
)
from sewfmu.scenarios.mechanisms.sampling import sampled

# the key figures of a run and their units (summary.json, sweeps, reports)
FIGURES = {"phi3_swing_deg": "deg", "phi5_swing_deg": "deg", "phi7_swing_deg": "deg",
           "M_path_width_mm": "mm", "M_path_height_mm": "mm",
           "min_transmission_angle_C_deg": "deg", "min_transmission_angle_N_deg": "deg",
           "min_transmission_angle_F_deg": "deg"}

L5_L4_RATIOS = (3.5, 4.5, 5.5, 6.0, 6.5, 7.0)
ROD_RATIOS = tuple(round(0.7 + 0.05 * k, 2) for k in range(21))     # 0.7 to 1.7


def _phi1():
    """The crank angles of the studies: every 0.5° of a turn."""
    return np.radians(np.arange(0.0, 360.0, 0.5))


def _swing_deg(angles: np.ndarray) -> float:
    return float(np.degrees(np.ptp(np.unwrap(angles))))


def summary_of_run(result) -> dict:
    last = last_revolution(result)
    col = lambda name: column(result, "feed", name)[last]
    return {
        "phi3_swing_deg": _swing_deg(col("phi3")),
        "phi5_swing_deg": _swing_deg(col("phi5")),
        "phi7_swing_deg": _swing_deg(col("phi7")),
        "M_path_width_mm": float(np.ptp(col("M_x")) * 1e3),
        "M_path_height_mm": float(np.ptp(col("M_y")) * 1e3),
        "min_transmission_angle_C_deg": float(np.degrees(col("mu_C").min())),
        "min_transmission_angle_N_deg": float(np.degrees(col("mu_N").min())),
        "min_transmission_angle_F_deg": float(np.degrees(col("mu_F").min())),
    }


def _draw(ax, model: FeedLinkage, phi1: float, color) -> None:
    j = model.motion(phi1).joints
    for chain in (("A", "B", "C", "D", "E", "F", "H", "G", "N", "K", "A"), ("H", "M")):
        ax.plot([j[n].x * 1e3 for n in chain], [j[n].y * 1e3 for n in chain], "o-", color=color,
                lw=1, ms=2.5)
    ax.plot([], [], "-", color=color, label=f"φ1 = {math.degrees(phi1):.0f}°")


def plot(curves, path, title: str) -> None:
    """The mechanism at four crank angles with M's path; φ3, φ7, φ5 against φ1."""
    plt = pyplot()          # matplotlib, its files out of the user's home

    fig = plt.figure(figsize=(12, 8))
    ax_mech = fig.add_subplot(1, 2, 1)
    ax_zoom = fig.add_subplot(2, 2, 2)
    ax_ang = fig.add_subplot(2, 2, 4)
    for label, result in curves:
        model = FeedLinkage(with_values(FeedParams(), **parameters(result, "feed")))
        for k, phi1 in enumerate(np.radians([0, 90, 180, 270])):
            _draw(ax_mech, model, phi1, f"C{k}")
        last = last_revolution(result)
        mx, my = column(result, "feed", "M_x")[last] * 1e3, column(result, "feed", "M_y")[last] * 1e3
        ax_mech.plot(mx, my, "k-", lw=2, label="path of M")
        ax_zoom.plot(mx, my, "k-", lw=1.5)
        for k, phi1 in enumerate(np.radians([0, 90, 180, 270])):
            m = model.motion(phi1).joints["M"]
            ax_zoom.plot(m.x * 1e3, m.y * 1e3, "o", color=f"C{k}")
        phi = column(result, "shaft", "phi")[last]
        deg = np.degrees(phi - phi[0])
        for name in ("phi3", "phi7", "phi5"):
            values = np.degrees(np.unwrap(column(result, "feed", name)[last]))
            ax_ang.plot(deg, values - values.mean(), label=f"{name} − {values.mean():.1f}°")
    ax_mech.set(aspect="equal", xlabel="x [mm]", ylabel="y [mm]", title="mechanism and M's path")
    ax_zoom.set(aspect="equal", xlabel="x [mm]", ylabel="y [mm]", title="feed-dog path of M")
    ax_ang.set(xlabel="crank angle φ1 [°]", ylabel="angle about its mean [°]")
    for ax in (ax_mech, ax_zoom, ax_ang):
        ax.grid(alpha=0.3)
    ax_mech.legend(fontsize=8, loc="upper right")
    ax_ang.legend(fontsize=8)
    fig.suptitle("\n".join(textwrap.wrap(title, 90)), fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --- the lever-ratio study -----------------------------------------------------------------------
def _case(params: FeedParams, **changes) -> dict:
    try:
        motion = sampled(FeedLinkage(with_values(params, **changes)).motion, _phi1())
    except AssemblyError as err:
        return {"assembles": False, "error": str(err)}
    phi5 = np.degrees(np.unwrap(motion.phi5.value))
    return {"assembles": True, "phi5_amplitude_deg": float(np.ptp(phi5)),
            "phi5_deg": phi5.round(6).tolist()}


def ratio_study(given: Mapping[str, Mapping] | None = None) -> dict:
    """φ5's swing for lever ratios l5/l4 and rod ratios l2/l8 about the feed mechanism as
    `given` sets it ({"feed": {parameter: value}})."""
    base = with_values(FeedParams(), **(given or {}).get("feed", {}))
    design = _case(base)
    if not design["assembles"]:             # the design itself: its ratios mean nothing
        raise AssemblyError(design["error"])
    lever = []
    for ratio in L5_L4_RATIOS:
        case = _case(base, l4=base.l5 / ratio)
        lever.append({"l5_over_l4": ratio, "l4_mm": base.l5 / ratio * 1e3, **case})
    rods = []
    for ratio in ROD_RATIOS:
        case = _case(base, l2=base.l8 * float(ratio))
        rods.append({"l2_over_l8": float(ratio), "l2_mm": base.l8 * float(ratio) * 1e3, **case})
    return {"phi1_deg": np.degrees(_phi1()).tolist(), "design": design,
            "l5_over_l4": base.l5 / base.l4, "l2_over_l8": base.l2 / base.l8,
            "lever_ratio": lever, "rod_ratio": rods}


def plot_study(study: dict, path) -> None:
    plt = pyplot()          # matplotlib, its files out of the user's home

    fig, (ax_curves, ax_lever, ax_rods) = plt.subplots(1, 3, figsize=(15, 4.8))
    for row in study["lever_ratio"]:
        if row["assembles"]:
            phi5 = np.asarray(row["phi5_deg"])
            ax_curves.plot(study["phi1_deg"], phi5 - phi5.mean(), label=f"l5/l4 = {row['l5_over_l4']}")
    ax_curves.set(xlabel="crank angle φ1 [°]", ylabel="φ5 about its mean [°]",
                  title="feed-bar lever swing φ5(φ1) (cf. the paper's fig. 2b)")
    ax_curves.legend(fontsize=8)
    for ax, key, rows, label in ((ax_lever, "l5_over_l4", study["lever_ratio"], "l5 / l4"),
                                 (ax_rods, "l2_over_l8", study["rod_ratio"], "l2 / l8 (rod 2 / rod 8)")):
        ok = [r for r in rows if r["assembles"]]
        bad = [r for r in rows if not r["assembles"]]
        ax.plot([r[key] for r in ok], [r["phi5_amplitude_deg"] for r in ok], "o-")
        if bad:
            ax.plot([r[key] for r in bad], [0.0] * len(bad), "rx", ms=8, label="cannot assemble")
            ax.legend(fontsize=8)
        ax.set(xlabel=label, ylabel="amplitude (swing) of φ5 [°]")
    ax_lever.axvspan(5.0, 6.5, color="C2", alpha=0.15)
    ax_lever.set_title("recommended 5.0 … 6.5 shaded")
    ax_rods.set_title("branch rod-length ratio")
    for ax in (ax_curves, ax_lever, ax_rods):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _headline(study: dict) -> dict:
    """Numbers a sweep can plot: the design's ratios and swing, and the range of each ratio
    over which the mechanism assembles (the amplitude at each ratio is in study.json)."""
    def assembling(rows, key, end):
        ok = [r[key] for r in rows if r["assembles"]]
        return end(ok) if ok else math.nan

    design = study["design"]
    return {"l5_over_l4": study["l5_over_l4"], "l2_over_l8": study["l2_over_l8"],
            "phi5_amplitude_deg": design["phi5_amplitude_deg"] if design["assembles"]
            else math.nan,
            "lowest_assembling_l2_over_l8": assembling(study["rod_ratio"], "l2_over_l8", min),
            "highest_assembling_l2_over_l8": assembling(study["rod_ratio"], "l2_over_l8", max)}


# --- the drawing (the GIF, the page) ------------------------------------------------------------
MM = 1e3
CHAINS = (("A", "B", "C", "D"), ("D", "E"), ("E", "F", "H", "G"), ("G", "N", "K", "A"), ("H", "M"))


class Scene:
    to_scale = True
    tracked = "M"

    def __init__(self, result):
        self.result = result
        self.model = FeedLinkage(with_values(FeedParams(), **parameters(result, "feed")))
        self.phi = column(result, "shaft", "phi")
        self.mx = column(result, "feed", "M_x") * MM
        self.my = column(result, "feed", "M_y") * MM
        self.last = last_revolution(result).nonzero()[0]
        self.xlim, self.ylim = reach(self._joints, self.last, 12.0)
        self.inset = None

    def _joints(self, i: int) -> dict[str, tuple[float, float]]:
        return {n: (m.x * MM, m.y * MM) for n, m in self.model.motion(self.phi[i]).joints.items()}

    def points(self, i: int) -> dict[str, tuple[float, float]]:
        """The joints at sample i (mm), M where it was recorded."""
        return {**self._joints(i), "M": (self.mx[i], self.my[i])}

    def chains(self) -> list[tuple[str, ...]]:
        return list(CHAINS)

    def draw(self, ax, i: int) -> tuple[float, float]:
        j = self._joints(i)
        for chain in CHAINS:
            ax.plot(*zip(*[j[n] for n in chain]), "o-", color="0.25", lw=1.4, ms=2.5)
        for pivot in ("A", "D", "G"):
            ax.plot(*j[pivot], "^", color="0.4", ms=7)
        done = self.last[self.last <= i]
        ax.plot(self.mx[self.last], self.my[self.last], color="0.85", lw=1)   # the whole path
        ax.plot(self.mx[done], self.my[done], color="#aa3377", lw=1.6)       # traced so far
        self._draw_zoom(ax, i, done)
        ax.set_title(f"feed mechanism   {angle_label(self.result, i)}", fontsize=9)
        ax.set_xlabel("x [mm]", fontsize=8)
        ax.tick_params(labelsize=7)
        return self.mx[i], self.my[i]

    def _draw_zoom(self, ax, i: int, done) -> None:
        """M's path enlarged (an inset, to scale at its own magnification)."""
        if self.inset is not None:
            self.inset.remove()
        inset = self.inset = ax.inset_axes([0.05, 0.5, 0.4, 0.45])
        mx, my = self.mx[self.last], self.my[self.last]
        inset.plot(mx, my, color="0.8", lw=1)
        inset.plot(self.mx[done], self.my[done], color="#aa3377", lw=1.6)
        inset.plot(self.mx[i], self.my[i], "o", color="#aa3377", ms=4)
        pad = 0.15 * max(np.ptp(mx), np.ptp(my))
        inset.set_xlim(mx.min() - pad, mx.max() + pad)
        inset.set_ylim(my.min() - pad, my.max() + pad)
        inset.set_aspect("equal")
        inset.set_title("path of M, enlarged", fontsize=7)
        inset.tick_params(labelsize=6)

class Feed(Mechanism):
    """The lever-hinge feed mechanism: the shaft drives the feed dog M through two branches."""
    name = "feed"
    roles = {"shaft": "MainShaft", "feed": "FeedLinkage"}
    figures = FIGURES
    Scene = Scene
    kinematic = True
    regression = {"FeedLinkage": RegressionCase(2 * math.pi / 303.5, 5e-5, shaft_at(303.5))}
    studies = {"feed_ratio": Study(
        "Feed mechanism: swing of the feed-bar lever φ5 for l5/l4 from 3.5 to 7.0 and for the "
        "branches' rod-length ratio l2/l8 from 0.7 to 1.7", ratio_study, plot_study, _headline,
        units={"l5_over_l4": "1", "l2_over_l8": "1", "phi5_amplitude_deg": "deg",
               "lowest_assembling_l2_over_l8": "1", "highest_assembling_l2_over_l8": "1"},
        roles=("feed",))}
    summary_of_run = staticmethod(summary_of_run)
    plot = staticmethod(plot)


MECHANISM = Feed()
