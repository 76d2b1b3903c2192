"""The co-simulation algorithms by name (experiment.master): Jacobi and Gauss–Seidel
(fixed_step.py), iterative (coupling.py), adaptive (adaptive.py). The run loop that steps them is
scenarios/master.py; their settings are scenarios/algorithm_settings.py's.
"""
from __future__ import annotations

from sewfmu.scenarios.cosim.algorithms.adaptive import Adaptive
from sewfmu.scenarios.cosim.algorithms.fixed_step import GaussSeidel, Jacobi
from sewfmu.scenarios.cosim.algorithms.iterative import Iterative

ALGORITHMS = {cls.name: cls for cls in (Jacobi, GaussSeidel, Iterative, Adaptive)}

