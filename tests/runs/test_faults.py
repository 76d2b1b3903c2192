"""Faults, signals and odd input: sweeps never lose or mix data, worker processes live and die with
the sweep, an interruption is an interruption, outputs are whole and follow the umask, and every
mistake is one line that says what and where. Real signals and real processes throughout."""
import contextlib
import csv
import json
import math
import os
import pty
import random
import re
import select
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest

from sewfmu.cli import main
from sewfmu.scenarios.files.outputs import OutputError, Record, claim
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.format.values import ScenarioError
from sewfmu.scenarios.runs.sweep import POINTS_FILE, grid_points, points_of, run_sweep, settings_of
from sewfmu.scenarios.runs.workers import WorkerDied, run_tasks
from tests.paths import REPO

pytestmark = [pytest.mark.slow]

PUNCH = (REPO / "scenarios" / "catalogue" / "punch_drive.toml").read_text()
GRID = {"shaft.omega0": [100.0, 250.0], "punch.F30": [0.0, 8.0]}


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


def _scenario(**punch):
    sc = load("punch_drive")
    sc.revolutions = 2
    sc.instances["punch"].parameters.update(punch)
    return sc


def _table(folder):
    with open(folder / "sweep.csv") as f:
        return [{k: v for k, v in row.items() if k != "wall_time_s"} for row in csv.DictReader(f)]


def _log_rows(folder):
    return [json.loads(line) for line in (folder / POINTS_FILE).read_text().splitlines()]


def _sewfmu(*args, **kw):
    return subprocess.Popen([sys.executable, "-m", "sewfmu", *args], cwd=kw.pop("cwd", REPO),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)


def _children(pid: int) -> dict[int, list[int]]:
    children = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(entry.name))
    return children


def _descendants(pid: int) -> set[int]:
    children, found, todo = _children(pid), set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.add(child)
            todo.append(child)
    return found


def _alive(pid: int) -> bool:
    try:
        state = (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _workers_of(pid: int) -> list[int]:
    """The sweep's worker processes: children of its forkserver."""
    def cmdline(child):
        try:
            return Path(f"/proc/{child}/cmdline").read_bytes()
        except OSError:                  # it has just ended
            return b""

    children = _children(pid)
    # the sweep runs in a child of the `sewfmu` process, which guards it (cosim/guardian.py)
    servers = [c for c in _descendants(pid) if b"forkserver" in cmdline(c)]
    return [w for s in servers for w in children.get(s, []) if _alive(w)]


def _wait_for(condition, timeout=60.0, what="condition"):
    deadline = time.time() + timeout
    while time.time() < deadline:
        if condition():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


# --- a sweep point is what decides its result ----------------------------------------------------
def test_a_rerun_with_other_settings_recomputes_and_one_with_the_same_reuses(tmp_path):
    points = grid_points(GRID)
    first = run_sweep(_scenario(), points, tmp_path, workers=2, progress=False)
    # other fixed settings (as --set punch.c3=... would give): every point is new
    stiffer = run_sweep(_scenario(c3=2.0e5), points, tmp_path, workers=2, progress=False)
    assert all(a["key"] != b["key"] for a, b in zip(first, stiffer))
    for a, b in zip(first, stiffer):
        if a["F2_weld_mean"] > 0 and a["shaft.omega0"] == 100.0:
            assert b["F2_weld_mean"] != pytest.approx(a["F2_weld_mean"], rel=1e-6)
    assert len(_log_rows(tmp_path)) == 8
    # the table holds the last run's settings only: no mix
    assert [float(r["F2_weld_mean"]) for r in _table(tmp_path)] == \
        [r["F2_weld_mean"] for r in stiffer]
    # back to the first settings: reused, not recomputed (nothing appended to the record, which
    # is the sweep's own: not edited here)
    again = run_sweep(_scenario(), points, tmp_path, workers=2, progress=False)
    assert [r["F2_weld_mean"] for r in again] == [r["F2_weld_mean"] for r in first]
    assert len(_log_rows(tmp_path)) == 8


def test_an_edited_scenario_file_or_other_fmu_code_makes_other_points(tmp_path, fmu_paths):
    sc = _scenario()
    base = settings_of(sc, fmu_paths)
    edited = _scenario()
    edited.step = 1.25e-4
    assert settings_of(edited, fmu_paths) != base
    fmi3 = _scenario()
    fmi3.set_value("experiment.fmi", 3)                # the same numbers, but other FMUs
    assert settings_of(fmi3, fmu_paths) != base
    # the same FMU with other code (its modelDescription's version carries the code hash)
    other = tmp_path / "PunchContact.fmu"
    with zipfile.ZipFile(fmu_paths["PunchContact"]) as src, zipfile.ZipFile(other, "w") as dst:
        for item in src.infolist():
            data = src.read(item)
            if item.filename == "modelDescription.xml":
                data = re.sub(rb'(<fmiModelDescription[^>]*\sversion=")', rb"\1changed-", data)
            dst.writestr(item, data)
    assert settings_of(sc, {**fmu_paths, "PunchContact": other}) != base
    point = grid_points(GRID)[0]
    assert point.identity(base) != point.identity(settings_of(edited, fmu_paths))


def test_damaged_log_lines_are_skipped_with_a_warning_and_the_points_rerun(tmp_path, capsys):
    points = grid_points(GRID)
    run_sweep(_scenario(), points, tmp_path, workers=2, progress=False)
    lines = (tmp_path / POINTS_FILE).read_text().splitlines()
    damaged = [lines[0], "", "[1, 2]", "null", '{"no": "key"}', lines[1], "\x00\x00\x00",
               lines[2][: len(lines[2]) // 2]]          # torn by a kill, without its newline
    # the damage done as the sweep's own writes (a crash, a kill), in a folder of its own: a
    # record the user edited is the user's, and refused
    tmp_path = tmp_path / "damaged"
    tmp_path.mkdir()
    claim(tmp_path, [POINTS_FILE])
    with Record(tmp_path / POINTS_FILE) as record:
        record.write("\n".join(damaged))
    capsys.readouterr()
    rows = run_sweep(_scenario(), points, tmp_path, workers=2, progress=False)
    err = capsys.readouterr().err
    assert "warning" in err and "damaged" in err and POINTS_FILE in err
    assert [r["status"] for r in rows] == ["ok"] * 4
    # the torn last line is cut off (the record is sewfmu's), the rows appended after it are
    # whole lines of their own
    text = (tmp_path / POINTS_FILE).read_text().splitlines()
    assert text[:len(damaged) - 1] == damaged[:-1] and damaged[-1] not in text
    appended = [json.loads(line) for line in text[len(damaged) - 1:]]
    assert len(appended) == 2 and all(r["status"] == "ok" for r in appended)
    assert _table(tmp_path) == _table_of_fresh_run(tmp_path / "fresh", points)


def _table_of_fresh_run(folder, points):
    run_sweep(_scenario(), points, folder, workers=2, progress=False)
    return _table(folder)


def test_a_point_that_failed_is_tried_again_on_a_rerun(tmp_path):
    points = grid_points({"linkage.L_AB": [39.0e-3, 29.0e-3]})     # 29 mm cannot be assembled
    rows = run_sweep(_scenario(), points, tmp_path, workers=2, keep_results=True, progress=False)
    assert [r["status"] for r in rows] == ["ok", "failed"]
    rows = run_sweep(_scenario(), points, tmp_path, workers=2, keep_results=True, progress=False)
    assert [r["status"] for r in rows] == ["ok", "failed"]
    # the failed point ran again (a row appended), the finished one did not
    assert sorted(r["linkage.L_AB"] for r in _log_rows(tmp_path)) == [29.0e-3, 29.0e-3, 39.0e-3]
    assert len(list((tmp_path / "points").glob("*/results.csv"))) == 1
    # a file where the points' folder would go: refused before any point runs, left alone
    other = tmp_path / "other"
    other.mkdir()
    (other / "points").write_text("in the way")
    with pytest.raises(OutputError, match="points there is a file where sewfmu would make"):
        run_sweep(_scenario(), points, other, workers=2, keep_results=True, progress=False)
    assert sorted(p.name for p in other.iterdir()) == ["points"]


def test_a_misspelt_sweep_parameter_is_refused_before_any_point_runs(tmp_path):
    with pytest.raises(ScenarioError, match="c33"):
        run_sweep(_scenario(), grid_points({"punch.c33": [1.0, 2.0]}), tmp_path, workers=2,
                  progress=False)
    assert not (tmp_path / POINTS_FILE).exists()
    with pytest.raises(ScenarioError, match="workers"):
        run_sweep(_scenario(), grid_points(GRID), tmp_path, workers=0, progress=False)


def test_workers_zero_is_refused_on_the_command_line(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["sweep", "punch_grid", "--workers", "0"])
    assert exit_.value.code == 1                     # a refusal like any other
    assert "--workers" in capsys.readouterr().err


def test_repeated_sweep_points_are_an_error():
    sc = load("punch_grid")
    sc.sweep = {"grid": {"shaft.omega0": [100.0, 200.0, 100.0]}}
    with pytest.raises(ScenarioError, match="the same"):
        points_of(sc)


# --- worker processes ----------------------------------------------------------------------------
def test_a_worker_that_dies_is_one_failed_task_and_the_others_go_on():
    tasks = [("root", math.sqrt, (4.0,)), ("abort", os.abort, ()), ("domain", math.sqrt, (-1.0,))]
    tasks += [(f"more{i}", math.sqrt, (float(i),)) for i in range(6)]
    answers = dict(run_tasks(tasks, workers=2))
    assert answers["root"] == 2.0
    assert isinstance(answers["abort"], WorkerDied) and "SIGABRT" in str(answers["abort"])
    assert isinstance(answers["domain"], RuntimeError) and "math domain error" in str(answers["domain"])
    assert [answers[f"more{i}"] for i in range(6)] == [math.sqrt(i) for i in range(6)]


def _slow_sweep(out: Path, revolutions: int = 30):
    return _sewfmu("sweep", "punch_grid", "--workers", "2", "--quiet", "--out", str(out),
                   "--set", f"experiment.revolutions={revolutions}")


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM, signal.SIGINT])
def test_the_workers_end_with_the_main_process_however_it_ends(tmp_path, sig):
    proc = _slow_sweep(tmp_path / "sweep")
    _wait_for(lambda: len(_workers_of(proc.pid)) == 2, what="two workers")
    family = _descendants(proc.pid)
    time.sleep(0.5)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == (-sig if sig == signal.SIGKILL else 128 + sig), err
    if sig != signal.SIGKILL:
        assert len(err.strip().splitlines()) == 1 and "interrupted" in err, err
    _wait_for(lambda: not [p for p in family if _alive(p)], timeout=10,
              what="every worker to end")


def test_random_workers_killed_the_final_table_equals_an_undisturbed_run(tmp_path):
    """The stress test: kill workers of a running sweep at random, then rerun the same command
    (which retries the points whose workers died): the table equals an undisturbed run's."""
    calm = _slow_sweep(tmp_path / "calm", revolutions=6)
    out, err = calm.communicate(timeout=300)
    assert calm.returncode == 0, err
    rng = random.Random(14)
    disturbed = _slow_sweep(tmp_path / "disturbed", revolutions=6)
    kills = 0
    while disturbed.poll() is None and kills < 4:
        time.sleep(rng.uniform(0.3, 1.0))
        workers = _workers_of(disturbed.pid)
        if workers:
            with contextlib.suppress(ProcessLookupError):       # it may just have ended
                os.kill(rng.choice(workers), signal.SIGKILL)
                kills += 1
    out, err = disturbed.communicate(timeout=300)
    assert disturbed.returncode == 0, err
    assert kills >= 1
    died = [r for r in _table(tmp_path / "disturbed") if r["status"] == "failed"]
    assert died and all("killed by SIGKILL" in r["error"] for r in died)
    assert len(died) <= kills
    rerun = _slow_sweep(tmp_path / "disturbed", revolutions=6)
    out, err = rerun.communicate(timeout=300)
    assert rerun.returncode == 0, err
    assert _table(tmp_path / "disturbed") == _table(tmp_path / "calm")


# --- interruption --------------------------------------------------------------------------------
@pytest.mark.parametrize("sig, delay", [(signal.SIGINT, 0.4), (signal.SIGINT, 1.5),
                                        (signal.SIGTERM, 1.5)])
def test_an_interrupted_run_exits_as_interrupted_and_keeps_only_its_record(tmp_path, sig, delay):
    out = tmp_path / "run"
    proc = _sewfmu("run", "punch_drive", "--set", "experiment.revolutions=400", "--out", str(out))
    time.sleep(delay)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 128 + sig, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "interrupted" in lines[0] and "failed" not in err, err
    # what it recorded, in OUT/interrupted/, or nothing at all before its first record; no
    # temporaries either
    written = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*"))
    if "nothing of the interrupted run was written" in lines[0]:
        assert written == [], written
    else:
        assert written == ["run", "run/interrupted", "run/interrupted/.sewfmu-outputs",
                           "run/interrupted/results.csv", "run/interrupted/summary.json"]
        assert f"is in {out / 'interrupted' / 'results.csv'}" in lines[0]


def test_an_interrupted_run_leaves_the_previous_results_as_they_were(tmp_path):
    out = tmp_path / "run"
    assert main(["run", "punch_drive", "--set", "experiment.revolutions=1", "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    proc = _sewfmu("run", "punch_drive", "--set", "experiment.revolutions=400", "--out", str(out))
    time.sleep(1.5)
    proc.send_signal(signal.SIGINT)
    proc.communicate(timeout=30)
    assert proc.returncode == 130
    # its own record goes beside them, into interrupted/, and leaves them as they were
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before
    assert sorted(os.listdir(tmp_path)) == ["run"]
    # the next run that finishes removes that record
    assert main(["run", "punch_drive", "--set", "experiment.revolutions=1", "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(before)


# --- outputs -------------------------------------------------------------------------------------
def test_a_compare_run_failing_in_its_third_variant_changes_nothing(tmp_path, capsys):
    def compare_file(values):
        path = tmp_path / "cmp.toml"
        path.write_text(PUNCH.replace("revolutions = 10", "revolutions = 1")
                        + f'\n[compare]\nparameter = "linkage.L_AB"\nvalues = {values}\n')
        return str(path)

    out = tmp_path / "out"
    assert main(["run", compare_file([39.0e-3, 38.9e-3]), "--out", str(out)]) == 0
    before = sorted(str(p.relative_to(out)) for p in out.rglob("*"))
    summary = (out / "summary.json").read_bytes()
    assert main(["run", compare_file([39.0e-3, 38.8e-3, 29.0e-3]), "--out", str(out)]) == 1
    assert "cannot be assembled" in capsys.readouterr().err
    assert sorted(str(p.relative_to(out)) for p in out.rglob("*")) == before
    assert (out / "summary.json").read_bytes() == summary
    assert sorted(os.listdir(tmp_path)) == ["cmp.toml", "out"]


@pytest.mark.parametrize("mask", [0o002, 0o027])
def test_files_follow_the_umask(tmp_path, mask):
    out = tmp_path / "out"
    proc = subprocess.run(["sh", "-c", f"umask {mask:03o} && exec {sys.executable} -m sewfmu "
                           f"run punch_drive --set experiment.revolutions=1 --out {out}"],
                          cwd=REPO, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    for name in ("results.csv", "summary.json"):
        assert (out / name).stat().st_mode & 0o777 == 0o666 & ~mask, name
    assert out.stat().st_mode & 0o777 == 0o777 & ~mask


def test_what_killed_runs_left_is_removed_by_the_next_run(tmp_path):
    dead = _dead_pid()
    out = tmp_path / "out"
    staging = out / f".outputs.sewfmu-{dead}.partial"
    staging.mkdir(parents=True)
    (staging / "results.csv").write_bytes(b"0" * 100_000)
    sweep = tmp_path / "sweep"
    sweep.mkdir()                # a point's results.csv pending, where a sweep writes it
    torn = sweep / f".point-x.results.csv.sewfmu-{dead}.tmp"
    torn.write_bytes(b"1" * 100_000)
    alive = out / f".outputs.sewfmu-{os.getppid()}.partial"   # a live process's: kept
    alive.mkdir()
    assert main(["run", "punch_drive", "--set", "experiment.revolutions=1", "--out", str(out)]) == 0
    assert not staging.exists() and alive.exists()
    run_sweep(_scenario(), grid_points({"shaft.omega0": [100.0]}), sweep, workers=1,
              progress=False)
    assert not torn.exists()


def test_temporaries_of_other_programs_and_notes_in_a_variant_folder_stay(tmp_path):
    """Only sewfmu's own temporaries are debris; a rerun replaces the files it wrote, not a
    variant folder with the user's notes in it."""
    dead = _dead_pid()
    out = tmp_path / "out"
    assert main(["run", "punch_speed", "--set", "experiment.revolutions=1", "--out",
                 str(out)]) == 0
    variant = next(p for p in out.iterdir() if p.is_dir())
    notes = variant / "notes.txt"
    notes.write_text("mine")
    other = out / f".editor.{dead}.tmp"                       # another program's, not ours
    other.write_text("theirs")
    assert main(["run", "punch_speed", "--set", "experiment.revolutions=1", "--out",
                 str(out)]) == 0
    assert notes.read_text() == "mine" and other.read_text() == "theirs"
    assert (variant / "results.csv").exists()


def test_sweep_points_that_differ_get_folders_of_their_own(tmp_path):
    """100 and 100.0000001 are two points, two folders, two result files."""
    sweep = tmp_path / "sweep"
    rows = run_sweep(_scenario(), grid_points({"shaft.omega0": [100.0, 100.0000001]}), sweep,
                     workers=1, progress=False, keep_results=True)
    assert [r["status"] for r in rows] == ["ok", "ok"]
    folders = sorted(p.name for p in (sweep / "points").iterdir() if p.is_dir())
    assert folders == ["shaft.omega0=100", "shaft.omega0=100.0000001"]


def test_a_users_own_files_in_the_output_folder_stay(tmp_path, monkeypatch):
    """A run replaces what the previous run wrote there, and nothing else: a scenario kept beside
    its results, a compare run that had variant folders, the current folder as --out."""
    mine = tmp_path / "thesis"
    mine.mkdir()
    (mine / "chapter1.tex").write_text("precious")
    scenario = mine / "mine.toml"
    scenario.write_text(PUNCH.replace("revolutions = 10", "revolutions = 1")
                        + '\n[compare]\nparameter = "shaft.omega0"\nvalues = [100.0, 200.0]\n')
    assert main(["run", str(scenario), "--out", str(mine)]) == 0
    assert {"chapter1.tex", "mine.toml", "summary.json", "shaft.omega0=100",
            "shaft.omega0=200"} <= set(os.listdir(mine))
    # the same folder, now without [compare]: the old variant folders go, the user's files stay
    scenario.write_text(PUNCH.replace("revolutions = 10", "revolutions = 1"))
    monkeypatch.chdir(mine)
    assert main(["run", "mine.toml", "--out", "."]) == 0
    assert sorted(p for p in os.listdir(mine) if not p.startswith(".")) == \
        ["chapter1.tex", "mine.toml", "results.csv", "summary.json"]
    assert (mine / "chapter1.tex").read_text() == "precious"


# --- scenario mistakes that used to pass silently ------------------------------------------------
@pytest.mark.parametrize("edit, words", [
    (lambda t: t.replace('"linkage.xi -> punch.xi",', '"linkage.xi -> punch.xi",\n  '
                         '"linkage.xi_dot -> punch.xi",'),
     ["input punch.xi has two sources", "linkage.xi", "linkage.xi_dot"]),
    (lambda t: t.replace("revolutions = 10", "stop_time = 0.1"), ["experiment.shaft", "stop_time"]),
    (lambda t: t + '\n[compare]\nparameter = "shaft.omega0"\nvalues = [100.0, 200.0]\nvalue = 3\n',
     ["compare.value"]),
    (lambda t: t + '\n[compare]\nparameter = "shaft.omega0"\nvalues = [100.0, 100.0]\n',
     ["compare.values", "more than once"]),
    (lambda t: t.replace('analysis = "punch"', 'analysis = "punch"\nrecord = ["punch.y", "punch.y"]'),
     ["record", "more than once"]),
    (lambda t: t.replace('[instances.punch]', '[instances."pun.ch"]'), ["instances.pun.ch", "'.'"]),
    (lambda t: t.replace('description = ', 'description = 5\nx = '), ["unknown key 'x'"]),
])
def test_scenario_mistakes_are_errors_naming_file_and_key(tmp_path, capsys, edit, words):
    path = tmp_path / "broken.toml"
    path.write_text(edit(PUNCH))
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "broken.toml" in err, err
    for word in words:
        assert word in err, err


def test_compare_over_a_setting_that_is_not_a_number(tmp_path):
    path = tmp_path / "masters.toml"
    path.write_text(PUNCH.replace("revolutions = 10", "revolutions = 1")
                    + '\n[compare]\nparameter = "experiment.master"\n'
                      'values = ["jacobi", "gauss-seidel"]\n')
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert set(summary["runs"]) == {"experiment.master=jacobi", "experiment.master=gauss-seidel"}
    assert {r["master"] for r in summary["runs"].values()} == {"jacobi", "gauss-seidel"}


# --- messages ------------------------------------------------------------------------------------
@pytest.mark.parametrize("encode", [lambda t: b"\xef\xbb\xbf" + t.encode("utf-8"),
                                    lambda t: t.encode("utf-16")])
def test_a_file_with_a_byte_order_mark_runs(tmp_path, encode):
    path = tmp_path / "marked.toml"
    path.write_bytes(encode(PUNCH.replace("revolutions = 10", "revolutions = 1")
                            .replace("Punch drive", "Punch drive, ω = 100 s⁻¹")))
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 0
    assert load(str(path)).description.startswith("Punch drive, ω")


@pytest.mark.parametrize("setting, words", [
    ("shaft.omega0=1e400", ["omega0", "finite", "range of a float"]),
    ("shaft.omega0=1" + "0" * 400, ["omega0", "range of a float", "401 digits"]),
    ("experiment.step=" + "9" * 400, ["experiment.step", "positive finite"]),
])
def test_numbers_beyond_a_float_are_explained(capsys, tmp_path, setting, words):
    assert main(["run", "punch_drive", "--set", setting, "--out", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and len(err) < 400, err
    for word in words:
        assert word in err, err


def test_a_file_in_another_encoding_is_named_with_its_line(tmp_path, capsys):
    path = tmp_path / "latin.toml"
    path.write_bytes(PUNCH.replace("Punch drive", "Punch drive, café").encode("latin-1"))
    assert main(["run", str(path)]) == 1
    err = capsys.readouterr().err.strip()
    assert "latin.toml: line 1" in err and "0xe9" in err and "UTF-8" in err, err


def test_a_closed_pipe_ends_quietly(tmp_path):
    proc = subprocess.run(f"{sys.executable} -m sewfmu list | head -1", shell=True,
                          cwd=REPO, capture_output=True, text=True, timeout=60,
                          executable="/bin/bash")
    assert proc.stdout.strip() == "components (FMUs):"
    assert proc.stderr == "", proc.stderr


def test_a_terminal_that_is_not_utf8_gets_escapes_not_a_traceback():
    env = {**os.environ, "PYTHONIOENCODING": "ascii", "LC_ALL": "C"}
    proc = subprocess.run([sys.executable, "-m", "sewfmu", "list"], cwd=REPO, env=env,
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert "\\u03c6" in proc.stdout and "Traceback" not in proc.stderr


def test_an_unwritable_output_folder_is_one_line(tmp_path, capsys):
    (tmp_path / "file").write_text("")
    assert main(["run", "punch_drive", "--set", "experiment.revolutions=1",
                 "--out", str(tmp_path / "file" / "out")]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "file" in err and "Traceback" not in err, err
    assert "Error:" not in err, err               # not a raw exception name


def test_a_long_run_shows_its_progress_on_a_terminal(tmp_path):
    master, slave = pty.openpty()
    proc = subprocess.Popen([sys.executable, "-m", "sewfmu", "run", "punch_drive",
                             "--set", "experiment.revolutions=120", "--out", str(tmp_path / "o")],
                            cwd=REPO, stdout=subprocess.DEVNULL, stderr=slave)
    os.close(slave)
    seen = b""
    while True:
        ready, _, _ = select.select([master], [], [], 60)
        if not ready:
            break
        try:
            chunk = os.read(master, 4096)
        except OSError:
            break
        if not chunk:
            break
        seen += chunk
    proc.wait(timeout=60)
    os.close(master)
    text = seen.decode("utf-8", "replace")
    assert proc.returncode == 0, text
    assert "step" in text and "of" in text and "left" in text, text
    assert text.rstrip().endswith("\x1b[K")                   # the line is cleared at the end
