"""Extracted FMUs kept between runs and processes (scenarios/cosim/fmu_cache.py): one folder per FMU
content, shared by concurrent runs, its bytecode kept, stale entries removed, and a plain
temporary extraction where there is no cache to write. What the cache may touch, and damaged,
bombed and killed extractions: tests/cosim/test_cache_owns.py."""
import os
import subprocess
import sys
import time
from pathlib import Path

from sewfmu.scenarios.cosim import fmu_cache
from tests.paths import REPO

_EXTRACT_AND_RUN = """
import sys
from pathlib import Path
from sewfmu.scenarios.cosim.fmi_calls import LogCollector
from sewfmu.scenarios.cosim.instances import open_instance
inst = open_instance("shaft", Path(sys.argv[1]), LogCollector())
inst.real_out = ["phi"]
inst.prepare(); inst.instantiate(); inst.enter_initialization(1.0); inst.exit_initialization()
inst.do_step(0.0, 0.5); inst.read_outputs(); inst.release()
print(inst.unzip_dir, inst.out_buf[0])
"""


def _run(fmu: Path, cache: Path, **env):
    return subprocess.Popen([sys.executable, "-c", _EXTRACT_AND_RUN, str(fmu)],
                            env={**os.environ, "SEWFMU_CACHE_DIR": str(cache),
                                 "PYTHONDONTWRITEBYTECODE": "1", **env},
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO)


def test_concurrent_runs_share_one_extraction_with_its_bytecode(fmu_paths, tmp_path):
    cache = tmp_path / "cache"
    runs = [_run(fmu_paths["MainShaft"], cache) for _ in range(4)]     # all at once
    outputs = [p.communicate(timeout=120) for p in runs]
    assert all(p.returncode == 0 for p in runs), [err[-500:] for _, err in outputs]
    folders = {out.split()[0] for out, _ in outputs}
    assert len(folders) == 1 and {out.split()[1] for out, _ in outputs} == {"50.0"}
    folder = Path(folders.pop())
    assert folder.parent.parent == cache / fmu_cache.SUBFOLDER and folder.name == "fmu"
    # one entry, no scratch folder left (the lock and the backup tools' tag are the cache's own)
    assert sorted(p.name for p in folder.parent.parent.iterdir()) == sorted(
        [folder.parent.name, "CACHEDIR.TAG", ".sewfmu-lock"])
    # the FMU's code left its bytecode, PYTHONDONTWRITEBYTECODE notwithstanding
    assert list(folder.glob("resources/*/__pycache__/*.pyc"))
    # and the bytecode is no damage: a later run uses the entry as it is
    marker = (folder.parent / fmu_cache.MARKER).stat()
    again = _run(fmu_paths["MainShaft"], cache)
    assert again.communicate(timeout=120)[0].split()[0] == str(folder)
    assert (folder.parent / fmu_cache.MARKER).stat().st_ino == marker.st_ino


def test_another_content_is_another_entry_and_stale_ones_go(fmu_paths, tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    monkeypatch.setenv("SEWFMU_CACHE_DIR", str(cache))
    first = fmu_cache.extract_cached(fmu_paths["MainShaft"])
    assert fmu_cache.extract_cached(fmu_paths["MainShaft"]) == first       # reused
    assert fmu_cache.is_cached(first)
    old = time.time() - (fmu_cache.STALE_DAYS + 1) * 86400
    os.utime(Path(first).parent, (old, old))          # the entry, which a use touches
    second = fmu_cache.extract_cached(fmu_paths["PunchLinkage"])
    assert second != first and Path(second).is_dir()
    assert not Path(first).parent.exists()          # unused for longer than STALE_DAYS
    # beyond MAX_ENTRIES the least recently used go (if unused for an hour)
    monkeypatch.setattr(fmu_cache, "MAX_ENTRIES", 1)
    os.utime(Path(second).parent, (time.time() - 7200,) * 2)
    third = fmu_cache.extract_cached(fmu_paths["PunchContact"])
    assert Path(third).is_dir() and not Path(second).parent.exists()


def test_without_a_cache_to_write_the_fmu_is_extracted_for_the_process(fmu_paths, tmp_path,
                                                                        monkeypatch):
    monkeypatch.setenv("SEWFMU_CACHE_DIR", "")
    folder = fmu_cache.extract_cached(fmu_paths["MainShaft"])
    assert (Path(folder) / "modelDescription.xml").is_file()
    assert not fmu_cache.is_cached(folder)
    assert Path(folder).name.startswith(f"sewfmu-fmu-{os.getpid()}-")   # a killed run's: found
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setenv("SEWFMU_CACHE_DIR", str(blocked / "cache"))
    assert fmu_cache.cache_root() is None
