"""The co-simulation algorithms by name (experiment.master): Jacobi and Gauss-Seidel
(fixed_step.py), iterative (iterative.py), adaptive (adaptive.py); the interface they share is
base.py, the run loop that steps them cosim/master.py. Their names and settings are the format's
(format/master_settings.py), so that a file is checked without the engine.
"""
from __future__ import annotations

from sewfmu.scenarios.cosim.algorithms.adaptive import Adaptive
from sewfmu.scenarios.cosim.algorithms.fixed_step import GaussSeidel, Jacobi
from sewfmu.scenarios.cosim.algorithms.iterative import Iterative

ALGORITHMS = {cls.name: cls for cls in (Jacobi, GaussSeidel, Iterative, Adaptive)}

# the masters that step every FMU once per fixed communication step (what a container FMU does)
FIXED_STEP = tuple(name for name, cls in ALGORITHMS.items()
                   if not cls.rolls_back and not cls.variable_step)
