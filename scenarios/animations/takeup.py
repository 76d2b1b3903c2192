"""The thread take-up moving: the four-bar A-B-C-D with the coupler triangle B-C-E (from the
linkage model at the recorded crank angle) and the eye E at its recorded position, tracing the
willow leaf."""
from __future__ import annotations

from sewfmu.components.parameters import with_values
from sewfmu.components.takeup import TakeupLinkage, TakeupParams
from sewfmu.scenarios import analyses
from sewfmu.scenarios.animations import angle_label, reach

MM = 1e3


class Scene:
    to_scale = True
    tracked = "E"

    def __init__(self, result):
        self.result = result
        self.model = TakeupLinkage(with_values(TakeupParams(),
                                               **analyses.parameters(result, "takeup")))
        self.phi = analyses.column(result, "shaft", "phi")
        self.ez = analyses.column(result, "takeup", "E_z") * MM
        self.ex = analyses.column(result, "takeup", "E_x") * MM
        self.last = analyses.last_revolution(result).nonzero()[0]
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
