"""The punch drive split at the fabric: the punch body (PunchBody) and the welded material (Fabric)
as two components, the same physics as PunchContact cut where the punch meets the material.

PunchBody integrates m·y'' = -F1 + F2 + F3 - m·g with F2 an input (the fabric's force on the
punch): within a step F2(τ) = F2 + F2'·τ from its inputs, exactly as PunchContact integrates
without a fabric (its pieces are the same damped oscillators, its spring-11 switches located the
same way).

Fabric computes F2 from the punch's y and y' by the unilateral, non-retaining law

    F2 = -(c2·y + b2·y')   while y < 0 and that is > 0,   else 0

which needs no memory: the contact is decided by the punch's state. Within a step it extrapolates
the punch's motion from its inputs (y + y'·τ + y''·τ²/2) to locate where contact begins or ends
inside the step and the largest F2 on the way (the impact at landing falls between communication
points); its outputs at a communication point follow its inputs at that point (direct
feedthrough), so a master that exchanges after every step gives the body the force of the punch's
own new state.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields, make_dataclass

from .parameters import validate
from .punch_contact import PunchContact, PunchContactParams

# the fabric's switch search: sub-intervals per step (its extrapolated motion is a parabola, so
# at most two crossings of y = 0 and of c2·y + b2·y' = 0 each; 8 intervals separate them)
_FABRIC_INTERVALS = 8
_TIME_RESOLUTION = 1e-15


# the fabric's parameters: what PunchContact's law of F2 uses
FABRIC = ("c2", "b2")


def _params_of_punch(name: str, keep) -> type:
    """A parameter dataclass with PunchContact's parameters that `keep` selects: the same
    defaults, units, descriptions and order, declared once."""
    chosen = [(f.name, f.type, field(default=f.default, metadata=f.metadata))
              for f in fields(PunchContactParams) if keep(f.name)]
    made = make_dataclass(name, chosen, frozen=True)
    made.__module__ = __name__
    return made


# PunchContact's parameters without the fabric's, and the fabric's alone
PunchBodyParams = _params_of_punch("PunchBodyParams", lambda name: name not in FABRIC)
FabricParams = _params_of_punch("FabricParams", lambda name: name in FABRIC)


class PunchBody(PunchContact):
    """PunchContact without the fabric: F2 is an external force (PunchContact.step's e0, e1)."""

    def __init__(self, params: PunchBodyParams = PunchBodyParams()):
        validate(params)
        values = {f.name: getattr(params, f.name) for f in fields(params)}
        # no fabric inside: with c2 = b2 = 0 the contact set {y < 0, c2·y + b2·y' < 0} is empty
        self._set_up(PunchContactParams(**values, **{name: 0.0 for name in FABRIC}))


@dataclass(frozen=True)
class FabricStep:
    """What the fabric saw within one step of the punch's extrapolated motion."""
    F2_max: float              # the largest F2 in the step
    switches: tuple[tuple[float, bool], ...]    # (time in the step, contact after it)


class Fabric:
    """The welded material: F2 from the punch's height and speed (unilateral, non-retaining)."""

    def __init__(self, params: FabricParams = FabricParams()):
        validate(params)
        self.p = params

    def in_contact(self, y: float, v: float) -> bool:
        return y < 0.0 and self.p.c2 * y + self.p.b2 * v < 0.0

    def force(self, y: float, v: float) -> float:
        """F2 >= 0: the fabric pushes the punch up while the punch presses into it."""
        return -(self.p.c2 * y + self.p.b2 * v) if self.in_contact(y, v) else 0.0

    def force_rate(self, y: float, v: float, a: float) -> float:
        """dF2/dt for the punch's acceleration a (0 out of contact)."""
        return -(self.p.c2 * v + self.p.b2 * a) if self.in_contact(y, v) else 0.0

    def step(self, y0: float, v0: float, a0: float, h: float) -> FabricStep:
        """Contact switches and the largest F2 along y0 + v0·τ + a0·τ²/2, τ in [0, h]."""
        def state(t):
            return y0 + t * (v0 + 0.5 * a0 * t), v0 + a0 * t

        def g(t):                       # < 0 inside the contact set
            y, v = state(t)
            return max(y, self.p.c2 * y + self.p.b2 * v)

        switches = []
        contact = g(0.0) < 0.0
        t_prev = 0.0
        for k in range(1, _FABRIC_INTERVALS + 1):
            t = h * k / _FABRIC_INTERVALS
            if (g(t) < 0.0) != contact:
                t_switch = _bisect(lambda tt, c=contact: (g(tt) < 0.0) != c, t_prev, t)
                contact = not contact
                switches.append((t_switch, contact))
            t_prev = t
        return FabricStep(self._largest_force(y0, v0, a0, h, switches), tuple(switches))

    def _largest_force(self, y0, v0, a0, h, switches) -> float:
        """The largest F2 on the contact pieces of the step. F2(τ) = -(c2·y + b2·y') is a
        parabola in τ: its largest value on a piece is at an end or at its vertex."""
        c2, b2 = self.p.c2, self.p.b2
        # F2(τ) = q0 + q1·τ + q2·τ²
        q0 = -(c2 * y0 + b2 * v0)
        q1 = -(c2 * v0 + b2 * a0)
        q2 = -0.5 * c2 * a0
        edges = [0.0] + [t for t, _ in switches] + [h]
        inside = [self.in_contact(y0, v0)] + [c for _, c in switches]
        best = 0.0
        for (lo, hi), contact in zip(zip(edges, edges[1:]), inside):
            if not contact:
                continue
            candidates = [lo, hi]
            if q2 < 0.0:
                vertex = -q1 / (2.0 * q2)
                if lo < vertex < hi:
                    candidates.append(vertex)
            best = max(best, *(q0 + t * (q1 + t * q2) for t in candidates))
        return max(best, 0.0)


def _bisect(flipped, lo: float, hi: float) -> float:
    """The first time in (lo, hi] where `flipped` holds, to the time resolution."""
    while hi - lo > _TIME_RESOLUTION * max(1.0, abs(hi)):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        if flipped(mid):
            hi = mid
        else:
            lo = mid
    return hi
