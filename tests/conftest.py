"""Shared fixtures: the FMUs built once per test session into a temporary folder."""
import pytest

from components.build import build_all


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fmus")
    build_all(folder)
    return folder


@pytest.fixture(scope="session")
def fmu_paths(fmu_dir):
    return {p.stem: p for p in fmu_dir.glob("*.fmu")}


@pytest.fixture(scope="session", autouse=True)
def _free_test_hosts():
    """Free every test host's FMU instance before the interpreter exits (see fmu_host.py)."""
    yield
    from tests.fmu_host import close_all
    close_all()
