"""The carriage of the coordinate device: start-stop response, and the resonance study.

The resonance study needs the steady state at 71 stitch rates for three designs. Rather than
co-simulating each rate until the transient has died out (seconds of simulated time each), it
computes the periodic steady state directly: the exact one-stitch map of each mode (the same
exact discretization as the FMU, for an acceleration linear over each step) gives the initial
state that repeats itself after one stitch. The test suite checks this against the FMU
co-simulation of carriage_startstop and against a frequency-domain (harmonic) solution.
"""
from __future__ import annotations

import math
import textwrap
from typing import Mapping

import numpy as np

from sewfmu.components.carriage import (
    CarriageDrive,
    CarriageDriveParams,
    CarriageModal,
    CarriageParams,
)
from sewfmu.components.oscillator import DampedOscillator
from sewfmu.components.parameters import with_values
from sewfmu.scenarios.files.matplotlib_home import pyplot
from sewfmu.scenarios.mechanisms.animation import angle_label
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
FIGURES = {"omega1": "rad/s", "omega2": "rad/s", "stitch_rate_per_min": "1/min",
           "peak_abs_U2_last_stitch_um": "um", "peak_abs_U2_um": "um"}

RATES = tuple(600.0 + 20.0 * k for k in range(71))      # stitches/min, 600 to 2000
MACHINE_RATE = 1600.0                                    # the catalogue's shaft speed
STEPS_PER_STITCH = 360
# the carriage as the scenario sets it, and the paper's two remedies relative to it
STIFFER, SHORTER = "traverse twice as stiff (EJ × 2)", "cantilever 0.1 m shorter"


def summary_of_run(result) -> dict:
    model = CarriageModal(with_values(CarriageParams(), **parameters(result, "carriage")))
    last = last_revolution(result)
    omega = float(column(result, "shaft", "omega")[-1])
    u2 = column(result, "carriage", "U2")
    return {"omega1": float(model.omega[0]), "omega2": float(model.omega[1]),
            "stitch_rate_per_min": omega * 60 / (2 * math.pi),
            "peak_abs_U2_last_stitch_um": float(np.abs(u2[last]).max() * 1e6),
            "peak_abs_U2_um": float(np.abs(u2).max() * 1e6)}


def plot(curves, path, title: str) -> None:
    plt = pyplot()          # matplotlib, its files out of the user's home

    fig, (ax_x, ax_a, ax_u) = plt.subplots(3, 1, sharex=True, figsize=(10, 8))
    for label, result in curves:
        t = result.time
        last = t >= t[-1] - 5 * 60 / summary_of_run(result)["stitch_rate_per_min"]
        ax_x.plot(t[last], column(result, "drive", "x")[last] * 1e3)
        ax_a.plot(t[last], column(result, "drive", "a")[last])
        ax_u.plot(t[last], column(result, "carriage", "U2")[last] * 1e6, label="U2 (tip, at B)")
        ax_u.plot(t[last], column(result, "carriage", "U1")[last] * 1e6, label="U1 (at A)")
    ax_x.set_ylabel("table position x [mm]")
    ax_a.set_ylabel("table acceleration [m/s²]")
    ax_u.set_ylabel("deflection [µm]")
    ax_u.set_xlabel("time [s] (the last five stitches)")
    ax_u.legend(fontsize=8)
    for ax in (ax_x, ax_a, ax_u):
        ax.grid(alpha=0.3)
    fig.suptitle("\n".join(textwrap.wrap(title, 90)), fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --- periodic steady state ------------------------------------------------------------------------
def _step_maps(model: CarriageModal, h: float):
    """Per mode: the exact one-step map x' = Φ·x + g0·a0 + g1·a1 for a(τ) = a0 + a1·τ."""
    maps = []
    for i in range(2):
        w, g = model.omega[i], -model.modal_load[i]
        b, c = 2 * model.p.zeta * w, w * w
        cols = [DampedOscillator(1.0, b, c, 0.0, 0.0, 0.0, *x0).state(h)
                for x0 in ((1.0, 0.0), (0.0, 1.0))]
        phi = np.array(cols).T
        g0 = np.array(DampedOscillator(1.0, b, c, g, 0.0, 0.0, 0.0, 0.0).state(h))
        g1 = np.array(DampedOscillator(1.0, b, c, 0.0, g, 0.0, 0.0, 0.0).state(h))
        maps.append((phi, g0, g1))
    return maps


def periodic_response(model: CarriageModal, drive: CarriageDrive, rate_per_min: float,
                      steps: int = STEPS_PER_STITCH):
    """Steady-state U over one stitch (time, U of shape (2, steps + 1)) at a constant rate."""
    omega = rate_per_min * 2 * math.pi / 60
    period = 2 * math.pi / omega
    h = period / steps
    t = np.arange(steps + 1) * h
    _, _, acc, jerk = sampled(drive.motion, omega * t, omega, 0.0)
    q = np.zeros((2, 2, steps + 1))            # mode, (q, q'), time
    for i, (phi, g0, g1) in enumerate(_step_maps(model, h)):
        # the forced part over one stitch from rest, then the initial state that repeats
        x = np.zeros(2)
        forced = np.empty((2, steps + 1))
        forced[:, 0] = x
        for k in range(steps):
            x = phi @ x + g0 * acc[k] + g1 * jerk[k]
            forced[:, k + 1] = x
        x0 = np.linalg.solve(np.eye(2) - np.linalg.matrix_power(phi, steps), forced[:, -1])
        free = x0.copy()
        for k in range(steps + 1):
            q[i, :, k] = forced[:, k] + free
            free = phi @ free
    return t, np.asarray(model.modes) @ q[:, 0, :]


def resonance_study(given: Mapping[str, Mapping] | None = None) -> dict:
    """The steady-state peak |U2| over RATES for the carriage as `given` sets it ({role:
    {parameter: value}}: carriage, drive, and the shaft's omega0 as the machine's stitch rate)
    and for the paper's two remedies applied to it."""
    given = given or {}
    carriage = with_values(CarriageParams(), **given.get("carriage", {}))
    drive = CarriageDrive(with_values(CarriageDriveParams(), **given.get("drive", {})))
    omega0 = given.get("shaft", {}).get("omega0")
    machine = MACHINE_RATE if omega0 is None else float(omega0) * 60 / (2 * math.pi)
    designs = {"the carriage as set": {}, STIFFER: {"EJ": 2 * carriage.EJ},
               SHORTER: {"l": carriage.l - 0.1}}
    curves = {}
    for name, changes in designs.items():
        try:
            model = CarriageModal(with_values(carriage, **changes))
        except ValueError as err:           # a remedy that leaves the parameters' ranges
            curves[name] = {"parameters": changes, "error": str(err)}
            continue
        peaks = [float(np.abs(periodic_response(model, drive, n)[1][1]).max()) for n in RATES]
        at_machine = float(np.abs(periodic_response(model, drive, machine)[1][1]).max())
        k = int(np.argmax(peaks))
        curves[name] = {"parameters": changes, "omega1": float(model.omega[0]),
                        "omega2": float(model.omega[1]),
                        "first_resonance_stitch_rate": float(model.omega[0] * 60 / (2 * math.pi)),
                        "resonant_stitch_rate": float(RATES[k]),
                        "peak_abs_U2_at_machine_rate_um": at_machine * 1e6,
                        "peak_abs_U2_um": [p * 1e6 for p in peaks]}
    base = curves["the carriage as set"]
    if "error" in base:                     # the design itself: nothing to compare it with
        raise ValueError(base["error"])
    return {"omega1": base["omega1"], "omega2": base["omega2"],
            "resonant_stitch_rate": base["resonant_stitch_rate"],
            "machine_stitch_rate": machine,
            "peak_abs_U2_at_machine_rate_um": base["peak_abs_U2_at_machine_rate_um"],
            "stitch_rates_per_min": list(RATES), "designs": curves}


def plot_resonance(study: dict, path) -> None:
    plt = pyplot()          # matplotlib, its files out of the user's home

    fig, ax = plt.subplots(figsize=(9, 5))
    for name, curve in study["designs"].items():
        if "error" in curve:
            continue
        ax.plot(study["stitch_rates_per_min"], curve["peak_abs_U2_um"], "o-", ms=3,
                label=f"{name}: ω1 = {curve['omega1']:.0f} rad/s")
    machine = study["machine_stitch_rate"]
    ax.axvline(machine, color="k", ls="--", lw=1)
    ax.text(machine, ax.get_ylim()[1] * 0.95, f" the machine: {machine:.0f} /min", fontsize=9)
    ax.set(xlabel="stitch rate [stitches/min]", ylabel="steady-state peak |U2| [µm]",
           title="Resonance of the carriage under start-stop stitches")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def base_motion(t) -> dict:
    """The drive's start-stop acceleration of the carriage's base at 1600 stitches/min (the
    modal model's regression input)."""
    omega = 1600 * 2 * math.pi / 60
    _, _, a, jerk = sampled(CarriageDrive().motion, omega * t, omega, 0.0)
    return {"a_base": a, "a_base_dot": jerk}


# --- the drawing (the GIF, the page) ------------------------------------------------------------
MM = 1e3
TABLE = (4.0, 2.0)       # mm: the table as drawn (width, height)


class Scene:
    to_scale = True
    tracked = "table"

    def __init__(self, result):
        self.result = result
        self.model = CarriageModal(with_values(CarriageParams(),
                                               **parameters(result, "carriage")))
        self.x = column(result, "drive", "x") * MM
        self.u1 = column(result, "carriage", "U1")
        self.u2 = column(result, "carriage", "U2")
        last = last_revolution(result)
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

class Carriage(Mechanism):
    """The carriage of the coordinate device: the shaft's cam drive moves the table, whose guide
    deflects in two modes."""
    name = "carriage"
    roles = {"shaft": "MainShaft", "drive": "CarriageDrive", "carriage": "CarriageModal"}
    figures = FIGURES
    Scene = Scene
    regression = {"CarriageDrive": RegressionCase(2 * math.pi / 167.55160819145564, 1e-4,
                                                  shaft_at(167.55160819145564)),
                  "CarriageModal": RegressionCase(3 * 60 / 1600, 1e-4, base_motion)}
    studies = {"carriage_resonance": Study(
        "Carriage: steady-state peak tip deflection |U2| for 600 to 2000 stitches/min, the "
        "paper's carriage and its two remedies", resonance_study, plot_resonance,
        lambda s: {k: s[k] for k in ("omega1", "omega2", "resonant_stitch_rate",
                                     "machine_stitch_rate", "peak_abs_U2_at_machine_rate_um")},
        units={"omega1": "rad/s", "omega2": "rad/s", "resonant_stitch_rate": "1/min",
               "machine_stitch_rate": "1/min", "peak_abs_U2_at_machine_rate_um": "um"},
        roles=("shaft", "drive", "carriage"))}
    summary_of_run = staticmethod(summary_of_run)
    plot = staticmethod(plot)


MECHANISM = Carriage()
