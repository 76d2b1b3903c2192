"""The feed mechanism moving: the closed lever-hinge chain (from the linkage model at the
recorded crank angle) and the feed-dog point M at its recorded position, tracing its path."""
from __future__ import annotations

import numpy as np

from sewfmu.components.feed import FeedLinkage, FeedParams
from sewfmu.components.parameters import with_values
from sewfmu.scenarios import analyses
from sewfmu.scenarios.animations import angle_label, reach

MM = 1e3
CHAINS = (("A", "B", "C", "D"), ("D", "E"), ("E", "F", "H", "G"), ("G", "N", "K", "A"), ("H", "M"))


class Scene:
    to_scale = True
    tracked = "M"

    def __init__(self, result):
        self.result = result
        self.model = FeedLinkage(with_values(FeedParams(), **analyses.parameters(result, "feed")))
        self.phi = analyses.column(result, "shaft", "phi")
        self.mx = analyses.column(result, "feed", "M_x") * MM
        self.my = analyses.column(result, "feed", "M_y") * MM
        self.last = analyses.last_revolution(result).nonzero()[0]
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
