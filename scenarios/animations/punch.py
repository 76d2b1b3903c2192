"""The punch drive moving: the six-bar (from the linkage model at the recorded crank angle), the
slider at the recorded ξ, the punch at its recorded height y over the fabric, spring 11 between
them, and the fabric's pressing force F2 as a bar."""
from __future__ import annotations

import numpy as np

from sewfmu.components.parameters import with_values
from sewfmu.components.punch_linkage import SIX_BAR, PunchLinkage, PunchLinkageParams
from sewfmu.scenarios import analyses
from sewfmu.scenarios.analyses.punch import signal
from sewfmu.scenarios.animations import angle_label

MM = 1e3
HOLDER = 14.0      # mm: slider to punch tip with spring 11 unloaded (Δ = 0), as drawn
PUNCH = 8.0        # mm: height of the punch body
BAR = 25.0         # mm: length of the force bar at the run's largest F2


class Scene:
    to_scale = True
    tracked = "tip"

    def __init__(self, result):
        self.result = result
        self.model = PunchLinkage(with_values(PunchLinkageParams(),
                                              **analyses.parameters(result, "linkage")))
        p = self.model.p
        self.phi = analyses.column(result, "shaft", "phi")
        self.xi = analyses.column(result, "linkage", "xi")
        self.y = signal(result, "y")
        self.F2 = signal(result, "F2")
        self.x = p.x_D * MM
        # the fabric surface in the linkage's frame: the slider's top height less the lift xi0
        self.surface = (self.model.y_top - p.xi0) * MM - HOLDER
        self.F2_scale = max(float(np.max(self.F2[analyses.last_revolution(result)])), 1e-9)
        joints = [self._joints(i) for i in range(0, len(self.phi), max(1, len(self.phi) // 400))]
        xs = [pt[0] for js in joints for pt in js.values()] + [self.x]
        ys = [pt[1] for js in joints for pt in js.values()] + [self.surface]
        self.xlim = (min(xs) - 14.0, max(max(xs), self.x + 14.0) + BAR + 4.0)
        self.ylim = (self.surface - 9.0, max(ys) + 6.0)

    def _joints(self, i: int) -> dict[str, tuple[float, float]]:
        """The six-bar's joints (mm) at sample i; D at the recorded slider height."""
        d = (self.x, self.surface + HOLDER + self.xi[i] * MM)
        if self.model.p.mode != SIX_BAR:
            return {"D": d}
        js = self.model.joints(self.model.alpha0 - self.phi[i])
        out = {name: (m.x * MM, m.y * MM) for name, m in js.items()}
        out["D"] = d
        return out

    def points(self, i: int) -> dict[str, tuple[float, float]]:
        """The drawing's points at sample i (mm), for a page that draws it itself (chains)."""
        tip = self.surface + self.y[i] * MM
        return {**self._joints(i), "top": (self.x, tip + PUNCH), "tip": (self.x, tip),
                "fabric_left": (self.x - 12.0, self.surface), "fabric_right": (self.x + 12.0, self.surface)}

    def chains(self) -> list[tuple[str, ...]]:
        six_bar = (("O1", "A", "B", "O2", "C", "D"),) if self.model.p.mode == SIX_BAR else ()
        return [*six_bar, ("D", "top"), ("top", "tip"), ("fabric_left", "fabric_right")]

    def draw(self, ax, i: int) -> tuple[float, float]:
        j = self._joints(i)
        if "A" in j:
            for chain in (("O1", "A", "B", "O2", "C", "D"),):
                ax.plot(*zip(*[j[n] for n in chain]), "o-", color="0.25", lw=1.6, ms=3)
            ax.plot(*j["B"], "o", color="0.25", ms=3)
            for pivot in ("O1", "O2"):
                ax.plot(*j[pivot], "^", color="0.4", ms=8)
        # slider and its guide
        ax.plot([self.x, self.x], [self.surface + HOLDER - 2, self.ylim[1]], color="0.8", lw=4,
                zorder=0)
        ax.add_patch(_rect(self.x - 2.5, j["D"][1] - 1.5, 5.0, 3.0, "0.55"))
        tip = self.surface + self.y[i] * MM
        top = tip + PUNCH
        _spring(ax, self.x, top, j["D"][1] - 1.5)
        ax.add_patch(_rect(self.x - 3.0, tip, 6.0, PUNCH, "#4477aa"))
        # the fabric, and the force it presses with
        contact = self.F2[i] > 0.0
        ax.add_patch(_rect(self.x - 12.0, self.surface - 3.0, 24.0, 3.0,
                           "#d9a441" if contact else "#eed9a4"))
        length = BAR * self.F2[i] / self.F2_scale
        ax.add_patch(_rect(self.x + 14.0, self.surface - 3.0, max(length, 0.0), 2.0, "#aa3377"))
        ax.text(self.x + 14.0, self.surface - 7.5, f"F2 = {self.F2[i]:5.1f} N", fontsize=8)
        ax.text(self.x - 12.0, self.surface - 7.5, "fabric", fontsize=8)
        ax.set_title(f"punch drive   {angle_label(self.result, i)}", fontsize=9)
        ax.set_xlabel("x [mm]", fontsize=8)
        ax.tick_params(labelsize=7)
        return self.x, tip


def _rect(x, y, w, h, color):
    from matplotlib.patches import Rectangle  # matplotlib: only when drawing
    return Rectangle((x, y), w, h, facecolor=color, edgecolor="0.2", lw=0.6)


def _spring(ax, x, bottom, top, turns=6, width=1.6):
    """A zigzag between two heights: spring 11, its length to scale."""
    zs = np.linspace(bottom, top, 2 * turns + 1)
    xs = x + width * np.array([0] + [(-1) ** k for k in range(2 * turns - 1)] + [0])
    ax.plot(xs, zs, color="0.3", lw=0.9)
