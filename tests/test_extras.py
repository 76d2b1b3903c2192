"""Every place an optional package is used says, when it is missing, which extra installs it and
how, in one line (sewfmu.MissingExtra, a sewfmu.Error), from the API as from the command line;
never a bare ModuleNotFoundError. A missing package is simulated as Python does it: None in
sys.modules makes its import raise ModuleNotFoundError."""
import sys

import numpy as np
import pytest

import sewfmu
from sewfmu.extras import EXTRAS, require
from sewfmu.scenarios.design import sensitivity as design_sensitivity
from sewfmu.scenarios.design.optimize import Optimum
from sewfmu.scenarios.design.sensitivity import Sensitivity


def _missing(monkeypatch, *modules):
    for name in modules:
        monkeypatch.setitem(sys.modules, name, None)


def test_require_names_the_extra_and_the_command(monkeypatch):
    _missing(monkeypatch, "pandas")
    with pytest.raises(sewfmu.MissingExtra) as err:
        require("pandas", "to_pandas()")
    assert isinstance(err.value, sewfmu.Error) and isinstance(err.value, ModuleNotFoundError)
    assert err.value.name == "pandas"
    line = str(err.value)
    assert "\n" not in line and line.startswith("to_pandas() needs the optional package pandas")
    assert "pip install" in line and "[pandas]" in line


def test_a_package_that_is_not_an_extra_is_not_dressed_up(monkeypatch):
    with pytest.raises(ModuleNotFoundError) as err:
        require("no_such_module_sewfmu_test", "a test")
    assert not isinstance(err.value, sewfmu.Error)


def test_every_extra_names_a_section_of_pyproject():
    import tomllib
    from pathlib import Path

    extras = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())[
        "project"]["optional-dependencies"]
    assert set(EXTRAS.values()) <= set(extras)


def test_design_results_to_pandas(monkeypatch):
    table = np.zeros(2, dtype=[("a", "f8")])
    optimum = Optimum("s", {}, {}, {}, table, True, True, "local", "brentq", {}, "", 0, 0.0)
    indices = Sensitivity("s", "sobol", table, {}, 2, 0)
    _missing(monkeypatch, "pandas")
    for result in (optimum, indices):
        with pytest.raises(sewfmu.MissingExtra, match=r"\[pandas\]"):
            result.to_pandas()


def test_sensitivity_without_salib_says_so_before_any_run(monkeypatch):
    _missing(monkeypatch, "SALib", "SALib.sample", "SALib.sample.sobol", "SALib.sample.morris")
    problem = {"num_vars": 1, "names": ["a"], "bounds": [[0, 1]]}
    for method in ("sobol", "morris"):
        with pytest.raises(sewfmu.MissingExtra, match=r"needs the optional package SALib.*\[design\]"):
            design_sensitivity.sample(method, problem, 4)


def test_sweep_on_a_scheduler_without_dask(monkeypatch, tmp_path):
    _missing(monkeypatch, "distributed")
    with pytest.raises(sewfmu.MissingExtra, match=r"Dask scheduler.*\[dask\]"):
        sewfmu.sweep("punch_drive", grid={"punch.c2": [30000.0, 40000.0]},
                     set={"experiment.revolutions": 1}, scheduler="tcp://127.0.0.1:1",
                     out=tmp_path / "s")
