"""Punch body of the ultrasonic sewing machine: one mass between springs and the fabric.

y is the punch's height above the fabric surface (y < 0: pressing into it), xi(t) the kinematic
excitation from the linkage, Delta = xi - y the deformation of spring 11 (docs/punch_drive.md):

    m·y'' = -F1 + F2 + F3 - m·g
    F1 = F10 + c1·y + b1·y'                                  closing spring 6
    F2 = -(c2·y + b2·y')  while y < 0 and that is > 0        fabric: unilateral, non-retaining
    F3 = F30 + c3·Delta + b3·Delta'                          spring 11 (bilateral, the paper's)
         or, compression only: F3 only while Delta > 0 and F3 > 0

Between switches the equation is linear with constant coefficients, and within a communication
step the excitation is the Taylor polynomial xi(τ) = x0 + x1·τ + x2·τ² built from the inputs
xi, xi', xi''. So each piece is solved exactly (a damped oscillator under polynomial forcing) and
the switches of contact and of spring 11 are located in time inside the step by bisection on the
exact solution. No step size limit follows from stability, only from the extrapolation of xi.

Compression only with a preload F30 > 0 makes spring 11 a captive spring: its force jumps from 0
to F30 at Delta = 0. There the punch rests on the slider's stop, and the exact motion is an endless
micro-bouncing on it (relative speed decaying slowly, one switch every few microseconds). The
model treats that as what it is physically, the punch held on the stop ("held": y = xi, the stop
force m·(xi'' + g) + F1 - F2 anywhere in [0, F30]), entered when a crossing of the stop would start
an excursion shorter than the switch search resolves (a fraction of the shortest natural period),
and left when the stop force needed leaves [0, F30] (above F30 the spring compresses, below 0 the
punch lifts off the stop).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

from .oscillator import DampedOscillator
from .parameters import CHOICE, NONNEGATIVE, parameter, validate

GRAVITY = 9.81

# contact and spring switches are searched on sub-intervals of at most this fraction of the
# shortest natural period, so that a touch-and-go inside one step is not jumped over
_SAMPLES_PER_PERIOD = 16
_MAX_SWITCHES_PER_STEP = 64
# bounded work per step: a step that needs more search sub-intervals than this is refused, not
# ground through (1e6 s at the defaults would be 4e9 of them)
MAX_SEARCH_INTERVALS = 4000
_TIME_RESOLUTION = 1e-15           # s; bisection stops below this bracket width


@dataclass(frozen=True)
class PunchContactParams:
    m: float = parameter(0.063, "kg", "mass of the punch with its holder")
    F10: float = parameter(20.0, "N", "preload of the closing spring 6", NONNEGATIVE)
    c1: float = parameter(2000.0, "N/m", "stiffness of the closing spring 6")
    b1: float = parameter(0.71, "N.s/m", "damping of the closing spring 6", NONNEGATIVE)
    c2: float = parameter(5.0e4, "N/m", "contact stiffness of the fabric")
    b2: float = parameter(97.64, "N.s/m", "contact damping of the fabric", NONNEGATIVE)
    c3: float = parameter(1.0e5, "N/m", "stiffness of spring 11 (slider to stop)")
    b3: float = parameter(7.10, "N.s/m", "damping of spring 11", NONNEGATIVE)
    F30: float = parameter(0.0, "N", "preload of spring 11", NONNEGATIVE)
    compression_only: int = parameter(0, "1", "spring 11: 0 bilateral (the paper's equation), "
                                      "1 compression only", CHOICE, choices=(0, 1))


# the state and the outputs are named tuples rather than frozen dataclasses (immutable all the
# same): each is made at every step of the FMU, and a tuple is made several times faster
class PunchState(NamedTuple):
    """Everything the punch remembers between steps."""
    y: float
    y_dot: float
    contact: bool          # fabric force F2 active
    spring_on: bool        # spring 11 transmits force (always True when bilateral)
    landings: int = 0      # contact onsets so far
    F2_max: float = 0.0    # largest F2 during the last step (the impact at landing is a jump
                           # that falls between communication points)
    held: bool = False     # compression only, F30 > 0: the punch rests on the stop of spring 11
                           # (y follows xi; spring_on is then True: the stop transmits force)


class PunchOutputs(NamedTuple):
    y: float
    y_dot: float
    y_ddot: float
    F1: float
    F2: float
    F3: float
    Delta: float
    contact: bool
    F2_max: float


class ZenoError(RuntimeError):
    """Too many contact switches in one step (chattering that the model cannot resolve)."""


class StepTooLong(ValueError):
    """A step longer than the switch search can cover with bounded work."""


class _Held:
    """The punch held on the stop of spring 11 over one piece: it moves with the excitation
    xi(t0 + u) = a0 + a1·u + a2·u² (the same interface as DampedOscillator)."""

    __slots__ = ("a0", "a1", "a2")

    def __init__(self, a0, a1, a2):
        self.a0, self.a1, self.a2 = a0, a1, a2

    def state(self, tau):
        return self.a0 + tau * (self.a1 + tau * self.a2), self.a1 + 2.0 * tau * self.a2

    def accel(self, tau, y, v):
        return 2.0 * self.a2


class PunchContact:
    """The punch body's dynamics with exact piecewise integration and located switches.

    An external force on the punch, e(τ) = e0 + e1·τ within a step (upward positive, like F2),
    is where a fabric outside the model acts (PunchBody, split at the fabric); it is 0 here."""

    def __init__(self, params: PunchContactParams = PunchContactParams()):
        validate(params)
        self._set_up(params)

    def _set_up(self, params: PunchContactParams) -> None:
        self.p = params
        stiffest = params.c1 + params.c2 + params.c3
        self.shortest_period = 2.0 * math.pi * math.sqrt(params.m / stiffest)
        # only a preloaded compression-only spring 11 has a stop the punch can rest on
        self.has_stop = bool(params.compression_only) and params.F30 > 0.0

    # --- state at the setup position ---------------------------------------------------------
    def initial_state(self, xi: float, xi_dot: float, xi_ddot: float = 0.0,
                      ext: float = 0.0) -> PunchState:
        """At rest on the excitation (Delta = 0), with the switches consistent with that state."""
        contact, spring_on = self._consistent_flags(xi, 0.0, xi, xi_dot)
        held = self._sticks(xi, 0.0, xi, xi_dot, xi_ddot, contact, spring_on, ext)
        # held, the punch moves with the slider from the start (xi' is small then, by _sticks)
        return PunchState(xi, xi_dot if held else 0.0, contact, spring_on or held, held=held)

    # --- forces ------------------------------------------------------------------------------
    def outputs(self, s: PunchState, xi: float, xi_dot: float, xi_ddot: float = 0.0,
                ext: float = 0.0) -> PunchOutputs:
        p = self.p
        f1, f2 = self._spring6_and_fabric(s.y, s.y_dot, s.contact)
        delta = xi - s.y
        if s.held:                   # the stop carries whatever keeps the punch on the slider
            f3 = self._stop_force(s.y, s.y_dot, xi_ddot, s.contact, ext)
            return PunchOutputs(s.y, s.y_dot, xi_ddot, f1, f2, f3, delta, s.contact,
                                max(s.F2_max, f2))
        f3 = p.F30 + p.c3 * delta + p.b3 * (xi_dot - s.y_dot)
        if not s.spring_on:
            f3 = 0.0
        elif p.compression_only:
            f3 = max(0.0, f3)
        a = (-f1 + f2 + f3 + ext) / p.m - GRAVITY
        return PunchOutputs(s.y, s.y_dot, a, f1, f2, f3, delta, s.contact, max(s.F2_max, f2))

    def _spring6_and_fabric(self, y, v, contact) -> tuple[float, float]:
        """(F1, F2): the closing spring's force and the fabric's (>= 0, only in contact)."""
        p = self.p
        f2 = max(0.0, -(p.c2 * y + p.b2 * v)) if contact else 0.0
        return p.F10 + p.c1 * y + p.b1 * v, f2

    def _stop_force(self, y, v, xi_ddot, contact, ext=0.0) -> float:
        """Force of spring 11's stop that makes the punch move with the slider (y'' = xi'')."""
        f1, f2 = self._spring6_and_fabric(y, v, contact)
        return self.p.m * (xi_ddot + GRAVITY) + f1 - f2 - ext

    def _compresses_on_release(self, y, v, xi_ddot, contact, ext=0.0) -> bool:
        """Leaving the stop: into spring 11 (stop force above F30) or off the slider (below 0)."""
        return self._stop_force(y, v, xi_ddot, contact, ext) > self.p.F30

    # --- switching functions: negative while the current flag is consistent -------------------
    def _contact_g(self, y, v):
        """< 0 inside the contact set {y < 0 and F2* > 0}."""
        return max(y, self.p.c2 * y + self.p.b2 * v)

    def _spring_g(self, y, v, xi, xi_dot):
        """< 0 inside the compression set {Delta > 0 and F3* > 0}."""
        p = self.p
        delta = xi - y
        return max(-delta, -(p.F30 + p.c3 * delta + p.b3 * (xi_dot - v)))

    def _release_g(self, y, v, xi_ddot, contact, ext=0.0):
        """< 0 while the stop can hold the punch: stop force in [0, F30]."""
        f = self._stop_force(y, v, xi_ddot, contact, ext)
        return max(f - self.p.F30, -f)

    def _consistent_flags(self, y, v, xi, xi_dot) -> tuple[bool, bool]:
        """(contact, spring_on) as the state itself decides them."""
        contact = self._contact_g(y, v) < 0.0
        spring_on = self._spring_g(y, v, xi, xi_dot) < 0.0 if self.p.compression_only else True
        return contact, spring_on

    def _sticks(self, y, v, xi, xi_dot, xi_ddot, contact, spring_on, ext=0.0) -> bool:
        """Whether the punch, at the stop of spring 11, comes to rest on it: the stop can hold
        it (stop force in [0, F30]) and the excursion the current mode would start (ballistic:
        2·|Delta'| / |Delta''|) is shorter than the switch search resolves. The relative kinetic
        energy given up, m·Delta'^2 / 2, is below m·(|Delta''|·T/32)^2 / 2."""
        p = self.p
        if not self.has_stop:
            return False
        f3_star = p.F30 + p.c3 * (xi - y) + p.b3 * (xi_dot - v)
        if f3_star < 0.5 * p.F30:           # a zero of F3* inside the travel, not the stop
            return False
        if not 0.0 <= self._stop_force(xi, xi_dot, xi_ddot, contact, ext) <= p.F30:
            return False
        f1, f2 = self._spring6_and_fabric(y, v, contact)
        a = (-f1 + f2 + (f3_star if spring_on else 0.0) + ext) / p.m - GRAVITY
        excursion_speed = abs(xi_dot - v)
        return 2.0 * excursion_speed <= abs(xi_ddot - a) * self.shortest_period / _SAMPLES_PER_PERIOD

    # --- one communication step ----------------------------------------------------------------
    def step(self, s: PunchState, x0: float, x1: float, x2: float, h: float,
             e0: float = 0.0, e1: float = 0.0) -> PunchState:
        """Advance by h under the excitation xi(τ) = x0 + x1·τ + x2·τ², τ in [0, h], and the
        external force e0 + e1·τ."""
        y, v, contact, spring_on, held = s.y, s.y_dot, s.contact, s.spring_on, s.held
        landings = s.landings
        if held:
            # the punch rides on the slider: it starts this step where the new inputs put it,
            # and leaves the stop at once if the stop cannot hold it under them
            y, v = x0, x1
            if self._release_g(y, v, 2.0 * x2, contact, e0) > 0.0:
                held, spring_on = False, self._compresses_on_release(y, v, 2.0 * x2, contact, e0)
        elif self.p.compression_only:
            # new inputs may have moved the slider: re-decide whether spring 11 bears
            spring_on = self._spring_g(y, v, x0, x1) < 0.0
        t0 = 0.0
        f2_max = 0.0
        search = self.shortest_period / _SAMPLES_PER_PERIOD
        intervals = math.ceil(h / search)
        if intervals > MAX_SEARCH_INTERVALS:
            raise StepTooLong(
                f"a step of {h:g} s needs {intervals:.3g} switch-search intervals of {search:.3g} s "
                f"(1/{_SAMPLES_PER_PERIOD} of the punch's shortest natural period); at most "
                f"{MAX_SEARCH_INTERVALS} per step: take steps of at most "
                f"{MAX_SEARCH_INTERVALS * search:.3g} s")
        # a guard against an endless loop; every excursion that is not held spans a good part of
        # a search sub-interval, so the count scales with them
        budget = _MAX_SWITCHES_PER_STEP + 4 * intervals
        for _ in range(budget):
            piece = self._piece(y, v, contact, spring_on, held, x0, x1, x2, t0, e0, e1)
            event = self._first_switch(piece, contact, spring_on, held, x0, x1, x2, t0, h, e0, e1)
            t_end = h if event is None else event[0]
            if contact:
                f2_max = max(f2_max, self._largest_F2(piece, t_end - t0))
            if event is None:
                y, v = piece.state(h - t0)
                return PunchState(y, v, contact, spring_on, landings, f2_max, held)
            t_switch, which = event
            y, v = piece.state(t_switch - t0)
            t0 = t_switch
            xi_ddot = 2.0 * x2
            if which == "contact":
                contact = not contact
                landings += contact
            elif held:
                held = False
                spring_on = self._compresses_on_release(y, v, xi_ddot, contact, e0 + e1 * t0)
            else:
                spring_on = not spring_on
                xi, xi_dot = x0 + t0 * (x1 + t0 * x2), x1 + 2.0 * t0 * x2
                if self._sticks(y, v, xi, xi_dot, xi_ddot, contact, spring_on, e0 + e1 * t0):
                    held, spring_on, y, v = True, True, xi, xi_dot
        raise ZenoError(f"more than {budget} contact switches within one step of {h:g} s "
                        f"(y = {y:.6g} m): the contact chatters; check c2, b2, c3, b3")

    def _largest_F2(self, piece, length: float) -> float:
        """Largest fabric force -(c2·y + b2·y') on a contact piece of the given length."""
        c2, b2 = self.p.c2, self.p.b2

        def force(tau):
            y, v = piece.state(tau)
            return -(c2 * y + b2 * v)

        def slope(tau):
            y, v = piece.state(tau)
            return -(c2 * v + b2 * piece.accel(tau, y, v))

        best = max(force(0.0), force(length))
        lo, hi = 0.0, length
        if slope(lo) > 0.0 > slope(hi):      # an interior maximum: bisect on the slope
            while hi - lo > _TIME_RESOLUTION * 1e3:
                mid = 0.5 * (lo + hi)
                if slope(mid) > 0.0:
                    lo = mid
                else:
                    hi = mid
            best = max(best, force(0.5 * (lo + hi)))
        return max(best, 0.0)

    def _piece(self, y, v, contact, spring_on, held, x0, x1, x2, t0, e0=0.0, e1=0.0):
        """The exact solution from time t0 of the step, in the current mode."""
        p = self.p
        b, c = p.b1, p.c1
        # excitation re-centred at t0: xi(t0 + u) = a0 + a1·u + a2·u²
        a0 = x0 + t0 * (x1 + t0 * x2)
        a1 = x1 + 2.0 * t0 * x2
        a2 = x2
        if held:
            return _Held(a0, a1, a2)
        f0, f1, f2 = -p.F10 - p.m * GRAVITY + e0 + e1 * t0, e1, 0.0
        if contact:
            b += p.b2
            c += p.c2
        if spring_on:
            b += p.b3
            c += p.c3
            f0 += p.F30 + p.c3 * a0 + p.b3 * a1
            f1 += p.c3 * a1 + 2.0 * p.b3 * a2
            f2 += p.c3 * a2
        return DampedOscillator(p.m, b, c, f0, f1, f2, y, v)

    def _switch_functions(self, piece, tau, contact, spring_on, held, x0, x1, x2, t_abs,
                          e0=0.0, e1=0.0):
        """Switching functions at piece time tau, signed so that > 0 means 'flip this flag'."""
        y, v = piece.state(tau)
        g = self._contact_g(y, v)
        out = [("contact", g if contact else -g)]
        if held:
            out.append(("spring", self._release_g(y, v, 2.0 * x2, contact, e0 + e1 * t_abs)))
        elif self.p.compression_only:
            xi = x0 + t_abs * (x1 + t_abs * x2)
            xi_dot = x1 + 2.0 * t_abs * x2
            gs = self._spring_g(y, v, xi, xi_dot)
            out.append(("spring", gs if spring_on else -gs))
        return out

    def _first_switch(self, piece, contact, spring_on, held, x0, x1, x2, t0, h, e0=0.0, e1=0.0):
        """(time in the step, which flag) of the first switch in (t0, h], or None."""
        n_sub = max(1, math.ceil((h - t0) / (self.shortest_period / _SAMPLES_PER_PERIOD)))

        def funcs(t):
            return self._switch_functions(piece, t - t0, contact, spring_on, held, x0, x1, x2, t,
                                          e0, e1)

        t_prev = t0
        for k in range(1, n_sub + 1):
            t = t0 + (h - t0) * k / n_sub
            hits = [name for name, val in funcs(t) if val > 0.0]
            if hits:
                best = None
                for name in hits:
                    t_hit = self._bisect(lambda tt, nm=name: dict(funcs(tt))[nm], t_prev, t)
                    if best is None or t_hit < best[0]:
                        best = (t_hit, name)
                return best
            t_prev = t
        return None

    @staticmethod
    def _bisect(f, lo, hi):
        """Smallest bracket end where f > 0, with f(lo) <= 0 < f(hi); returns the 'hi' end so the
        new mode starts strictly inside its own set."""
        while hi - lo > _TIME_RESOLUTION * max(1.0, abs(hi)):
            mid = 0.5 * (lo + hi)
            if mid <= lo or mid >= hi:
                break
            if f(mid) > 0.0:
                hi = mid
            else:
                lo = mid
        return hi
