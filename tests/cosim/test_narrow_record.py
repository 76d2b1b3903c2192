"""A designer's own scenario one step beside the documented path: a narrowed record plots what is
there and names what a picture needs in one line; to_pandas without pandas names the extra."""
import subprocess
import sys
from pathlib import Path

import pytest

import sewfmu
from tests.paths import REPO


def _narrow(tmp_path) -> Path:
    """docs/scenarios.md's example (its record list leaves out linkage.xi)."""
    text = (REPO / "docs" / "scenarios.md").read_text(encoding="utf-8")
    toml = text.split("```toml", 1)[1].split("```", 1)[0]
    assert "linkage.xi" not in toml.split("record", 1)[1].split("\n", 1)[0]
    path = tmp_path / "narrow.toml"
    path.write_text(toml, encoding="utf-8")
    return path


@pytest.mark.slow
def test_a_narrowed_record_plots_what_is_there_and_names_what_is_missing(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "sewfmu", "run", str(_narrow(tmp_path)),
                           "--plot", "--animate", "--report", "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "a bug in sewfmu" not in proc.stderr and "KeyError" not in proc.stderr
    warnings = [line for line in proc.stderr.splitlines() if line.startswith("sewfmu: warning")]
    assert warnings and all("linkage.xi" in line for line in warnings)
    assert {"narrow.png", "report.html", "results.csv"} <= {p.name for p in
                                                            (tmp_path / "o").iterdir()}


def test_to_pandas_without_pandas_names_the_extra(monkeypatch):
    run = sewfmu.run("punch_drive", set={"experiment.revolutions": 2})
    monkeypatch.setitem(sys.modules, "pandas", None)          # as if it were not installed
    with pytest.raises(sewfmu.Error, match=r"pip install .*\[pandas\]"):
        run.to_pandas()
