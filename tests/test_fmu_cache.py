"""Extracted FMUs kept between runs and processes (scenarios/cosim/fmu_cache.py): one folder per FMU
content, shared by concurrent runs, its bytecode kept, stale entries removed, and a plain
temporary extraction where there is no cache to write."""
import os
import subprocess
import sys
import time
from pathlib import Path

from sewfmu.scenarios.cosim import fmu_cache

REPO = Path(__file__).resolve().parent.parent

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
    entries = [p for p in cache.iterdir()]
    assert [p.name for p in entries] == [Path(folders.pop()).name]    # no scratch folder left
    # the FMU's code left its bytecode, PYTHONDONTWRITEBYTECODE notwithstanding
    assert list(entries[0].glob("resources/*/__pycache__/*.pyc"))


def test_another_content_is_another_entry_and_stale_ones_go(fmu_paths, tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    monkeypatch.setenv("SEWFMU_CACHE_DIR", str(cache))
    first = fmu_cache.extract_cached(fmu_paths["MainShaft"])
    assert fmu_cache.extract_cached(fmu_paths["MainShaft"]) == first       # reused
    old = time.time() - (fmu_cache.STALE_DAYS + 1) * 86400
    os.utime(first, (old, old))
    second = fmu_cache.extract_cached(fmu_paths["PunchLinkage"])
    assert second != first and Path(second).is_dir()
    assert not Path(first).exists()                 # unused for longer than STALE_DAYS


def test_without_a_cache_to_write_the_fmu_is_extracted_for_the_process(fmu_paths, tmp_path,
                                                                        monkeypatch):
    monkeypatch.setenv("SEWFMU_CACHE_DIR", "")
    folder = fmu_cache.extract_cached(fmu_paths["MainShaft"])
    assert (Path(folder) / "modelDescription.xml").is_file()
    assert not fmu_cache.is_cached(folder)
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setenv("SEWFMU_CACHE_DIR", str(blocked / "cache"))
    assert fmu_cache.cache_root() is None
