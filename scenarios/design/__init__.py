"""Design studies: work over many runs of one scenario, each a point of a design space.

- space.py: what a study varies (`instance.parameter` between two bounds, with units, checked
  against the ranges the FMUs declare) and what it asks of the key figures (a goal, constraints,
  with units);
- evaluations.py: runs at points of the space, in this process (the FMUs extracted and loaded
  once, no files) or in the sweep engine's worker processes; every point remembered by its
  identity in evaluations.csv, so that a study run again into its folder resumes;
- optimize.py (scipy.optimize), fit.py (scipy.optimize.least_squares against measurements),
  sensitivity.py (SALib's Morris and Sobol methods, the samples run as a sweep);
- plots.py: the pictures of the three.

A point that fails (an FMU refusing a value, a diverging coupling: a sewfmu Error) is an
infeasible point with its reason, never a crash of the study and never a number.
"""
