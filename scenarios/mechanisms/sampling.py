"""Models evaluated over arrays of crank angles, for the analyses and plots.

The models in components/ run inside the FMUs and so take plain floats (standard library only).
An analysis wants a whole revolution at once: `sampled(model.motion, phi)` evaluates the model at
every element of its (broadcast) array arguments and returns the same structure (a Motion, an
Excitation, a dict of Motions, a tuple, ...) with a numpy array of that shape in every leaf.
"""
from __future__ import annotations

import dataclasses
from typing import Any, Callable

import numpy as np

from sewfmu.components.kinematics import AssemblyError


def sampled(evaluate: Callable[..., Any], *args) -> Any:
    """`evaluate(*scalars)` at every element of the broadcast `args`, stacked leaf by leaf.

    An AssemblyError at some sample is raised with `.index`, the flat index of that sample."""
    arrays = np.broadcast_arrays(*[np.asarray(a, dtype=float) for a in args])
    shape = arrays[0].shape
    flat = [a.ravel() for a in arrays]
    results = []
    for k in range(flat[0].size if flat else 0):
        try:
            results.append(evaluate(*(float(a[k]) for a in flat)))
        except AssemblyError as err:
            err.index = k
            raise
    return _stack(results, shape)


def _stack(results: list, shape: tuple) -> Any:
    first = results[0]
    if dataclasses.is_dataclass(first):
        return type(first)(**{f.name: _stack([getattr(r, f.name) for r in results], shape)
                              for f in dataclasses.fields(first)})
    if isinstance(first, dict):
        return {key: _stack([r[key] for r in results], shape) for key in first}
    if isinstance(first, tuple):
        items = [_stack([r[i] for r in results], shape) for i in range(len(first))]
        return type(first)(*items) if hasattr(first, "_fields") else tuple(items)
    return np.asarray(results).reshape(shape)
