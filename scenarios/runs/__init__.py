"""Runs and what they leave: a run with its files and provenance, [compare] variants, the
comparison with a monolithic solution, sweeps and their workers, progress, report.html."""
