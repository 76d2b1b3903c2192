"""The record of a run that did not finish (runs/results.py keep_unfinished) after the attack:
written within the 2 s an interruption takes however long it is (a record too long to format as
CSV in time is the whole record as results.npy), a user's file in the way refused with its
reason, and a staging folder a killed writer left inside OUT/interrupted/ removed by the next
finished run. Records are checked value for value against the arrays they were made from."""
import subprocess
import sys
import time

import numpy as np
import pytest

from sewfmu.errors import Error
from sewfmu.scenarios.cosim.master import RunResult
from sewfmu.scenarios.runs import results
from tests.fake_fmu import fake_scenario


def _record(rows: int) -> RunResult:
    t = np.linspace(0.0, 1.0, rows)
    columns = {f"a.x{k}": np.sin((k + 1) * t) * 10.0 ** k for k in range(7)}
    return RunResult(fake_scenario({}, [], 1.0, 0.1), t, columns, 0.0,
                     units={name: "m" for name in columns})


def test_a_short_record_is_csv_with_every_value(tmp_path):
    record = _record(1000)
    said = results.keep_unfinished(record, "interrupted (SIGINT) at t = 1 s", tmp_path)
    path = tmp_path / "interrupted" / "results.csv"
    assert said == f"the record up to t = 1 s is in {path}"
    with open(path, encoding="utf-8") as f:
        assert f.readline().strip() == "time [s]," + ",".join(f"a.x{k} [m]" for k in range(7))
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    np.testing.assert_array_equal(data[:, 0], record.time)
    for k in range(7):
        np.testing.assert_array_equal(data[:, k + 1], record.columns[f"a.x{k}"])


@pytest.mark.slow
def test_a_400000_row_record_is_kept_whole_within_the_budget(tmp_path):
    record = _record(400_000)
    started = time.monotonic()
    said = results.keep_unfinished(record, "interrupted (SIGINT) at t = 1 s", tmp_path)
    took = time.monotonic() - started
    assert took < results.CSV_BUDGET + 0.8, took
    folder = tmp_path / "interrupted"
    name = "results.csv" if (folder / "results.csv").exists() else "results.npy"
    assert said.startswith(f"the record up to t = 1 s is in {folder / name}")
    if name == "results.npy":                  # the usual case on a 2-core machine
        assert "400000 rows" in said
        kept = np.load(folder / name)
        assert kept.dtype.names[0] == "time [s]" and kept.dtype.names[1] == "a.x0 [m]"
        np.testing.assert_array_equal(kept["time [s]"], record.time)
        for k in range(7):
            np.testing.assert_array_equal(kept[f"a.x{k} [m]"], record.columns[f"a.x{k}"])


def test_a_users_own_interrupted_results_csv_is_refused_with_its_reason(tmp_path):
    (tmp_path / "interrupted").mkdir()
    mine = tmp_path / "interrupted" / "results.csv"
    mine.write_text("my,own\n1,2\n")
    with pytest.raises(Error) as caught:
        results.keep_unfinished(_record(10), "interrupted (SIGINT)", tmp_path)
    assert "results.csv" in str(caught.value)
    assert mine.read_text() == "my,own\n1,2\n"


def test_the_next_finished_run_removes_what_a_killed_writer_left_in_interrupted(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    pid = int(dead.stdout)
    left = tmp_path / "interrupted" / f".outputs.sewfmu-{pid}.partial"
    (left / "deep").mkdir(parents=True)
    (left / "deep" / "results.csv").write_text("1,2\n" * 1000)
    users = tmp_path / "interrupted" / "notes.txt"
    users.write_text("mine")
    results.forget_unfinished(tmp_path)
    assert not left.exists()
    assert users.read_text() == "mine"
