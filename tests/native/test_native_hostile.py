"""A native FMU under a hostile host (hostile/hostile_host.c), built from the FMU's own
sources with AddressSanitizer and UndefinedBehaviorSanitizer: mutated serialized states, random
value references, NaN and infinite values, negative steps, in a loop. No memory error, no
undefined behaviour, and no altered state is ever accepted."""
from __future__ import annotations

import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest

from sewfmu.scenarios.fmu_build.native import MODEL_FILES, MODELS
from tests.native.fmpy_native import Instance

HOST = Path(__file__).resolve().parent / "hostile" / "hostile_host.c"


@pytest.mark.slow
@pytest.mark.parametrize("name", list(MODEL_FILES))
def test_a_hostile_host_finds_no_memory_error_and_no_accepted_forgery(native_fmu, name,
                                                                      tmp_path):
    if not all((MODELS / f).is_file() for f in MODEL_FILES[name]):
        pytest.skip(f"{name}: native/models/ lacks one of {', '.join(MODEL_FILES[name])}")
    if not shutil.which("gcc"):
        pytest.skip("no gcc")
    fmu = native_fmu(name, 2)
    with zipfile.ZipFile(fmu) as archive:
        archive.extractall(tmp_path)
    sources = tmp_path / "sources"
    host = tmp_path / "hostile"
    built = subprocess.run(["gcc", "-std=c99", "-g", "-O1", "-ffp-contract=off",
                            "-fsanitize=address,undefined", "-fno-sanitize-recover=all",
                            f"-I{sources}", str(HOST), *map(str, sorted(sources.glob("*.c"))),
                            "-o", str(host), "-lm"], capture_output=True, text=True)
    if built.returncode != 0 and "sanitize" in built.stderr:
        pytest.skip(f"gcc cannot build with the sanitizers here: {built.stderr[:200]}")
    assert built.returncode == 0, built.stderr
    done = subprocess.run([str(host), Instance.describe(fmu).guid, "20000"],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip() == "foreign states accepted: 0", done.stdout
