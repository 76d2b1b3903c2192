"""Key figures and plots of the punch drive, like the paper's figure 4 (the last revolution).

The figures are computed from sampled signals, the same way for the co-simulation's recorded
communication points and for the monolithic reference's dense samples:

- contact intervals are the runs of samples with contact; an onset is placed where y crosses zero
  (linear interpolation; y is smooth there), a loss where F2 reaches zero (F2 is continuous at a
  loss: extrapolated from the last two samples in contact);
- contact_onset_deg / contact_loss_deg: first onset and last loss in the last revolution, as the
  crank angle within that revolution; contact_duration_deg: the angle with F2 > 0 in it;
- F2_weld_mean: the mean of F2 over the middle half of [onset, loss], by crank angle.
"""
from __future__ import annotations

import math
import textwrap
import time

import numpy as np

from sewfmu.scenarios.analyses import (
    Mechanism,
    RegressionCase,
    column,
    last_revolution,
    shaft_at,
    whole_revolution,
)
from sewfmu.scenarios.analyses.solutions.sampling import sampled

# the key figures of a run and their units (summary.json, sweeps, reports)
FIGURES = {"contact_onset_deg": "deg", "contact_loss_deg": "deg", "contact_duration_deg": "deg",
           "n_contacts": "1", "F2_peak": "N", "F2_weld_mean": "N"}


def _zero_between(a0, f0, a1, f1, lo, hi):
    """Zero of the line through (a0, f0), (a1, f1), clipped to [lo, hi]."""
    if f1 == f0:
        return 0.5 * (lo + hi)
    return min(max(a0 - f0 * (a1 - a0) / (f1 - f0), lo), hi)


def summary(phi: np.ndarray, y: np.ndarray, F2: np.ndarray, contact: np.ndarray,
            F2_max: np.ndarray | None = None) -> dict:
    """The punch's key figures over the last shaft revolution of the samples. F2_max, where
    given, is the largest F2 within each sample interval (the FMU's peak hold)."""
    start, end = whole_revolution(float(phi[-1]))
    k0 = max(int(np.searchsorted(phi, start)) - 1, 0)      # one sample before, for the edges
    k1 = int(np.searchsorted(phi, end + 1e-9, side="right"))
    ang = np.degrees(phi[k0:k1] - start)
    y, F2 = y[k0:k1], F2[k0:k1]
    peaks = F2 if F2_max is None else np.maximum(F2, F2_max[k0:k1])
    # a sample's peak hold covers the interval before it: count those ending inside the revolution
    F2_peak = float(peaks[ang > 0].max(initial=0.0))
    on = np.asarray(contact[k0:k1], dtype=bool) & (F2 > 0)
    intervals = []
    k, n = 0, len(ang)
    while k < n:
        if not on[k]:
            k += 1
            continue
        i0 = k
        while k < n and on[k]:
            k += 1
        i1 = k - 1
        if i0 == 0:
            onset = ang[0]
        elif y[i0 - 1] > 0 >= y[i0]:
            onset = _zero_between(ang[i0 - 1], y[i0 - 1], ang[i0], y[i0], ang[i0 - 1], ang[i0])
        elif i1 > i0:          # re-contact below the surface: extrapolate F2 back to zero
            onset = _zero_between(ang[i0], F2[i0], ang[i0 + 1], F2[i0 + 1], ang[i0 - 1], ang[i0])
        else:
            onset = 0.5 * (ang[i0 - 1] + ang[i0])
        if i1 == n - 1:
            loss = ang[-1]
        elif i1 > i0:
            loss = _zero_between(ang[i1 - 1], F2[i1 - 1], ang[i1], F2[i1], ang[i1], ang[i1 + 1])
        else:
            loss = 0.5 * (ang[i1] + ang[i1 + 1])
        onset, loss = max(onset, 0.0), min(loss, 360.0)
        if loss > onset:
            intervals.append((onset, loss))
    if not intervals:
        return {"contact_onset_deg": None, "contact_loss_deg": None, "contact_duration_deg": 0.0,
                "n_contacts": 0, "F2_peak": F2_peak,
                "F2_weld_mean": None}
    onset, loss = intervals[0][0], intervals[-1][1]
    quarter = 0.25 * (loss - onset)
    return {
        "contact_onset_deg": float(onset),
        "contact_loss_deg": float(loss),
        "contact_duration_deg": float(sum(b - a for a, b in intervals)),
        "n_contacts": len(intervals),
        "F2_peak": F2_peak,
        "F2_weld_mean": _mean_between(ang, F2, onset + quarter, loss - quarter),
    }


def _mean_between(x: np.ndarray, f: np.ndarray, a: float, b: float) -> float:
    """Mean of f over [a, b] by the trapezoidal rule on the samples, edges interpolated."""
    inside = (x > a) & (x < b)
    xs = np.concatenate([[a], x[inside], [b]])
    fs = np.concatenate([[np.interp(a, x, f)], f[inside], [np.interp(b, x, f)]])
    return float(np.trapezoid(fs, xs) / (b - a))


# the punch's signals: all from PunchContact, or, split at the fabric, from PunchBody and Fabric
_FROM_FABRIC = ("F2", "F2_max", "contact")


def signal(result, name: str):
    """A punch signal of a run of punch_drive (role punch) or punch_split (roles body, fabric)."""
    roles = result.scenario.roles
    if "punch" in roles:
        role = "punch"
    else:
        role = "fabric" if name in _FROM_FABRIC else "body"
    return result.columns.get(f"{roles[role]}.{name}") if name == "F2_max" \
        else column(result, role, name)


def summary_of_run(result) -> dict:
    return summary(column(result, "shaft", "phi"), signal(result, "y"), signal(result, "F2"),
                   signal(result, "contact"), signal(result, "F2_max"))


def summary_of_monolithic(solution) -> dict:
    return summary(solution.phi, solution.y, solution.F2, solution.contact)


def monolithic_figures(scenario, rtol: float | None = None,
                       punch_roles: tuple[str, ...] = ("punch",)) -> tuple[dict, float]:
    """Key figures of the punch drive solved as one ODE (DOP853, tight tolerances, or `rtol`
    with atol = rtol/1000) and the solver's wall time. `punch_roles`: the instances whose
    parameters together make the punch (the split drive's body and fabric)."""
    from sewfmu.components.shaft import ShaftParams  # loaded on first use (start-up time)
    from sewfmu.scenarios.analyses.solutions import punch_monolithic  # scipy: only when asked

    params = {role: dict(scenario.instances[name].parameters)
              for role, name in scenario.roles.items()}
    params["punch"] = {k: v for role in punch_roles for k, v in params.pop(role).items()}
    t_end = scenario.end_time()
    omega = params["shaft"].get("omega0", ShaftParams().omega0)
    started = time.perf_counter()
    tolerances = {} if rtol is None else {"rtol": rtol, "atol": rtol * 1e-3}
    solution = punch_monolithic.solve(params["shaft"], params["linkage"], params["punch"], t_end,
                                      sample_step=math.radians(0.01) / omega,
                                      sample_from=max(0.0, t_end - 2.2 * math.pi / omega),
                                      **tolerances)
    return summary_of_monolithic(solution), time.perf_counter() - started


# --- plots ------------------------------------------------------------------------------------
def plot(curves, path, title: str) -> None:
    """y(φ) and F2(φ) over the last revolution; `curves` is a list of (label, run result)."""
    import matplotlib  # matplotlib: only when drawing
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib: only when drawing

    fig, (ax_y, ax_f) = plt.subplots(2, 1, sharex=True, figsize=(8, 6.5))
    for label, result in curves:
        mask = last_revolution(result)
        phi = column(result, "shaft", "phi")
        deg = np.degrees(phi[mask] - whole_revolution(float(phi[-1]))[0])
        ax_y.plot(deg, signal(result, "y")[mask] * 1e3, label=label)
        ax_f.plot(deg, signal(result, "F2")[mask], label=label)
    if f"{result.scenario.roles['linkage']}.xi" in result.columns:   # the slider, if recorded
        ax_y.plot(deg, column(result, "linkage", "xi")[mask] * 1e3, "k:", lw=1,
                  label="ξ (slider)")
    ax_y.axhline(0.0, color="0.6", lw=0.8)
    ax_y.set_ylabel("punch height y [mm]")
    ax_f.set_ylabel("fabric force F2 [N]")
    ax_f.set_xlabel("crank angle in the last revolution φ [°]")
    ax_f.set_xlim(0, 360)
    ax_f.set_xticks(range(0, 361, 45))
    for ax in (ax_y, ax_f):
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    fig.suptitle("\n".join(textwrap.wrap(title, 80)), fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def excitation(t) -> dict:
    """The six-bar's excitation of the punch at ω = 200 s⁻¹ (its regression input)."""
    from sewfmu.components.punch_linkage import PunchLinkage  # loaded on first use (start-up time)

    e = sampled(PunchLinkage().motion, 200.0 * t, 200.0, 0.0)
    return {"xi": e.xi, "xi_dot": e.xi_dot, "xi_ddot": e.xi_ddot}


MECHANISM = Mechanism(
    roles={"shaft": "MainShaft", "linkage": "PunchLinkage", "punch": "PunchContact"},
    figures=FIGURES, animation="punch", monolithic=True,
    regression={"PunchLinkage": RegressionCase(2 * math.pi / 100, 2.5e-4, shaft_at(100.0)),
                "PunchContact": RegressionCase(4 * math.pi / 200, 2.5e-4, excitation)})
