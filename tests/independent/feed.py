"""The feed mechanism's key figures (scenario feed) computed independently of sewfmu, from
the papers as docs/feed.md.

Nothing here imports sewfmu. The whole chain's six loop-closure equations are solved together by
scipy.optimize.fsolve, continuing from the previous crank angle; the first configuration is found
dyad by dyad from several starting guesses and kept only on the assembly branches the
specification names (checked again at every angle by the sign of the cross products).
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import fsolve

# defaults of docs/feed.md (SI units)
FEED = {"r_l": 0.0035781, "r_f": 0.0044767, "alpha1": math.radians(116.0), "l2": 0.225,
        "l8": 0.225, "x_D": -0.05875, "y_D": -0.219257, "x_G": 0.043263, "y_G": -0.22257,
        "l3": 0.030, "l3p": 0.030, "alpha3": math.radians(10.0), "l7": 0.028, "l7p": 0.028,
        "alpha7": math.radians(11.0), "l4": 0.025, "l5": 0.120, "l_HM": 0.100}
STEP_DEG = 0.5            # the scenario's communication step in crank angle (0.5° at 303.5 s⁻¹)


def _e(angle):
    return np.array([math.cos(angle), math.sin(angle)])


def _cross(p, q, x):
    """(q − p) × (x − p): > 0 where x lies on the left of the directed line p→q."""
    return (q[0] - p[0]) * (x[1] - p[1]) - (q[1] - p[1]) * (x[0] - p[0])


class Feed:
    """Unknowns q = (φ2, φ3, φ8, φ7, φ4, φ5): rod 2, lever 3 (arm D→C), rod 8, rocker 7 (arm
    G→N), rod 4, lever 5 (H→F). Loop equations for the crank angle φ1:

        B + l2·e(φ2) − D − l3·e(φ3) = 0                      (C reached from B and from D)
        K + l8·e(φ8) − G − l7·e(φ7) = 0                      (N reached from K and from G)
        E + l4·e(φ4) − H − l5·e(φ5) = 0                      (F reached from E and from H)

    with B = r_l·e(φ1), K = r_f·e(φ1 + α1), E = D + l3'·e(φ3 + α3), H = G + l7'·e(φ7 + 90° + α7).
    """

    def __init__(self, p: dict = FEED):
        self.p = p
        self.D = np.array([p["x_D"], p["y_D"]])
        self.G = np.array([p["x_G"], p["y_G"]])

    def joints(self, q, phi1):
        p = self.p
        f2, f3, f8, f7, f4, f5 = q
        B, K = p["r_l"] * _e(phi1), p["r_f"] * _e(phi1 + p["alpha1"])
        E = self.D + p["l3p"] * _e(f3 + p["alpha3"])
        H = self.G + p["l7p"] * _e(f7 + math.pi / 2 + p["alpha7"])
        return {"B": B, "K": K, "C": B + p["l2"] * _e(f2), "C'": self.D + p["l3"] * _e(f3),
                "N": K + p["l8"] * _e(f8), "N'": self.G + p["l7"] * _e(f7), "E": E, "H": H,
                "F": E + p["l4"] * _e(f4), "F'": H + p["l5"] * _e(f5),
                "M": H + p["l_HM"] * _e(f5)}

    def residual(self, q, phi1):
        j = self.joints(q, phi1)
        return np.concatenate([j["C"] - j["C'"], j["N"] - j["N'"], j["F"] - j["F'"]])

    def on_branch(self, q, phi1) -> bool:
        """C right of B→D, N left of K→G, F left of E→H (docs/feed.md)."""
        j = self.joints(q, phi1)
        return (_cross(j["B"], self.D, j["C"]) < 0 and _cross(j["K"], self.G, j["N"]) > 0
                and _cross(j["E"], j["H"], j["F"]) > 0)

    def solve(self, phi1, guess):
        q, _, ok, msg = fsolve(self.residual, guess, args=(phi1,), xtol=1e-14, full_output=True)
        if np.abs(self.residual(q, phi1)).max() > 1e-13:
            raise RuntimeError(f"feed: no assembly at φ1 = {math.degrees(phi1):.3f}°: {msg}")
        if not self.on_branch(q, phi1):
            raise RuntimeError(f"feed: left the specified branch at φ1 = {math.degrees(phi1):.3f}°")
        return q

    def first_configuration(self, phi1):
        """Dyad by dyad from starting guesses round the circle, keeping the specified branch."""
        p = self.p
        tries = np.radians(np.arange(0.0, 360.0, 30.0))
        B, K = p["r_l"] * _e(phi1), p["r_f"] * _e(phi1 + p["alpha1"])

        def dyad(P, lp, Q, lq, want):
            """Angles (of P→X, of Q→X) with |PX| = lp, |QX| = lq, X on the wanted side of P→Q."""
            for a in tries:
                for b in tries:
                    sol, _, ok, _ = fsolve(lambda x: P + lp * _e(x[0]) - Q - lq * _e(x[1]), [a, b],
                                           xtol=1e-14, full_output=True)
                    X = Q + lq * _e(sol[1])
                    if ok == 1 and np.allclose(P + lp * _e(sol[0]), X, atol=1e-12) \
                            and want(_cross(P, Q, X)):
                        return sol
            raise RuntimeError("feed: dyad cannot be assembled")

        f2, f3 = dyad(B, p["l2"], self.D, p["l3"], lambda c: c < 0)
        f8, f7 = dyad(K, p["l8"], self.G, p["l7"], lambda c: c > 0)
        E = self.D + p["l3p"] * _e(f3 + p["alpha3"])
        H = self.G + p["l7p"] * _e(f7 + math.pi / 2 + p["alpha7"])
        f4, f5 = dyad(E, p["l4"], H, p["l5"], lambda c: c > 0)
        return np.array([f2, f3, f8, f7, f4, f5])

    def sweep(self, phis):
        out = np.empty((len(phis), 6))
        q = self.first_configuration(phis[0])
        for k, phi1 in enumerate(phis):
            q = self.solve(phi1, q)
            out[k] = q
        return out


def _fold(angle):
    """Angle between two lines, folded to 0…90° (the transmission angle)."""
    a = np.abs(np.mod(angle, math.pi))
    return np.minimum(a, math.pi - a)


UNITS = {"phi3_swing_deg": "deg", "phi5_swing_deg": "deg", "phi7_swing_deg": "deg",
         "M_path_width_mm": "mm", "M_path_height_mm": "mm", "min_transmission_angle_C_deg": "deg",
         "min_transmission_angle_N_deg": "deg", "min_transmission_angle_F_deg": "deg"}


def figures_at(phis, p: dict = FEED) -> dict:
    feed = Feed(p)
    q = feed.sweep(phis)
    m = np.array([feed.joints(qk, phi1)["M"] for qk, phi1 in zip(q, phis)])
    swing = lambda col: float(np.degrees(np.ptp(np.unwrap(q[:, col]))))
    return {
        "phi3_swing_deg": swing(1),
        "phi5_swing_deg": swing(5),
        "phi7_swing_deg": swing(3),
        "M_path_width_mm": float(np.ptp(m[:, 0]) * 1e3),
        "M_path_height_mm": float(np.ptp(m[:, 1]) * 1e3),
        # the links meeting at the joint: rod 2 and arm D→C at C, rod 8 and arm G→N at N,
        # rod 4 and lever 5 at F
        "min_transmission_angle_C_deg": float(np.degrees(_fold(q[:, 0] - q[:, 1]).min())),
        "min_transmission_angle_N_deg": float(np.degrees(_fold(q[:, 2] - q[:, 3]).min())),
        "min_transmission_angle_F_deg": float(np.degrees(_fold(q[:, 4] - q[:, 5]).min())),
    }


def reference() -> tuple[dict, dict]:
    """(figures, notes) of scenario feed: the figures as defined, at the run's communication
    points of the last revolution (φ1 = 0°, 0.5°, …, 360°: the run's samples 720…1440), and the
    same figures from a 5× finer crank-angle grid (the continuous extremes, for information)."""
    sampled = figures_at(np.radians(np.arange(0, 721) * STEP_DEG))
    fine = figures_at(np.radians(np.arange(0, 3601) * STEP_DEG / 5))
    return sampled, {"fine_grid_figures": fine}
