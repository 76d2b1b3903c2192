"""Planar kinematics shared by every linkage: points in motion, cranks, dyads.

A point in motion is a `Motion`: position, velocity and acceleration as separate x and y
components, plain floats. Everything here uses the standard library only (`math`), because this
code runs inside the FMUs, in whatever Python the FMI host embeds; analyses that want a whole
crank revolution at once evaluate it sample by sample (scenarios/analyses/solutions/sampling.py).

Velocities and accelerations come from the differentiated loop-closure equations (never from
finite differences): for a dyad with |X - P| = r_P and |X - Q| = r_Q,

    (X - P)·(dX - dP) = 0                       (velocity loop)
    (X - P)·(ddX - ddP) + |dX - dP|² = 0        (acceleration loop)

and the same for Q, a 2×2 linear system in dX (ddX) whose matrix is singular exactly when the dyad
is stretched or folded flat (the limit of assembly).
"""
from __future__ import annotations

import math
from typing import Callable, NamedTuple

LEFT = +1   # X on the left of the directed line P -> Q: (Q - P) × (X - P) > 0
RIGHT = -1


class AssemblyError(ValueError):
    """A linkage cannot be assembled: the two links of a dyad cannot reach each other."""


# named tuples rather than frozen dataclasses: they are made several times per joint and per
# step in the FMUs' hot path, and a tuple is made several times faster
class Motion(NamedTuple):
    """Position (x, y), velocity (vx, vy) and acceleration (ax, ay) of a point."""
    x: float
    y: float
    vx: float = 0.0
    vy: float = 0.0
    ax: float = 0.0
    ay: float = 0.0


class Angle(NamedTuple):
    """An angle with its first and second time derivatives."""
    value: float
    rate: float = 0.0
    accel: float = 0.0


def angle(value, rate=0.0, accel=0.0) -> Angle:
    return Angle(float(value), float(rate), float(accel))


def point_on_link(pivot: Motion, length: float, ang: Angle, offset: float = 0.0) -> Motion:
    """A point at `length` from `pivot` on a link whose direction is `ang + offset` (rad).

    Used for cranks (the driven crank angle) and for arms rigid with a rocker.
    """
    c, s = math.cos(ang.value + offset), math.sin(ang.value + offset)
    w, dw = ang.rate, ang.accel
    w2 = w * w
    return Motion(pivot.x + length * c, pivot.y + length * s,
                  pivot.vx - length * w * s, pivot.vy + length * w * c,
                  pivot.ax + length * (-dw * s - w2 * c), pivot.ay + length * (dw * c - w2 * s))


def link_angle(start: Motion, end: Motion) -> Angle:
    """Direction of the vector start -> end (rad, CCW from +x), with rate and acceleration.

    Valid for a link of constant length, where d/dt(r × dr) = r × ddr.
    """
    rx, ry = end.x - start.x, end.y - start.y
    vx, vy = end.vx - start.vx, end.vy - start.vy
    ax, ay = end.ax - start.ax, end.ay - start.ay
    r2 = rx * rx + ry * ry
    return Angle(math.atan2(ry, rx), (rx * vy - ry * vx) / r2, (rx * ay - ry * ax) / r2)


def dyad_rrr(p: Motion, r_p: float, q: Motion, r_q: float, side: int, name: str = "dyad") -> Motion:
    """Joint X of two links (lengths r_p from P, r_q from Q): circle–circle intersection.

    `side` is LEFT or RIGHT of the directed line P -> Q. Raises AssemblyError where the circles
    do not intersect.
    """
    dx, dy = q.x - p.x, q.y - p.y
    d2 = dx * dx + dy * dy
    if not d2 > 0.0:
        raise AssemblyError(f"{name}: the two pivots coincide")
    d = math.sqrt(d2)
    # distance from P, along P->Q, to the chord through the two intersection points
    along = (d2 + r_p * r_p - r_q * r_q) / (2.0 * d)
    h2 = r_p * r_p - along * along
    if not h2 >= 0.0:
        raise AssemblyError(f"{name}: links of {r_p:.6g} m and {r_q:.6g} m cannot meet")
    ex, ey = dx / d, dy / d
    hh = side * math.sqrt(h2)
    x, y = p.x + along * ex - hh * ey, p.y + along * ey + hh * ex

    # velocity and acceleration loops; rows of the matrix are (X - P) and (X - Q)
    ax_, ay_ = x - p.x, y - p.y
    bx_, by_ = x - q.x, y - q.y
    det = ax_ * by_ - ay_ * bx_
    if det == 0.0:
        raise AssemblyError(f"{name}: links of {r_p:.6g} m and {r_q:.6g} m are stretched flat")

    # each system solved by Cramer's rule: (ra·by - rb·ay) / det, (ax·rb - bx·ra) / det,
    # written out twice rather than as a function made at every call (the FMUs' hot path)
    ra, rb = ax_ * p.vx + ay_ * p.vy, bx_ * q.vx + by_ * q.vy
    vx, vy = (ra * by_ - rb * ay_) / det, (ax_ * rb - bx_ * ra) / det
    dvpx, dvpy = vx - p.vx, vy - p.vy
    dvqx, dvqy = vx - q.vx, vy - q.vy
    ra = ax_ * p.ax + ay_ * p.ay - (dvpx * dvpx + dvpy * dvpy)
    rb = bx_ * q.ax + by_ * q.ay - (dvqx * dvqx + dvqy * dvqy)
    accx, accy = (ra * by_ - rb * ay_) / det, (ax_ * rb - bx_ * ra) / det
    return Motion(x, y, vx, vy, accx, accy)


def dyad_rrp(c: Motion, r: float, line_point: tuple[float, float], line_angle: float, side: int,
             name: str = "slider") -> Motion:
    """Slider X on a fixed line, joined to C by a rod of length r: circle–line intersection.

    The line passes through `line_point` with direction `line_angle` (rad). `side` = +1 takes the
    intersection further along the line direction, -1 the one behind.
    """
    ux, uy = math.cos(line_angle), math.sin(line_angle)
    relx, rely = c.x - line_point[0], c.y - line_point[1]
    along = relx * ux + rely * uy
    off = ux * rely - uy * relx          # signed distance of C from the line
    h2 = r * r - off * off
    if not h2 >= 0.0:
        raise AssemblyError(f"{name}: rod of {r:.6g} m cannot reach the slider line")
    s = along + side * math.sqrt(h2)
    x, y = line_point[0] + s * ux, line_point[1] + s * uy
    rodx, rody = x - c.x, y - c.y
    denom = rodx * ux + rody * uy
    if denom == 0.0:
        raise AssemblyError(f"{name}: rod of {r:.6g} m stands square to the slider line")
    s_dot = (rodx * c.vx + rody * c.vy) / denom
    dvx, dvy = s_dot * ux - c.vx, s_dot * uy - c.vy
    s_ddot = (rodx * c.ax + rody * c.ay - (dvx * dvx + dvy * dvy)) / denom
    return Motion(x, y, s_dot * ux, s_dot * uy, s_ddot * ux, s_ddot * uy)


def crank_turn(samples: int) -> list[float]:
    """`samples` crank angles evenly over one turn, from 0 (inclusive) to 2π (exclusive)."""
    step = 2.0 * math.pi / samples
    return [k * step for k in range(samples)]


def check_assembly(evaluate: Callable[[float], object], mechanism: str, params,
                   angle_name: str = "crank angle", samples: int = 3600) -> list:
    """Evaluate a linkage over one crank turn (every 360/samples degrees) and return what
    `evaluate` gave at each angle; if it cannot be assembled somewhere, raise AssemblyError
    naming the first crank angle and the parameters."""
    values = []
    for crank in crank_turn(samples):
        try:
            values.append(evaluate(crank))
        except (AssemblyError, ZeroDivisionError) as err:
            listed = ", ".join(f"{k}={v:g}" for k, v in vars(params).items())
            raise AssemblyError(f"{mechanism} cannot be assembled at {angle_name} = "
                                f"{math.degrees(crank):.1f}° ({err}); parameters: {listed}") from None
    return values
