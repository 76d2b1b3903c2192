"""The carriage moving: the table on its guide at its recorded position (to scale, in the main
drawing), and the guide cantilever with its recorded deflections U1, U2 (an inset, the
deflection exaggerated and labelled so)."""
from __future__ import annotations

import numpy as np

from sewfmu.components.carriage import CarriageModal, CarriageParams
from sewfmu.components.parameters import with_values
from sewfmu.scenarios import analyses
from sewfmu.scenarios.animations import angle_label

MM = 1e3
TABLE = (4.0, 2.0)       # mm: the table as drawn (width, height)


class Scene:
    to_scale = True
    tracked = "table"

    def __init__(self, result):
        self.result = result
        self.model = CarriageModal(with_values(CarriageParams(),
                                               **analyses.parameters(result, "carriage")))
        self.x = analyses.column(result, "drive", "x") * MM
        self.u1 = analyses.column(result, "carriage", "U1")
        self.u2 = analyses.column(result, "carriage", "U2")
        last = analyses.last_revolution(result)
        lo, hi = float(self.x[last].min()), float(self.x[last].max())
        self.xlim = (lo - 4.0, hi + 4.0)
        self.ylim = (-2.0, 12.0)          # the upper part holds the guide's inset
        peak = max(float(np.abs(self.u2[last]).max()), float(np.abs(self.u1[last]).max()), 1e-12)
        # exaggerated so that the largest tip deflection of the stitch shows a tenth of the length
        self.factor = float(10 ** np.floor(np.log10(0.1 * self.model.p.l / peak)))
        self.inset = None

    def points(self, i: int) -> dict[str, tuple[float, float]]:
        """The rail's ends and the table's corners at sample i (mm); the deflection is not drawn."""
        w, h = TABLE
        x = self.x[i]
        return {"rail_left": (self.xlim[0], 0.0), "rail_right": (self.xlim[1], 0.0),
                "T1": (x - w / 2, 0.0), "T2": (x - w / 2, h), "T3": (x + w / 2, h),
                "T4": (x + w / 2, 0.0), "table": (x, 0.0)}

    def chains(self) -> list[tuple[str, ...]]:
        return [("rail_left", "rail_right"), ("T1", "T2", "T3", "T4", "T1")]

    def draw(self, ax, i: int) -> tuple[float, float]:
        ax.plot(self.xlim, [0.0, 0.0], color="0.6", lw=2)                      # the guide rail
        from matplotlib.patches import Rectangle  # matplotlib: only when drawing
        w, h = TABLE
        ax.add_patch(Rectangle((self.x[i] - w / 2, 0.0), w, h, facecolor="#4477aa",
                               edgecolor="0.2"))
        ax.text(self.xlim[0] + 0.3, -1.4, f"table x = {self.x[i]:.3f} mm (to scale)", fontsize=8)
        ax.set_title(f"carriage   {angle_label(self.result, i)}", fontsize=9)
        ax.set_xlabel("x [mm]", fontsize=8)
        ax.tick_params(labelsize=7)
        self._draw_guide(ax, i)
        return self.x[i], 0.0

    def _draw_guide(self, ax, i: int) -> None:
        """The cantilever from root (z = 0) to tip (z = l), its deflection line through U1 at A
        and U2 at B, exaggerated."""
        if self.inset is not None:
            self.inset.remove()
        inset = self.inset = ax.inset_axes([0.06, 0.4, 0.9, 0.45])
        p = self.model.p
        z = np.linspace(0.0, p.l, 40)
        shapes = np.array([self.model.shapes(zz)[0] for zz in z])
        u = (shapes[:, 0] * self.u1[i] + shapes[:, 1] * self.u2[i]) * self.factor * MM
        inset.plot(z * MM, np.zeros_like(z), color="0.8", lw=1)
        inset.plot(z * MM, u, color="#4477aa", lw=2)
        inset.plot([p.a * MM, p.l * MM], [u[np.argmin(abs(z - p.a))], u[-1]], "s", color="0.2",
                   ms=3)
        reach = 0.12 * p.l * MM
        inset.set_ylim(-reach, reach)
        inset.set_xlim(-10.0, p.l * MM + 10.0)
        inset.set_title(f"guide cantilever, z [mm] from the root; deflection × {self.factor:g} "
                        f"(exaggerated)", fontsize=7)
        inset.tick_params(labelsize=6)
