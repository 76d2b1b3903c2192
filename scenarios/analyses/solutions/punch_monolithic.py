"""The monolithic solution of the punch drive: the same physics as one ODE, solved by scipy.

Independent of the co-simulation on purpose: the excitation is the linkage's exact kinematics at
the shaft angle phi(t) (no Taylor extrapolation), the force law is written here again from
docs/punch_drive.md, and the punch is integrated numerically (solve_ivp, DOP853 by default) with
the contact and spring switches located as terminal events, restarting in the new mode. Where a
preloaded compression-only spring 11 holds the punch on its stop, the punch moves with the exact
excitation until the stop force leaves [0, F30] (found by scanning and brentq).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from sewfmu.components.parameters import with_values
from sewfmu.components.punch_contact import GRAVITY, PunchContactParams
from sewfmu.components.punch_linkage import PunchLinkage, PunchLinkageParams
from sewfmu.components.shaft import MainShaft, ShaftParams
from sewfmu.scenarios.analyses.solutions.sampling import sampled


@dataclass
class MonolithicSolution:
    time: np.ndarray
    phi: np.ndarray
    y: np.ndarray
    y_dot: np.ndarray
    F2: np.ndarray
    F3: np.ndarray
    contact: np.ndarray
    held: np.ndarray           # the punch rides on the stop of a preloaded compression-only spring
    switch_times: list[float]
    n_rhs: int


def _fabric_push(p, y, v):
    """The fabric's Kelvin-Voigt force on the punch while they touch, before the contact's
    one-sidedness (F2 = max(0, this)); y and v may be arrays."""
    return -(p.c2 * y + p.b2 * v)


def solve(shaft: dict, linkage: dict, punch: dict, t_end: float, sample_step: float,
          sample_from: float = 0.0, method: str = "DOP853", rtol: float = 1e-10,
          atol: float = 1e-13, sample_switches: bool = True) -> MonolithicSolution:
    """Solve the punch drive from the setup position to t_end; sample the solution every
    sample_step from sample_from on, and at the switch instants if sample_switches."""
    sh = MainShaft(with_values(ShaftParams(), **shaft))
    lk = PunchLinkage(with_values(PunchLinkageParams(), **linkage))
    p = with_values(PunchContactParams(), **punch)
    n_rhs = 0

    def excitation(t):
        phi, omega, eps = sh.state(t)
        e = lk.motion(phi, omega, eps)
        return float(e.xi), float(e.xi_dot), float(e.xi_ddot)

    def forces(t, y, v, contact, spring_on):
        xi, xi_dot, _ = excitation(t)
        f1 = p.F10 + p.c1 * y + p.b1 * v
        f2 = _fabric_push(p, y, v) if contact else 0.0
        f3 = p.F30 + p.c3 * (xi - y) + p.b3 * (xi_dot - v) if spring_on else 0.0
        return f1, f2, f3

    def contact_g(t, s):               # < 0 inside {y < 0 and F2* > 0}
        return max(s[0], -_fabric_push(p, s[0], s[1]))

    def spring_g(t, s):                # < 0 inside {Delta > 0 and F3* > 0}
        xi, xi_dot, _ = excitation(t)
        delta = xi - s[0]
        return max(-delta, -(p.F30 + p.c3 * delta + p.b3 * (xi_dot - s[1])))

    xi0, xi_dot0, _ = excitation(0.0)
    state = np.array([xi0, 0.0])
    contact = False
    spring_on = True if not p.compression_only else spring_g(0.0, state) < 0
    held = _holds(p, 0.0, state, contact, spring_on, excitation)
    t0 = 0.0
    pieces = []            # (t_start, t_end, dense solution, contact, spring_on, held)
    switches = []
    while t0 < t_end:
        if held:
            t1, released = _ride_on_stop(p, t0, t_end, contact, excitation)
            pieces.append((t0, t1, _riding(excitation), contact, True, True))
            xi, xi_dot, xi_ddot = excitation(t1)
            state = np.array([xi, xi_dot])
            t0 = t1
            if released == "contact":
                switches.append(t0)
                contact = not contact
            elif released == "stop":
                switches.append(t0)
                held = False
                spring_on = _stop_force(p, xi, xi_dot, xi_ddot, contact) > p.F30
            continue

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
        pieces.append((t0, sol.t[-1], sol.sol, contact, spring_on, False))
        state = sol.y[:, -1].copy()
        t0 = float(sol.t[-1])
        if sol.status == 1:                        # a switch
            switches.append(t0)
            if sol.t_events[0].size:
                contact = not contact
            else:
                spring_on = not spring_on
                held = _holds(p, t0, state, contact, spring_on, excitation)
    return _sample(pieces, t_end, sample_step, sample_from, sh, lk, p,
                   switches if sample_switches else [], n_rhs)


# --- the punch held on the stop of a preloaded compression-only spring 11 ------------------------
# (the paper's spring 11 gives F3 a jump from 0 to F30 at Delta = 0; components/punch_contact.py
# explains why the punch is then held on the stop. Written here again for the reference.)

def _stop_force(p, y, v, xi_ddot, contact):
    """The stop force that makes the punch move with the slider."""
    f1 = p.F10 + p.c1 * y + p.b1 * v
    f2 = max(0.0, _fabric_push(p, y, v)) if contact else 0.0
    return p.m * (xi_ddot + GRAVITY) + f1 - f2


def _holds(p, t, state, contact, spring_on, excitation) -> bool:
    """At a crossing of the stop: the stop can hold the punch, and the excursion the new mode
    starts (2·|Delta'| / |Delta''|) is below 1/16 of the shortest natural period."""
    if not (p.compression_only and p.F30 > 0.0):
        return False
    xi, xi_dot, xi_ddot = excitation(t)
    y, v = state
    f3_star = p.F30 + p.c3 * (xi - y) + p.b3 * (xi_dot - v)
    if f3_star < 0.5 * p.F30 or not 0.0 <= _stop_force(p, xi, xi_dot, xi_ddot, contact) <= p.F30:
        return False
    f1 = p.F10 + p.c1 * y + p.b1 * v
    f2 = max(0.0, _fabric_push(p, y, v)) if contact else 0.0
    a = (-f1 + f2 + (f3_star if spring_on else 0.0)) / p.m - GRAVITY
    period = 2.0 * math.pi * math.sqrt(p.m / (p.c1 + p.c2 + p.c3))
    return 2.0 * abs(xi_dot - v) <= abs(xi_ddot - a) * period / 16


def _ride_on_stop(p, t0, t_end, contact, excitation):
    """(time, reason) where riding on the stop ends: 'contact' (the fabric contact switches),
    'stop' (the stop force leaves [0, F30]) or None at t_end. Scans in 10 µs and refines by
    brentq."""
    def release(t):
        xi, xi_dot, xi_ddot = excitation(t)
        f = _stop_force(p, xi, xi_dot, xi_ddot, contact)
        return max(f - p.F30, -f)

    def touch(t):
        xi, xi_dot, _ = excitation(t)
        g = max(xi, -_fabric_push(p, xi, xi_dot))
        return g if contact else -g

    if release(t0) > 0.0:                 # e.g. the fabric took over the load at a landing
        return t0, "stop"
    scan = 1e-5
    t_prev = t0
    while t_prev < t_end:
        t = min(t_prev + scan, t_end)
        hits = [(brentq(f, t_prev, t, xtol=1e-15, rtol=4 * np.finfo(float).eps), name)
                for f, name in ((touch, "contact"), (release, "stop")) if f(t) > 0.0]
        if hits:
            return min(hits)
        t_prev = t
    return t_end, None


def _riding(excitation):
    """Dense 'solution' of a held piece: (y, y') = (xi, xi') at the given times."""
    def dense(times):
        return np.array([excitation(float(t))[:2] for t in np.atleast_1d(times)]).T
    return dense


def _sample(pieces, t_end, sample_step, sample_from, shaft, linkage, p, switches,
            n_rhs) -> MonolithicSolution:
    k0 = int(math.ceil(sample_from / sample_step - 1e-9))
    k1 = int(math.floor(t_end / sample_step + 1e-9))
    # the switch instants are samples too: the impact force is a jump at the onset
    inside = [t for t in switches if sample_from <= t <= t_end]
    times = np.unique(np.concatenate([np.arange(k0, k1 + 1) * sample_step, inside, [t_end]]))
    y = np.empty_like(times)
    v = np.empty_like(times)
    contact = np.zeros(times.shape, dtype=bool)
    spring_on = np.zeros(times.shape, dtype=bool)
    held = np.zeros(times.shape, dtype=bool)
    for start, end, dense, c, s_on, on_stop in pieces:
        mask = (times >= start) & (times <= end)
        if mask.any():
            y[mask], v[mask] = dense(times[mask])
            contact[mask] = c
            spring_on[mask] = s_on
            held[mask] = on_stop
    motion = np.array([shaft.state(t) for t in times])
    e = sampled(linkage.motion, motion[:, 0], motion[:, 1], motion[:, 2])
    f2 = np.where(contact, np.maximum(_fabric_push(p, y, v), 0.0), 0.0)
    f3 = np.where(spring_on, p.F30 + p.c3 * (e.xi - y) + p.b3 * (e.xi_dot - v), 0.0)
    if p.compression_only:
        f3 = np.maximum(f3, 0.0)
    f1 = p.F10 + p.c1 * y + p.b1 * v
    f3 = np.where(held, p.m * (e.xi_ddot + GRAVITY) + f1 - f2, f3)
    return MonolithicSolution(times, motion[:, 0], y, v, f2, f3, contact, held, list(switches),
                             n_rhs)
