"""The regression references as a foreign FMI host replays them (tests/hosts/test_fmucheck.py,
tests/hosts/test_fmusim.py): what to run, and whether its output reproduces the reference."""
import numpy as np

from sewfmu.scenarios.references.fmu_reference import read_options
from sewfmu.scenarios.references.regression import REFERENCE_DIR


def reference_case(name: str):
    """(options of the .opt file, the input file or None, the expected rows) of FMU `name`."""
    folder = REFERENCE_DIR / name
    inputs = folder / f"{name}_in.csv"
    return (read_options(folder / f"{name}_ref.opt"), inputs if inputs.exists() else None,
            np.genfromtxt(folder / f"{name}_ref.csv", delimiter=",", names=True))


def assert_reproduces(got, ref, reltol: float, rows: int | None = None) -> None:
    """Every column of `got` within reltol × the column's largest value of the reference's,
    over its first `rows` rows (all of them by default)."""
    for column in ref.dtype.names:
        scale = max(np.abs(ref[column]).max(), 1e-300)
        assert np.abs(got[column] - ref[column][:rows]).max() <= reltol * scale, column
