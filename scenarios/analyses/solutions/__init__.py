"""The models solved without the co-simulation: evaluated over arrays of crank angles
(sampling.py) and the punch drive as one ODE (punch_monolithic.py), for the figures' monolithic
comparisons and the plots."""
