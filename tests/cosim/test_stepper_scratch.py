"""The compiled step loop with sewfmu's cache off (SEWFMU_CACHE_DIR="") or unwritable: compiled
into a temporary folder that is gone once the library is loaded, so that no run leaves a
sewfmu-stepper-* folder in $TMPDIR (attack46b, failure 2)."""
import os
import stat
import subprocess
import sys

import pytest

from sewfmu.scenarios.cosim import stepper

LOAD = ("from sewfmu.scenarios.cosim import stepper; lib = stepper.library(); "
        "assert lib is not None; print(lib.sew_jacobi_steps is not None)")


def _load_in_a_process(tmp_path, cache: str) -> list[str]:
    """Load the compiled loop in a fresh process with TMPDIR an empty folder of its own;
    return what is left in that folder afterwards."""
    tmpdir = tmp_path / "tmpdir"
    tmpdir.mkdir()
    env = {**os.environ, "TMPDIR": str(tmpdir), "SEWFMU_CACHE_DIR": cache}
    done = subprocess.run([sys.executable, "-c", LOAD], env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "True"
    return sorted(os.listdir(tmpdir))


@pytest.fixture(autouse=True)
def _compiler():
    try:
        stepper._host_compiler()
    except FileNotFoundError:
        pytest.skip("no C compiler for the compiled loop")


def test_the_cache_off_leaves_nothing_in_tmpdir(tmp_path):
    assert _load_in_a_process(tmp_path, "") == []


def test_an_unwritable_cache_leaves_nothing_in_tmpdir(tmp_path):
    # a file where the cache's folder would be: unwritable even for root
    blocked = tmp_path / "cache"
    blocked.write_text("not a folder")
    blocked.chmod(stat.S_IRUSR)
    assert _load_in_a_process(tmp_path, str(blocked)) == []


def test_a_failed_compile_leaves_nothing_in_tmpdir(tmp_path, monkeypatch):
    tmpdir = tmp_path / "tmpdir"
    tmpdir.mkdir()
    monkeypatch.setenv("TMPDIR", str(tmpdir))
    monkeypatch.setenv("SEWFMU_CACHE_DIR", "")
    monkeypatch.setattr(stepper.tempfile, "tempdir", None)     # read TMPDIR again
    monkeypatch.setattr(stepper, "SOURCE", tmp_path / "missing.c")
    tmp_path.joinpath("missing.c").write_text("this is not C\n")
    with pytest.raises(RuntimeError):
        stepper._compiled()
    assert os.listdir(tmpdir) == []
