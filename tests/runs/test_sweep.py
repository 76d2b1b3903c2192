"""Sweeps: a Dask cluster on loopback gives the local pool's table, a failing point does not stop
the sweep, and an interrupted sweep resumes where it stopped."""
import csv
import json

import pytest

from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.runs.sweep import POINTS_FILE, grid_points, run_sweep

GRID = {"shaft.omega0": [100.0, 250.0], "punch.F30": [0.0, 8.0]}


def _scenario():
    sc = load("punch_drive")
    sc.revolutions = 2
    return sc


def _table(folder):
    with open(folder / "sweep.csv") as f:
        return [{k: v for k, v in row.items() if k != "wall_time_s"} for row in csv.DictReader(f)]


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


@pytest.mark.slow
def test_dask_cluster_gives_the_same_table_as_the_local_pool(tmp_path):
    distributed = pytest.importorskip("distributed")
    points = grid_points(GRID)
    local = run_sweep(_scenario(), points, tmp_path / "local", workers=2, progress=False)
    assert [r["status"] for r in local] == ["ok"] * 4
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        run_sweep(_scenario(), points, tmp_path / "dask", scheduler=cluster.scheduler_address,
                  progress=False)
    assert _table(tmp_path / "dask") == _table(tmp_path / "local")
    # and the points differ from each other: the sweep really changed the parameters
    assert len({row["F2_weld_mean"] for row in _table(tmp_path / "local")}) == 4


def test_a_failing_point_is_recorded_and_the_sweep_goes_on(tmp_path):
    points = grid_points({"linkage.L_AB": [39.0e-3, 29.0e-3, 38.8e-3]})
    rows = run_sweep(_scenario(), points, tmp_path, workers=2, progress=False)
    assert [r["status"] for r in rows] == ["ok", "failed", "ok"]
    assert "cannot be assembled at crank angle" in rows[1]["error"]
    table = _table(tmp_path)
    assert table[1]["status"] == "failed" and table[1]["error"]
    assert table[2]["F2_weld_mean"]


@pytest.mark.slow
def test_an_interrupted_sweep_resumes_where_it_stopped(tmp_path):
    points = grid_points(GRID)
    run_sweep(_scenario(), points, tmp_path, workers=2, progress=False)
    lines = (tmp_path / POINTS_FILE).read_text().splitlines()
    kept = [json.loads(line) for line in lines[:2]]
    for row in kept:
        row["F2_weld_mean"] = -1.0          # a mark: a recomputed point would lose it
    # as if interrupted after two points, in the middle of writing the third: its record
    # listed before the first point (as a sweep does), then appended to
    from sewfmu.scenarios.files.outputs import Record, claim  # as the sweep writes it

    killed = tmp_path / "killed"
    killed.mkdir()
    claim(killed, [POINTS_FILE])
    with Record(killed / POINTS_FILE) as record:
        record.write("".join(json.dumps(r) + "\n" for r in kept) + lines[2][: len(lines[2]) // 2])
    rows = run_sweep(_scenario(), points, killed, workers=2, progress=False)
    marked = {r["key"] for r in kept}
    for row in rows:
        assert row["status"] == "ok"
        assert (row["F2_weld_mean"] == -1.0) == (row["key"] in marked)


def test_the_workers_preload_modules_that_exist():
    """multiprocessing's fork server skips a preload it cannot import, silently: every worker
    would then import sewfmu itself."""
    import importlib

    from sewfmu.scenarios.runs.sweep import WORKER_PRELOAD
    for name in WORKER_PRELOAD:
        importlib.import_module(name)
