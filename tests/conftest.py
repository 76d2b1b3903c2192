"""Shared fixtures: the FMUs built once per test session into a temporary folder, FMI 2.0
(`fmu_paths`) and FMI 3.0 (`fmu3_paths`); `fmus` gives each in turn, for the tests
of the FMUs themselves."""
import atexit
import os
import shutil
import tempfile

import pytest
from hypothesis import settings

from sewfmu.scenarios.fmu_build.build import build_all, default_fmu_dir

# Property tests draw the same examples on every run ("ci", the default), so that a red CI names a
# real, reproducible failure; HYPOTHESIS_PROFILE=explore draws new ones, many more of them.
settings.register_profile("ci", max_examples=25, derandomize=True, database=None, deadline=None)
settings.register_profile("explore", max_examples=1000, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

# the FMUs the tests build are extracted into a cache of this session's (scenarios/cosim/fmu_cache.py),
# not the user's: every build is a new file, and would stay there for weeks
if "SEWFMU_CACHE_DIR" not in os.environ:
    os.environ["SEWFMU_CACHE_DIR"] = tempfile.mkdtemp(prefix="sewfmu_test_cache_")
    atexit.register(shutil.rmtree, os.environ["SEWFMU_CACHE_DIR"], True)


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fmus")
    build_all(folder)
    return folder


@pytest.fixture(scope="session")
def fmu_paths(fmu_dir):
    return {p.stem: p for p in fmu_dir.glob("*.fmu")}


@pytest.fixture(scope="session")
def fmu3_dir(fmu_dir):
    folder = default_fmu_dir(3, fmu_dir)      # where a run with experiment.fmi = 3 looks
    build_all(folder, fmi=3)
    return folder


@pytest.fixture(scope="session")
def fmu3_paths(fmu3_dir):
    return {p.stem: p for p in fmu3_dir.glob("*.fmu")}


@pytest.fixture(params=[2, 3], ids=["fmi2", "fmi3"])
def fmus(request):
    return request.getfixturevalue("fmu_paths" if request.param == 2 else "fmu3_paths")


@pytest.fixture(scope="session", autouse=True)
def _free_test_hosts():
    """Free every test host's FMU instance before the interpreter exits (see fmu_host.py)."""
    yield
    from tests.fmu_host import close_all
    close_all()
