"""The thread take-up: key figures, plots, and the tolerance study of the eye's path.

The paper (Qiu, Pan, Xu 2019) differentiated E's path numerically, by central differences with
Δθ = 0.5°. The scenario `takeup` records E at exactly that crank-angle step, so the paper's
velocity is the central difference of the recorded positions, and it is set beside the analytic
velocity that the FMU outputs.
"""
from __future__ import annotations

import dataclasses
import math
import textwrap
from typing import Mapping

import numpy as np

from sewfmu.components.kinematics import AssemblyError
from sewfmu.components.parameters import with_values
from sewfmu.components.takeup import TakeupLinkage, TakeupParams
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
FIGURES = {"path_extent_z_mm": "mm", "path_extent_x_mm": "mm", "stroke_mm": "mm",
           "peak_speed_m_s": "m/s", "peak_acceleration_m_s2": "m/s2",
           "central_difference_step_deg": "deg", "central_difference_max_error_m_s": "m/s",
           "central_difference_max_error_percent_of_peak_speed": "%"}

LINKS = ("L_AB", "L_BC", "L_CD", "L_BE")


def central_difference(result):
    """The paper's velocity of E from the recorded samples: dE/dθ by central differences, × ω.
    NaN at the two ends, where a neighbour is missing."""
    phi, omega = column(result, "shaft", "phi"), column(result, "shaft", "omega")
    out = []
    for axis in ("z", "x"):
        e = column(result, "takeup", f"E_{axis}")
        v = np.full_like(e, np.nan)
        v[1:-1] = (e[2:] - e[:-2]) / (phi[2:] - phi[:-2]) * omega[1:-1]
        out.append(v)
    return out


def path_stroke(e_z: np.ndarray, e_x: np.ndarray) -> float:
    """The largest distance between two points of E's path: the eye's stroke, a measure of the
    thread amount it pulls per stitch."""
    pts = np.column_stack([e_z, e_x])
    hull = pts if len(pts) < 4 else pts[_convex_hull(pts)]
    diff = hull[:, None, :] - hull[None, :, :]
    return float(np.sqrt((diff ** 2).sum(-1)).max())


def _convex_hull(pts: np.ndarray) -> list[int]:
    """Indices of the convex hull (monotone chain); the diameter is between hull points."""
    order = np.lexsort((pts[:, 1], pts[:, 0]))

    def half(indices):
        chain: list[int] = []
        for i in indices:
            while len(chain) >= 2:
                o, a = pts[chain[-2]], pts[chain[-1]]
                if (a[0] - o[0]) * (pts[i][1] - o[1]) - (a[1] - o[1]) * (pts[i][0] - o[0]) > 0:
                    break
                chain.pop()
            chain.append(int(i))
        return chain

    lower, upper = half(order), half(order[::-1])
    return lower[:-1] + upper[:-1]


def summary_of_run(result) -> dict:
    last = last_revolution(result)
    eye = lambda name: column(result, "takeup", name)[last]
    ez, ex, vz, vx, az, ax = (eye(n) for n in ("E_z", "E_x", "E_vz", "E_vx", "E_az", "E_ax"))
    cd_z, cd_x = (v[last] for v in central_difference(result))
    speed = np.hypot(vz, vx)
    cd_error = np.hypot(cd_z - vz, cd_x - vx)
    d_theta = np.diff(column(result, "shaft", "phi")).mean()
    return {
        "path_extent_z_mm": float(np.ptp(ez) * 1e3),
        "path_extent_x_mm": float(np.ptp(ex) * 1e3),
        "stroke_mm": path_stroke(ez, ex) * 1e3,
        "peak_speed_m_s": float(speed.max()),
        "peak_acceleration_m_s2": float(np.hypot(az, ax).max()),
        "central_difference_step_deg": float(math.degrees(d_theta)),
        "central_difference_max_error_m_s": float(np.nanmax(cd_error)),
        "central_difference_max_error_percent_of_peak_speed":
            float(np.nanmax(cd_error) / speed.max() * 100),
    }


def _model_of(result) -> TakeupLinkage:
    return TakeupLinkage(with_values(TakeupParams(), **parameters(result, "takeup")))


def plot(curves, path, title: str) -> None:
    """E's path with the linkage drawn at four crank angles; displacement, speed (analytic and
    central-difference) and acceleration of E against the crank angle (last revolution)."""
    plt = pyplot()          # matplotlib, its files out of the user's home

    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    (ax_path, ax_disp), (ax_speed, ax_acc) = axes
    for label, result in curves:
        last = last_revolution(result)
        eye = lambda name: column(result, "takeup", name)[last]
        phi = column(result, "shaft", "phi")[last]
        deg = np.degrees(phi - phi[0])
        ez, ex = eye("E_z") * 1e3, eye("E_x") * 1e3
        ax_path.plot(ez, ex, lw=2, label=f"E ({label})")
        ax_disp.plot(deg, np.hypot(ez - ez[0], ex - ex[0]), label=label)
        speed = np.hypot(eye("E_vz"), eye("E_vx"))
        cd_z, cd_x = (v[last] for v in central_difference(result))
        ax_speed.plot(deg, speed, label=f"analytic ({label})")
        ax_speed.plot(deg, np.hypot(cd_z, cd_x), "--", label="central difference, Δθ = 0.5°")
        err = ax_speed.twinx()
        err.plot(deg, np.hypot(cd_z - eye("E_vz"), cd_x - eye("E_vx")), color="C3", lw=0.8)
        err.set_ylabel("|difference| [m/s]", color="C3")
        ax_acc.plot(deg, np.hypot(eye("E_az"), eye("E_ax")), label=label)
        model = _model_of(result)
        for theta, color in ((0.0, "C2"), (math.pi, "C4")):
            m = model.motion(theta)
            joints = [(0.0, 0.0), (m.B.x, m.B.y), (m.C.x, m.C.y), (model.p.z_D, model.p.x_D)]
            coupler = [(m.B.x, m.B.y), (m.E.x, m.E.y), (m.C.x, m.C.y)]
            for pts, style in ((joints, "o-"), (coupler, "--")):
                zs, xs = zip(*[(a * 1e3, b * 1e3) for a, b in pts])
                ax_path.plot(zs, xs, style, color=color, lw=1, ms=3)
            ax_path.plot([], [], "-", color=color, lw=1,
                         label=f"A-B-C-D and triangle BCE at θ = {math.degrees(theta):.0f}°")
    ax_path.set_aspect("equal")
    ax_path.set(xlabel="Z [mm]", ylabel="X [mm]", title="path of the take-up eye E")
    ax_disp.set(xlabel="crank angle θ [°]", ylabel="displacement of E from θ = 0 [mm]")
    ax_speed.set(xlabel="crank angle θ [°]", ylabel="speed of E [m/s]")
    ax_acc.set(xlabel="crank angle θ [°]", ylabel="acceleration of E [m/s²]")
    for ax in (ax_disp, ax_speed, ax_acc):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    ax_path.grid(alpha=0.3)
    ax_path.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.suptitle("\n".join(textwrap.wrap(title, 90)), fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --- the tolerance study --------------------------------------------------------------------------
TOLERANCE = 0.1e-3            # ±0.1 mm on each link length
PIN_ADJUSTMENT = np.linspace(-1.0e-3, 1.0e-3, 9)   # the eccentric pin changes L_CD by up to ±1 mm
_THETA = np.radians(np.arange(0.0, 360.0, 0.5))


def _path(params: TakeupParams):
    linkage = TakeupLinkage(params)
    e = sampled(lambda theta: linkage.motion(theta).E, _THETA)
    return e.x, e.y


def tolerance_study(given: Mapping[str, Mapping] | None = None) -> dict:
    """E's path under link-length errors and under the eccentric-pin adjustment of L_CD, about
    the take-up as `given` sets it ({"takeup": {parameter: value}})."""
    nominal = with_values(TakeupParams(), **(given or {}).get("takeup", {}))
    z0, x0 = _path(nominal)
    stroke0 = path_stroke(z0, x0)
    rows = []
    for link in LINKS:
        for sign in (-1, +1):
            delta = sign * TOLERANCE
            row = {"parameter": link, "change_mm": delta * 1e3}
            try:
                z, x = _path(with_values(nominal, **{link: getattr(nominal, link) + delta}))
            except AssemblyError as err:
                row["error"] = str(err)
            else:
                row["max_path_deviation_mm"] = float(np.hypot(z - z0, x - x0).max() * 1e3)
                row["stroke_change_mm"] = (path_stroke(z, x) - stroke0) * 1e3
            rows.append(row)
    pin = []
    for delta in PIN_ADJUSTMENT:
        row = {"parameter": "L_CD (eccentric pin)", "change_mm": float(delta * 1e3)}
        try:
            z, x = _path(with_values(nominal, L_CD=nominal.L_CD + delta))
        except AssemblyError as err:
            row["error"] = str(err)
        else:
            row["stroke_mm"] = path_stroke(z, x) * 1e3
            row["stroke_change_mm"] = row["stroke_mm"] - stroke0 * 1e3
            row["max_path_deviation_mm"] = float(np.hypot(z - z0, x - x0).max() * 1e3)
        pin.append(row)
    ok = [r for r in pin if "stroke_mm" in r]
    slope = float(np.polyfit([r["change_mm"] for r in ok], [r["stroke_mm"] for r in ok], 1)[0])
    return {"nominal_stroke_mm": stroke0 * 1e3, "link_tolerance_mm": TOLERANCE * 1e3,
            "design": dataclasses.asdict(nominal), "links": rows, "pin_adjustment": pin,
            "stroke_change_per_mm_of_pin_adjustment": slope}


def plot_tolerance(study: dict, path) -> None:
    plt = pyplot()          # matplotlib, its files out of the user's home

    fig, (ax_path, ax_bar, ax_pin) = plt.subplots(1, 3, figsize=(15, 4.8))
    nominal = with_values(TakeupParams(), **study["design"])
    for delta in (-1e-3, 0.0, 1e-3):
        z, x = _path(with_values(nominal, L_CD=nominal.L_CD + delta))
        ax_path.plot(z * 1e3, x * 1e3, label=f"L_CD {delta * 1e3:+.0f} mm")
    ax_path.set(aspect="equal", xlabel="Z [mm]", ylabel="X [mm]",
                title="E's path under the eccentric-pin adjustment")
    ax_path.legend(fontsize=8)
    labels = [f"{r['parameter']} {r['change_mm']:+.1f}" for r in study["links"]]
    ax_bar.barh(labels, [r.get("max_path_deviation_mm", np.nan) for r in study["links"]])
    ax_bar.set(xlabel="largest shift of E at equal crank angle [mm]",
               title=f"link lengths off by ±{study['link_tolerance_mm']:.1f} mm")
    ok = [r for r in study["pin_adjustment"] if "stroke_mm" in r]
    ax_pin.plot([r["change_mm"] for r in ok], [r["stroke_mm"] for r in ok], "o-")
    ax_pin.set(xlabel="eccentric-pin adjustment of L_CD [mm]", ylabel="stroke of E [mm]",
               title=f"{study['stroke_change_per_mm_of_pin_adjustment']:+.2f} mm of stroke per mm")
    for ax in (ax_path, ax_bar, ax_pin):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


REGRESSION_SPEED = 523.5987755982989      # rad/s: 5000 rpm, one revolution for its reference


# --- the drawing (the GIF, the page) ------------------------------------------------------------
MM = 1e3


class Scene:
    to_scale = True
    tracked = "E"

    def __init__(self, result):
        self.result = result
        self.model = TakeupLinkage(with_values(TakeupParams(),
                                               **parameters(result, "takeup")))
        self.phi = column(result, "shaft", "phi")
        self.ez = column(result, "takeup", "E_z") * MM
        self.ex = column(result, "takeup", "E_x") * MM
        self.last = last_revolution(result).nonzero()[0]
        self.xlim, self.ylim = reach(self._joints, self.last, 8.0)

    def _joints(self, i: int) -> dict[str, tuple[float, float]]:
        m, p = self.model.motion(self.phi[i]), self.model.p
        return {"A": (0.0, 0.0), "B": (m.B.x * MM, m.B.y * MM), "C": (m.C.x * MM, m.C.y * MM),
                "D": (p.z_D * MM, p.x_D * MM), "E": (m.E.x * MM, m.E.y * MM)}

    def points(self, i: int) -> dict[str, tuple[float, float]]:
        """The joints at sample i (mm), the eye E where it was recorded."""
        return {**self._joints(i), "E": (self.ez[i], self.ex[i])}

    def chains(self) -> list[tuple[str, ...]]:
        return [("A", "B", "C", "D"), ("B", "E", "C")]

    def draw(self, ax, i: int) -> tuple[float, float]:
        j = self._joints(i)
        ax.plot(*zip(*[j[n] for n in ("A", "B", "C", "D")]), "o-", color="0.25", lw=1.5, ms=3)
        ax.fill(*zip(*[j[n] for n in ("B", "C", "E")]), color="#4477aa", alpha=0.35)
        ax.plot(*zip(*[j[n] for n in ("B", "E", "C")]), "-", color="#4477aa", lw=1.2)
        for pivot in ("A", "D"):
            ax.plot(*j[pivot], "^", color="0.4", ms=7)
        done = self.last[self.last <= i]
        ax.plot(self.ez[self.last], self.ex[self.last], color="0.85", lw=1)
        ax.plot(self.ez[done], self.ex[done], color="#aa3377", lw=1.6)
        ax.set_title(f"thread take-up   {angle_label(self.result, i)}", fontsize=9)
        ax.set_xlabel("Z [mm]", fontsize=8)
        ax.set_ylabel("X [mm]", fontsize=8)
        ax.tick_params(labelsize=7)
        return self.ez[i], self.ex[i]

class Takeup(Mechanism):
    """The four-bar thread take-up: the eye E on the coupler traces the willow leaf."""
    name = "takeup"
    roles = {"shaft": "MainShaft", "takeup": "TakeupLinkage"}
    figures = FIGURES
    Scene = Scene
    kinematic = True
    regression = {"TakeupLinkage": RegressionCase(2 * math.pi / REGRESSION_SPEED, 2e-5,
                                                  shaft_at(REGRESSION_SPEED))}
    studies = {"takeup_tolerance": Study(
        "Thread take-up: E's path with link lengths off by ±0.1 mm, and the stroke against the "
        "eccentric-pin adjustment of L_CD (±1 mm)", tolerance_study, plot_tolerance,
        lambda s: {k: s[k] for k in ("nominal_stroke_mm",
                                     "stroke_change_per_mm_of_pin_adjustment")},
        units={"nominal_stroke_mm": "mm", "stroke_change_per_mm_of_pin_adjustment": "mm/mm"},
        roles=("takeup",))}
    summary_of_run = staticmethod(summary_of_run)
    plot = staticmethod(plot)


MECHANISM = Takeup()
