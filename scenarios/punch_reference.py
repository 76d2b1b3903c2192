"""Monolithic reference of the punch drive: the same physics as one ODE, solved by scipy.

Independent of the co-simulation on purpose: the excitation is the linkage's exact kinematics at
the shaft angle phi(t) (no Taylor extrapolation), the force law is written here again from
MECHANISMS.md §1b, and the punch is integrated numerically (solve_ivp, DOP853 by default) with
the contact and spring switches located as terminal events, restarting in the new mode.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from components.parameters import with_values
from components.punch_contact import GRAVITY, PunchContactParams
from components.punch_linkage import PunchLinkage, PunchLinkageParams
from components.shaft import MainShaft, ShaftParams


@dataclass
class ReferenceSolution:
    time: np.ndarray
    phi: np.ndarray
    y: np.ndarray
    y_dot: np.ndarray
    F2: np.ndarray
    F3: np.ndarray
    contact: np.ndarray
    switch_times: list[float]
    n_rhs: int


def solve(shaft: dict, linkage: dict, punch: dict, t_end: float, sample_step: float,
          sample_from: float = 0.0, method: str = "DOP853", rtol: float = 1e-10,
          atol: float = 1e-13, sample_switches: bool = True) -> ReferenceSolution:
    """Solve the punch drive from the setup position to t_end; sample the solution every
    sample_step from sample_from on, and at the switch instants if sample_switches."""
    sh = MainShaft(with_values(ShaftParams(), **shaft))
    lk = PunchLinkage(with_values(PunchLinkageParams(), **linkage))
    p = with_values(PunchContactParams(), **punch)
    n_rhs = 0

    def excitation(t):
        phi, omega, eps = sh.state(t)
        e = lk.excitation(phi, omega, eps)
        return float(e.xi), float(e.xi_dot)

    def forces(t, y, v, contact, spring_on):
        xi, xi_dot = excitation(t)
        f1 = p.F10 + p.c1 * y + p.b1 * v
        f2 = -(p.c2 * y + p.b2 * v) if contact else 0.0
        f3 = p.F30 + p.c3 * (xi - y) + p.b3 * (xi_dot - v) if spring_on else 0.0
        return f1, f2, f3

    def contact_g(t, s):               # < 0 inside {y < 0 and F2* > 0}
        return max(s[0], p.c2 * s[0] + p.b2 * s[1])

    def spring_g(t, s):                # < 0 inside {Delta > 0 and F3* > 0}
        xi, xi_dot = excitation(t)
        delta = xi - s[0]
        return max(-delta, -(p.F30 + p.c3 * delta + p.b3 * (xi_dot - s[1])))

    xi0, xi_dot0 = excitation(0.0)
    state = np.array([xi0, 0.0])
    contact = False
    spring_on = True if not p.compression_only else spring_g(0.0, state) < 0
    t0 = 0.0
    pieces = []            # (t_start, t_end, dense solution, contact, spring_on)
    switches = []
    while t0 < t_end:
        def rhs(t, s, contact=contact, spring_on=spring_on):
            nonlocal n_rhs
            n_rhs += 1
            f1, f2, f3 = forces(t, s[0], s[1], contact, spring_on)
            return [s[1], (-f1 + f2 + f3) / p.m - GRAVITY]

        ev_contact = lambda t, s: contact_g(t, s)
        ev_contact.terminal = True
        ev_contact.direction = +1 if contact else -1     # leaving the current mode only
        events = [ev_contact]
        if p.compression_only:
            ev_spring = lambda t, s: spring_g(t, s)
            ev_spring.terminal = True
            ev_spring.direction = +1 if spring_on else -1
            events.append(ev_spring)
        sol = solve_ivp(rhs, (t0, t_end), state, method=method, rtol=rtol, atol=atol,
                        events=events, dense_output=True)
        if not sol.success:
            raise RuntimeError(f"reference solver failed at t = {sol.t[-1]:g} s: {sol.message}")
        pieces.append((t0, sol.t[-1], sol.sol, contact, spring_on))
        state = sol.y[:, -1].copy()
        t0 = float(sol.t[-1])
        if sol.status == 1:                        # a switch
            switches.append(t0)
            if sol.t_events[0].size:
                contact = not contact
            else:
                spring_on = not spring_on
    return _sample(pieces, t_end, sample_step, sample_from, sh, lk, p,
                   switches if sample_switches else [], n_rhs)


def _sample(pieces, t_end, sample_step, sample_from, shaft, linkage, p, switches,
            n_rhs) -> ReferenceSolution:
    k0 = int(math.ceil(sample_from / sample_step - 1e-9))
    k1 = int(math.floor(t_end / sample_step + 1e-9))
    # the switch instants are samples too: the impact force is a jump at the onset
    inside = [t for t in switches if sample_from <= t <= t_end]
    times = np.unique(np.concatenate([np.arange(k0, k1 + 1) * sample_step, inside, [t_end]]))
    y = np.empty_like(times)
    v = np.empty_like(times)
    contact = np.zeros(times.shape, dtype=bool)
    spring_on = np.zeros(times.shape, dtype=bool)
    for start, end, dense, c, s_on in pieces:
        mask = (times >= start) & (times <= end)
        if mask.any():
            y[mask], v[mask] = dense(times[mask])
            contact[mask] = c
            spring_on[mask] = s_on
    motion = np.array([shaft.state(t) for t in times])
    e = linkage.excitation(motion[:, 0], motion[:, 1], motion[:, 2])
    f2 = np.where(contact, np.maximum(-(p.c2 * y + p.b2 * v), 0.0), 0.0)
    f3 = np.where(spring_on, p.F30 + p.c3 * (e.xi - y) + p.b3 * (e.xi_dot - v), 0.0)
    return ReferenceSolution(times, motion[:, 0], y, v, f2, f3, contact, list(switches), n_rhs)
