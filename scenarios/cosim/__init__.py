"""The co-simulation engine: FMU instances and their FMI calls, the connected system, the run
loop with its recorder and rollback, divergence and Ctrl-C; the algorithms in algorithms/.
Imports the format, never runs or interop."""
