"""Compute the independent key figures of every mechanism and write tests/independent/figures.json.

    .venv/bin/python -m tests.independent.make_references          (from the repository's root)

Nothing here imports sewfmu: each figure comes from tests/independent/<mechanism>.py, solved from
the papers as docs/<mechanism>.md give them, with their defaults. For each
scenario the file holds the parameters the reference assumed (tests/independent/test_figures.py
checks that the run used the same), and for each figure its value, unit and how it was computed.
The ODE references are solved twice, by DOP853 (the stored value) and by LSODA (a different
family: Adams/BDF); their spread is quoted in the "how" text as the reference's own uncertainty.
"""
from __future__ import annotations

import datetime
import json
import sys
from pathlib import Path

if __package__ in (None, ""):               # run as a script: make `tests` importable
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from tests.independent import carriage, feed, punch, takeup  # noqa: E402

OUT = Path(__file__).with_name("figures.json")


def _spread(a: dict, b: dict) -> dict:
    return {k: abs(a[k] - b[k]) for k in a}


def _entries(figures: dict, units: dict, how: dict) -> dict:
    return {k: {"value": v, "unit": units[k], "how": how[k]} for k, v in figures.items()}


def punch_scenarios(cross_check: bool) -> dict:
    figs, notes = punch.reference()
    spread = _spread(figs, punch.reference(method="LSODA")[0]) if cross_check else None
    base = (f"six-bar by its loop-closure equations (scipy fsolve, xtol 1e-14, continuation over "
            f"{punch.GRID} crank angles per turn; α0 = {notes['alpha0_deg']:.6f}° by brentq on "
            f"dy_D/dα; stroke {notes['stroke_mm']:.5f} mm), ξ' and ξ'' from the differentiated loop "
            f"equations, trigonometric interpolation between (largest relative deviation from "
            f"fresh solves {notes['interpolation_error_rel']:.1e}); punch ODE by scipy solve_ivp "
            f"DOP853, rtol {punch.RTOL:g}, atol {punch.ATOL:g}, 10 revolutions from y = xi0 at rest, "
            f"ω = {punch.OMEGA:g} s⁻¹; the contact condition max(y, y + (b2/c2)·ẏ) < 0 as a "
            f"terminal event ({notes['switches']} switches located)")
    spread_text = (lambda k, unit: f"; DOP853 vs LSODA: {spread[k]:.1e} {unit}") if spread \
        else (lambda k, unit: "")
    how = {
        "contact_onset_deg": base + "; the first landing event in the last revolution, crank angle "
                                    "within it" + spread_text("contact_onset_deg", "deg"),
        "contact_loss_deg": base + "; the last loss event in the last revolution"
                                   + spread_text("contact_loss_deg", "deg"),
        "contact_duration_deg": base + "; the sum of the contact intervals (F2 > 0) clipped to the "
                                       "last revolution" + spread_text("contact_duration_deg", "deg"),
        "n_contacts": base + "; the number of contact intervals in the last revolution",
        "F2_peak": base + "; the largest F2 of the continuous solution in the last revolution "
                          "(2001 samples per contact interval, refined by a bounded search; the "
                          "landing's jump included)" + spread_text("F2_peak", "N"),
        "F2_weld_mean": base + "; ∫F2 dt integrated as a third ODE state, differenced between the "
                               "middle half's ends of [onset, loss] and divided by its length (ω "
                               "constant: the mean by crank angle)" + spread_text("F2_weld_mean", "N"),
    }
    shaft = {"shaft.omega0": punch.OMEGA, "shaft.ramp_time": 0.0}
    linkage = {f"linkage.{k}": v for k, v in punch.LINKAGE.items()} | {"linkage.mode": 0}
    body_keys = ("m", "F10", "c1", "b1", "c3", "b3", "F30")
    drive = {
        "parameters": shaft | linkage | {f"punch.{k}": v for k, v in punch.PUNCH.items()}
        | {"punch.compression_only": 0, "experiment.revolutions": punch.REVOLUTIONS},
        "figures": _entries(figs, punch.UNITS, how), "notes": notes}
    split_how = {k: "the same physics as punch_drive (PunchBody + Fabric make PunchContact cut at "
                    "the fabric, docs/punch_drive.md), so the same reference: " + v for k, v in how.items()}
    split = {
        "parameters": shaft | linkage
        | {f"body.{k}": punch.PUNCH[k] for k in body_keys} | {"body.compression_only": 0}
        | {"fabric.c2": punch.PUNCH["c2"], "fabric.b2": punch.PUNCH["b2"],
           "experiment.revolutions": punch.REVOLUTIONS},
        "figures": _entries(figs, punch.UNITS, split_how), "notes": notes}
    return {"punch_drive": drive, "punch_split": split}


def carriage_scenario(cross_check: bool) -> dict:
    figs, notes = carriage.reference()
    spread = _spread(figs, carriage.reference(method="LSODA")[0]) if cross_check else None
    modal = ("K = inverse of the cantilever's flexibility matrix at a and l (beam-table "
             "deflections); M and p from the Ritz shapes by scipy quad (epsrel 1e-13, split at z = a) "
             "plus the carriage's m_k and J_c/(l − a)² terms; ω² by scipy.linalg.eigh(K, M)")
    response = (f"; U from M·Ü + C·U̇ + K·U = −p·a(t), C = M·Φ·diag(2ζω)·Φᵀ·M, with the drive's "
                f"continuous cycloidal a(t) (window 0.5 from φ = 0, 3 mm per stitch) at "
                f"{carriage.OMEGA:.6f} rad/s, by scipy solve_ivp DOP853 (rtol {carriage.RTOL:g}, "
                f"atol {carriage.ATOL:g}) piecewise between the window's ends, from rest; |U2| read "
                f"at the run's communication points (every 1° of crank)")
    sp = (lambda k: f"; DOP853 vs LSODA: {spread[k]:.1e} um") if spread else (lambda k: "")
    how = {
        "omega1": modal + " (first mode)",
        "omega2": modal + " (second mode)",
        "stitch_rate_per_min": "60·ω/(2π) of the shaft speed 167.55160819145564 rad/s",
        "peak_abs_U2_last_stitch_um": modal + response + ", largest over the last revolution "
                                      f"(both ends); continuous peak of the whole run "
                                      f"{notes['peak_abs_U2_continuous_um']:.4f} um"
                                      + sp("peak_abs_U2_last_stitch_um"),
        "peak_abs_U2_um": modal + response + ", largest over the whole run" + sp("peak_abs_U2_um"),
    }
    params = ({"shaft.omega0": carriage.OMEGA, "shaft.ramp_time": 0.0}
              | {f"drive.{k}": v for k, v in carriage.DRIVE.items()}
              | {f"carriage.{k}": v for k, v in carriage.CARRIAGE.items()}
              | {"experiment.revolutions": carriage.REVOLUTIONS})
    return {"carriage_startstop": {"parameters": params,
                                   "figures": _entries(figs, carriage.UNITS, how), "notes": notes}}


def feed_scenario() -> dict:
    figs, notes = feed.reference()
    base = ("the six loop-closure equations of the whole chain by scipy fsolve (xtol 1e-14), "
            "continued every 0.5° of crank from a first configuration found dyad by dyad on the "
            "specified branches (C right of B→D, N left of K→G, F left of E→H, checked at every "
            "angle); read at the run's communication points of the last revolution (φ1 = 0…360° "
            "every 0.5°)")
    how = {k: base + f"; on a 0.1° grid: {notes['fine_grid_figures'][k]:.9g}" for k in figs}
    for k in ("phi3_swing_deg", "phi5_swing_deg", "phi7_swing_deg"):
        how[k] = "max − min of the unwrapped angle; " + how[k]
    for k in ("M_path_width_mm", "M_path_height_mm"):
        how[k] = "max − min of M's x (width) or y (height), M = H + l_HM·e(φ5); " + how[k]
    for k in ("min_transmission_angle_C_deg", "min_transmission_angle_N_deg",
              "min_transmission_angle_F_deg"):
        how[k] = ("angle between the two links meeting at the joint (rod 2 / arm D→C, rod 8 / arm "
                  "G→N, rod 4 / lever 5), folded to 0…90°, smallest; " + how[k])
    params = {"shaft.omega0": 303.5, "shaft.ramp_time": 0.0} | {
        f"feed.{k}": v for k, v in feed.FEED.items()} | {"experiment.revolutions": 2}
    return {"feed": {"parameters": params, "figures": _entries(figs, feed.UNITS, how), "notes": notes}}


def takeup_scenario() -> dict:
    figs, notes = takeup.reference()
    base = ("four-bar loop closure by scipy fsolve (xtol 1e-14) continued every 0.5° of crank, C "
            "on the left of B→D; E = B + L_BE·e(φ_BC + ∠CBE); velocity and acceleration from the "
            "differentiated loop equation at 5000 rpm; read at the run's communication points of "
            "the last revolution (θ = 0…360° every 0.5°)")
    fine = notes["fine_grid"]
    how = {
        "path_extent_z_mm": base + f"; max − min of Z_E (0.05° grid: {fine['path_extent_z_mm']:.9g})",
        "path_extent_x_mm": base + f"; max − min of X_E (0.05° grid: {fine['path_extent_x_mm']:.9g})",
        "stroke_mm": base + "; the largest distance between two sampled points, by brute force "
                            "over all pairs",
        "peak_speed_m_s": base + f"; the largest |dE/dt| (0.05° grid: {fine['peak_speed_m_s']:.11g})",
        "peak_acceleration_m_s2": base + "; the largest |d²E/dt²| (0.05° grid: "
                                         f"{fine['peak_acceleration_m_s2']:.11g})",
        "central_difference_step_deg": "the scenario's communication step: 0.5° of crank",
        "central_difference_max_error_m_s": base + "; the largest |(E(θ+Δθ) − E(θ−Δθ))/(2Δθ)·ω − "
                                                   "dE/dt| over the 720 distinct sample angles",
        "central_difference_max_error_percent_of_peak_speed": base + "; the above over the peak "
                                                                     "speed, in %",
    }
    params = {"shaft.omega0": takeup.OMEGA, "shaft.ramp_time": 0.0} | {
        f"takeup.{k}": v for k, v in takeup.TAKEUP.items()} | {"experiment.revolutions": 2}
    return {"takeup": {"parameters": params, "figures": _entries(figs, takeup.UNITS, how),
                       "notes": notes}}


def compute(cross_check: bool = True) -> dict:
    """Every scenario's reference. `cross_check`: also solve the ODEs by LSODA (slower)."""
    scenarios = {}
    scenarios |= punch_scenarios(cross_check)
    scenarios |= carriage_scenario(cross_check)
    scenarios |= feed_scenario()
    scenarios |= takeup_scenario()
    return scenarios


def main() -> None:
    scenarios = compute()
    out = {"date": datetime.date.today().isoformat(),
           "generator": "tests/independent/make_references.py (no sewfmu code)",
           "specification": "the papers as docs/*.md give them, with their defaults",
           "scenarios": scenarios}
    OUT.write_text(json.dumps(out, indent=1, ensure_ascii=False, allow_nan=False) + "\n")
    for name, sc in scenarios.items():
        print(name)
        for k, f in sc["figures"].items():
            print(f"  {k:52s} {f['value']!r:>24} {f['unit']}")
    print(f"written: {OUT}")


if __name__ == "__main__":
    main()
