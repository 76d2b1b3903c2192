"""The native FMUs, built once per test session into a temporary folder (each from its Python
FMU, built there too): `native_fmu(name, fmi)` -> the .fmu's path."""
from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def native_fmu(tmp_path_factory):
    from sewfmu.scenarios.fmu_build.native import build_native_fmu  # the builder: only to build

    root = tmp_path_factory.mktemp("native_fmu")
    built = {}

    def build(name: str, fmi: int = 2):
        if (name, fmi) not in built:
            built[name, fmi] = build_native_fmu(name, root / f"native{fmi}", fmi=fmi,
                                                python_dir=root / f"python{fmi}")
        return built[name, fmi]
    return build
