"""sewfmu's version: the one place it is written (pyproject.toml and the FMUs read it here)."""
__version__ = "0.2.0"
