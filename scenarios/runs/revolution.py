"""One whole revolution of a run's shaft against the crank angle (Run.revolution in sewfmu/api.py):
what a plot over the crank angle wants, without the line a wrapped angle draws from 360° back
to 0°."""
from __future__ import annotations

import numpy as np

from sewfmu.scenarios.format.values import ScenarioError


def revolution(series, column: str, k: int, name: str):
    """The k-th whole revolution (k=-1 the last, as the analyses read it) of the shaft whose
    unwrapped angle is `column` of the structured array `series`: its samples with
    0 <= phi - 2πn < 2π, as a structured array with a field `crank_deg` (in [0, 360),
    increasing) before the recorded fields."""
    if series is None or column not in (series.dtype.names or ()):
        raise ScenarioError(f"{name}: revolution() reads the shaft's angle {column}, which the "
                            f"run did not record (add it to record)")
    phi = series[column]
    # the scenario's clock ends a run on a turn: a sample a rounding below it belongs to it
    turn = np.floor(phi / (2 * np.pi) + 1e-9)
    whole = [n for n in range(int(turn[0]), int(turn[-1]))
             if phi[0] <= 2 * np.pi * n + 1e-9 and (turn == n).sum() > 1]
    if not whole or not -len(whole) <= k < len(whole):
        raise ScenarioError(f"{name}: revolution({k}): the run holds {len(whole)} whole "
                            f"revolutions of {column}")
    rows = series[turn == whole[k]]
    one = np.empty(len(rows), dtype=[("crank_deg", "f8")] + rows.dtype.descr)
    # a sample a rounding below the turn's start or end stays inside [0, 360)
    one["crank_deg"] = np.clip(np.degrees(rows[column] - 2 * np.pi * whole[k]), 0.0,
                               np.nextafter(360.0, 0.0))
    for field in rows.dtype.names:
        one[field] = rows[field]
    return one
