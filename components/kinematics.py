"""Planar kinematics shared by every linkage: points in motion, cranks, dyads.

A point in motion is a `Motion`: position, velocity and acceleration, each an array whose last
axis is (x, y). Leading axes are free, so one call evaluates a whole crank revolution at once.
Velocities and accelerations come from the differentiated loop-closure equations (never from
finite differences): for a dyad with |X - P| = r_P and |X - Q| = r_Q,

    (X - P)·(dX - dP) = 0                       (velocity loop)
    (X - P)·(ddX - ddP) + |dX - dP|² = 0        (acceleration loop)

and the same for Q, a 2×2 linear system in dX (ddX) whose matrix is singular exactly when the dyad
is stretched or folded flat (the limit of assembly).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

LEFT = +1   # X on the left of the directed line P -> Q: (Q - P) × (X - P) > 0
RIGHT = -1


class AssemblyError(ValueError):
    """A linkage cannot be assembled: the two links of a dyad cannot reach each other."""


@dataclass(frozen=True)
class Motion:
    """Position, velocity and acceleration of a point; arrays of shape (..., 2)."""
    pos: np.ndarray
    vel: np.ndarray
    acc: np.ndarray

    @staticmethod
    def fixed(x: float, y: float, shape=()) -> "Motion":
        pos = np.broadcast_to(np.array([x, y], dtype=float), tuple(shape) + (2,))
        zero = np.zeros_like(pos)
        return Motion(pos, zero, zero)


@dataclass(frozen=True)
class Angle:
    """An angle with its first and second time derivatives (arrays of one shape)."""
    value: np.ndarray
    rate: np.ndarray
    accel: np.ndarray


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", a, b)


def _unit(angle: np.ndarray) -> np.ndarray:
    return np.stack([np.cos(angle), np.sin(angle)], axis=-1)


def _perp(v: np.ndarray) -> np.ndarray:
    """v turned by +90°."""
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


def point_on_link(pivot: Motion, length: float, angle: Angle, offset: float = 0.0) -> Motion:
    """A point at `length` from `pivot` on a link whose direction is `angle + offset` (rad).

    Used for cranks (the angle is the driven crank angle) and for arms rigid with a rocker.
    """
    e = _unit(np.asarray(angle.value) + offset)
    n = _perp(e)
    w = np.asarray(angle.rate)[..., None]
    dw = np.asarray(angle.accel)[..., None]
    return Motion(pivot.pos + length * e,
                  pivot.vel + length * w * n,
                  pivot.acc + length * (dw * n - w * w * e))


def link_angle(start: Motion, end: Motion) -> Angle:
    """Direction of the vector start -> end (rad, CCW from +x), with rate and acceleration.

    Valid for a link of constant length, where d/dt(r × dr) = r × ddr.
    """
    r = end.pos - start.pos
    v = end.vel - start.vel
    a = end.acc - start.acc
    r2 = _dot(r, r)
    return Angle(np.arctan2(r[..., 1], r[..., 0]), _cross(r, v) / r2, _cross(r, a) / r2)


def _first_failure(bad: np.ndarray) -> int:
    return int(np.flatnonzero(np.ravel(bad))[0])


def dyad_rrr(p: Motion, r_p: float, q: Motion, r_q: float, side: int, name: str = "dyad") -> Motion:
    """Joint X of two links (lengths r_p from P, r_q from Q): circle–circle intersection.

    `side` is LEFT or RIGHT of the directed line P -> Q. Raises AssemblyError naming the first
    sample (flat index `AssemblyError.index`) where the circles do not intersect.
    """
    d_vec = q.pos - p.pos
    d2 = _dot(d_vec, d_vec)
    d = np.sqrt(d2)
    # distance from P, along P->Q, to the chord through the two intersection points
    along = (d2 + r_p * r_p - r_q * r_q) / (2.0 * d)
    h2 = r_p * r_p - along * along
    bad = ~(h2 >= 0.0) | ~(d > 0.0)
    if np.any(bad):
        err = AssemblyError(f"{name}: links of {r_p:.6g} m and {r_q:.6g} m cannot meet")
        err.index = _first_failure(bad)
        raise err
    e = d_vec / d[..., None]
    pos = p.pos + along[..., None] * e + (side * np.sqrt(h2))[..., None] * _perp(e)

    # velocity and acceleration loops: rows of J are (X - P) and (X - Q)
    a_row = pos - p.pos
    b_row = pos - q.pos
    det = _cross(a_row, b_row)

    def solve(rhs_a: np.ndarray, rhs_b: np.ndarray) -> np.ndarray:
        # Cramer's rule for [a_row; b_row] · X = [rhs_a; rhs_b]
        x = (rhs_a * b_row[..., 1] - rhs_b * a_row[..., 1]) / det
        y = (a_row[..., 0] * rhs_b - b_row[..., 0] * rhs_a) / det
        return np.stack([x, y], axis=-1)

    vel = solve(_dot(a_row, p.vel), _dot(b_row, q.vel))
    dvp = vel - p.vel
    dvq = vel - q.vel
    acc = solve(_dot(a_row, p.acc) - _dot(dvp, dvp), _dot(b_row, q.acc) - _dot(dvq, dvq))
    return Motion(pos, vel, acc)


def dyad_rrp(c: Motion, r: float, line_point: tuple[float, float], line_angle: float, side: int,
             name: str = "slider") -> Motion:
    """Slider X on a fixed line, joined to C by a rod of length r: circle–line intersection.

    The line passes through `line_point` with direction `line_angle` (rad). `side` = +1 takes the
    intersection further along the line direction, -1 the one behind.
    """
    u = np.array([np.cos(line_angle), np.sin(line_angle)])
    rel = c.pos - np.asarray(line_point, dtype=float)
    along = _dot(rel, u)
    off = _cross(u, rel)          # signed distance of C from the line
    h2 = r * r - off * off
    bad = ~(h2 >= 0.0)
    if np.any(bad):
        err = AssemblyError(f"{name}: rod of {r:.6g} m cannot reach the slider line")
        err.index = _first_failure(bad)
        raise err
    s = along + side * np.sqrt(h2)
    pos = np.asarray(line_point, dtype=float) + s[..., None] * u
    rod = pos - c.pos
    denom = _dot(rod, u)
    s_dot = _dot(rod, c.vel) / denom
    vel = s_dot[..., None] * u
    dv = vel - c.vel
    s_ddot = (_dot(rod, c.acc) - _dot(dv, dv)) / denom
    return Motion(pos, vel, s_ddot[..., None] * u)
