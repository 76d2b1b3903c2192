"""The documentation's Python examples as a user runs them: pasted into a script and run with
`python try.py` in a fresh process, from an empty folder elsewhere (and through stdin, `python -
< try.py`), not exec'd inside pytest. A sweep's worker processes, the start-up, the files written
beside the script: what only a fresh process shows (a sweep from a plain script without a main
guard once failed every point there while the in-pytest test passed)."""
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tests.paths import REPO


def _blocks(page: str) -> list[str]:
    text = (REPO / page).read_text(encoding="utf-8")
    return re.findall(r"^```python\n(.*?)^```", text, re.M | re.S)


def _run(script: str, folder: Path, fmu_dir: Path, stdin: bool = False,
         timeout: float = 900) -> subprocess.CompletedProcess:
    path = folder / "try.py"
    path.write_text(script, encoding="utf-8")
    env = {**os.environ, "SEWFMU_FMU_DIR": str(fmu_dir), "PYTHONWARNINGS": "error::UserWarning"}
    env.pop("PYTHONPATH", None)
    command = [sys.executable, "-"] if stdin else [sys.executable, str(path)]
    with open(path, "rb") as source:
        return subprocess.run(command, cwd=folder, env=env, capture_output=True, text=True,
                              timeout=timeout, stdin=source if stdin else subprocess.DEVNULL)


def _check(proc: subprocess.CompletedProcess, what: str) -> None:
    assert proc.returncode == 0, f"{what} fails as a script:\n{proc.stdout[-2000:]}\n" \
                                 f"{proc.stderr[-4000:]}"
    assert "Traceback" not in proc.stderr, proc.stderr[-4000:]


@pytest.mark.slow
@pytest.mark.parametrize("stdin", [False, True], ids=["python try.py", "python - < try.py"])
def test_the_readme_example_runs_as_a_script(tmp_path, fmu_dir, stdin):
    (block,) = _blocks("README.md")
    _check(_run(block, tmp_path, fmu_dir, stdin), "README.md's example")


@pytest.mark.slow
def test_the_api_page_runs_as_one_script(tmp_path, fmu_dir):
    """docs/api.md's examples in order, as one script (each uses what the earlier defined)."""
    blocks = _blocks("docs/api.md")
    assert len(blocks) >= 6
    _check(_run("\n".join(blocks), tmp_path, fmu_dir), "docs/api.md's examples")
    assert not (REPO / "try.py").exists()


@pytest.mark.slow
def test_the_design_page_runs_as_one_script(design_page):
    """Run once for all the tests that read its results (tests/conftest.py's design_page)."""
    assert {"preload", "weld", "fabric", "stroke", "fast", "width", "rate", "rank"} <= \
        set(design_page)
