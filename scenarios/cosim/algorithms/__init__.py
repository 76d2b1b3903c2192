"""The co-simulation algorithms by name (experiment.master): Jacobi and Gauss–Seidel
(fixed_step.py), iterative (coupling.py), adaptive (adaptive.py). The run loop that steps them is
scenarios/master.py; their settings are scenarios/algorithm_settings.py's.
"""
from __future__ import annotations

from .adaptive import Adaptive
from .coupling import Iterative
from .fixed_step import GaussSeidel, Jacobi

ALGORITHMS = {cls.name: cls for cls in (Jacobi, GaussSeidel, Iterative, Adaptive)}

