"""`sewfmu app` without a browser: the values as the command line checks them, the jobs in their
processes (a run, a cancel, two at once), the files it serves and those it refuses, the command
line's refusals, and what the page asks of the public API (a progress callback, a sweep's
points as they finish, the mechanism's drawing as numbers). The page in a browser:
tests/app/test_app_browser.py."""
import socket
import subprocess
import sys
import time

import numpy as np
import pytest

import sewfmu
from tests.processes import processes_in

pytest.importorskip("dash", reason="the extra app (pip install -e '.[app]') is not installed")

from sewfmu.app import files, values  # noqa: E402
from sewfmu.app.jobs import Jobs  # noqa: E402

SHORT = {"experiment.revolutions": "2"}


def _defaults():
    return {row["name"]: row["value"] for row in values.inputs_of("punch_drive")}


def test_the_inputs_are_every_parameter_and_the_experiment():
    names = [row["name"] for row in values.inputs_of("punch_drive")]
    assert "shaft.omega0" in names and "punch.c2" in names
    assert "experiment.revolutions" in names and "experiment.step" in names
    units = {row["name"]: row["unit"] for row in values.inputs_of("punch_drive")}
    assert units["shaft.omega0"] == "rad/s"


def test_only_changed_values_are_sent_and_each_is_checked_as_set_is():
    defaults = _defaults()
    typed = {**defaults, "shaft.omega0": "955 rpm", "experiment.revolutions": "2"}
    assert values.changed_values("punch_drive", typed, defaults) == \
        {"shaft.omega0": "955 rpm", "experiment.revolutions": "2"}
    with pytest.raises(sewfmu.Error) as bad:
        values.changed_values("punch_drive", {**defaults, "shaft.omega0": "fast"}, defaults)
    assert "\n" not in str(bad.value) and "shaft.omega0" in str(bad.value)
    with pytest.raises(sewfmu.Error, match="punch.c2: give a value"):
        values.changed_values("punch_drive", {**defaults, "punch.c2": " "}, defaults)
    with pytest.raises(sewfmu.Error, match="unknown|no parameter|nowhere|not"):
        values.changed_values("punch_drive", {"shaft.nowhere": "1"}, defaults)


def test_the_command_line_and_the_toml_reproduce_the_values(tmp_path):
    changed = {"shaft.omega0": "955 rpm", "experiment.revolutions": "2", "punch.c2": "6e4"}
    assert values.command_line("punch_drive", {"shaft.omega0": "955 rpm"}) == \
        "sewfmu run punch_drive --set 'shaft.omega0=955 rpm'"
    path = tmp_path / "used.toml"
    path.write_text(values.scenario_toml(sewfmu.show("punch_drive"), changed))
    used, wanted = sewfmu.load(path), sewfmu.load("punch_drive", set={
        k: values.value_of(v) for k, v in changed.items()})
    assert used.revolutions == wanted.revolutions == 2
    assert used.instances["shaft"].parameters == wanted.instances["shaft"].parameters
    assert used.instances["punch"].parameters["c2"] == 6e4


@pytest.mark.parametrize("run_id, name", [
    ("../../etc", "passwd"), ("0123456789abcdef", "../summary.json"),
    ("0123456789abcdef", "/etc/passwd"), ("0123456789abcde/", "results.csv"),
    ("0123456789ABCDEF", "results.csv"), ("0123456789abcdef", "punch_drive.png"),
    (None, "results.csv"), ("0123456789abcdef", None), ("..", "results.csv"),
    ("0123456789abcdef/..", "results.csv")])
def test_a_file_is_served_only_by_run_id_and_a_fixed_name(tmp_path, run_id, name):
    (tmp_path / "0123456789abcdef").mkdir()
    for n in files.FILES + ("punch_drive.png",):
        (tmp_path / "0123456789abcdef" / n).write_text("x")
    assert files.result_file(tmp_path, run_id, name) is None


def test_a_run_s_own_files_are_served(tmp_path):
    (tmp_path / "0123456789abcdef").mkdir()
    (tmp_path / "0123456789abcdef" / "results.csv").write_text("time\n0\n")
    assert files.result_file(tmp_path, "0123456789abcdef", "results.csv") == \
        tmp_path / "0123456789abcdef" / "results.csv"
    assert files.result_file(tmp_path, "0123456789abcdef", "summary.json") is None
    assert files.present(tmp_path, "0123456789abcdef") == ["results.csv"]


def _request(changed):
    return {"source": "punch_drive", "scenario": "punch_drive", "changed": changed,
            "toml": sewfmu.show("punch_drive"), "command": ""}


def _wait(jobs, *ids, timeout=120):
    end = time.monotonic() + timeout
    while any(jobs.get(i).status == "running" for i in ids):
        assert time.monotonic() < end, "a job did not finish"
        time.sleep(0.05)


@pytest.mark.slow
def test_two_runs_at_once_each_give_the_figures_of_their_own_values(tmp_path):
    jobs = Jobs(tmp_path)
    try:
        slow = {**SHORT, "shaft.omega0": "100"}
        fast = {**SHORT, "shaft.omega0": "300 rad/s"}
        a, b = jobs.start("run", _request(slow)), jobs.start("run", _request(fast))
        assert a != b
        _wait(jobs, a, b)
        for job_id, changed in ((a, slow), (b, fast)):
            job = jobs.get(job_id)
            assert job.status == "done", job.error
            got = job.result["variants"][0]["figures"]
            want = sewfmu.run("punch_drive", set={k: values.value_of(v)
                                                  for k, v in changed.items()}).figures
            for key in ("F2_peak", "F2_weld_mean", "contact_onset_deg"):
                assert got[key] == pytest.approx(want[key], rel=1e-12), key
            assert sorted(files.present(tmp_path, job_id)) == \
                ["command.txt", "results.csv", "scenario.toml", "summary.json"]
            assert job.fraction == 1.0
            drawing = job.result["variants"][0]["mechanism"]
            assert drawing["tracked"] == "tip" and len(drawing["crank_deg"]) == 36
    finally:
        jobs.shutdown()


def test_cancel_ends_the_run_s_process_and_writes_nothing(tmp_path):
    jobs = Jobs(tmp_path)
    try:
        job_id = jobs.start("run", _request({"experiment.revolutions": "400"}))
        end = time.monotonic() + 60
        while jobs.get(job_id).done == 0:
            assert time.monotonic() < end
            time.sleep(0.05)
        assert jobs.cancel(job_id)
        job = jobs.get(job_id)
        assert job.ended.wait(10) and job.status == "cancelled"
        assert not job.process.is_alive()
        assert files.present(tmp_path, job_id) == []
        assert not jobs.cancel("not-a-job")
    finally:
        jobs.shutdown()


@pytest.mark.slow
def test_no_more_jobs_than_the_app_runs_at_once(tmp_path, capfd):
    """A script posting Run in a loop must not start a process each time: beyond MAX_RUNNING
    running jobs, one line; a cancelled job frees its place, and ends without a traceback."""
    from sewfmu.app.jobs import MAX_RUNNING, Busy

    jobs = Jobs(tmp_path)
    try:
        started = [jobs.start("run", _request({"experiment.revolutions": "400"}))
                   for _ in range(MAX_RUNNING)]
        with pytest.raises(Busy, match="the most this app runs at once"):
            jobs.start("run", _request(SHORT))
        end = time.monotonic() + 60
        while jobs.get(started[0]).done == 0:          # running, not just starting
            assert time.monotonic() < end
            time.sleep(0.05)
        jobs.cancel(started[0])
        assert jobs.get(started[0]).ended.wait(10)
        assert jobs.start("run", _request(SHORT))       # its place is free again
    finally:
        jobs.shutdown()
    assert "Traceback" not in capfd.readouterr().err


def test_a_failing_run_is_its_one_line(tmp_path):
    jobs = Jobs(tmp_path)
    try:
        job_id = jobs.start("run", _request({**SHORT, "shaft.omega0": "-5"}))
        _wait(jobs, job_id)
        job = jobs.get(job_id)
        assert job.status == "error" and "omega0" in job.error and "\n" not in job.error
    finally:
        jobs.shutdown()


def test_run_tells_its_progress_to_a_function():
    heard = []
    sewfmu.run("punch_drive", set={"experiment.revolutions": 10},
               progress=lambda done, total: heard.append((done, total)))
    assert heard and all(0 <= done <= total for done, total in heard)
    assert all(b >= a for (a, _), (b, _) in zip(heard, heard[1:]))
    assert heard[-1][0] == heard[-1][1]              # the end is reported too


def test_sweep_tells_each_point_as_it_finishes():
    heard = []
    s = sewfmu.sweep("punch_drive", grid={"shaft.omega0": [100.0, 200.0]},
                     set={"experiment.revolutions": 1}, workers=2, on_point=heard.append)
    assert sorted(r["shaft.omega0"] for r in heard) == [100.0, 200.0]
    assert {r["key"] for r in heard} == {r["key"] for r in s.rows}


@pytest.mark.parametrize("name, tracked, columns", [
    ("punch_drive", "tip", None), ("feed", "M", ("feed.M_x", "feed.M_y")),
    ("takeup", "E", ("takeup.E_z", "takeup.E_x"))])
def test_the_mechanism_s_drawing_holds_the_recorded_point(name, tracked, columns):
    run = sewfmu.run(name, set={"experiment.revolutions": 2})
    drawing = run.mechanism(frames=12)
    assert drawing["tracked"] == tracked and len(drawing["crank_deg"]) == 12
    assert all(0 <= a < 360 for a in drawing["crank_deg"])
    assert all(n in drawing["points"] for chain in drawing["chains"] for n in chain)
    i = drawing["samples"]
    if columns:
        x, y = (run.series[c][i] * 1e3 for c in columns)
    else:       # the tip over the fabric by the recorded height y
        surface = np.array([p[1] for p in drawing["points"]["fabric_left"]])
        x, y = run.series["punch.y"][i] * 0, surface + run.series["punch.y"][i] * 1e3
        x = x + drawing["points"]["tip"][0][0]
    got = np.array(drawing["points"][tracked])
    assert np.allclose(got[:, 0], x) and np.allclose(got[:, 1], y)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _sewfmu(*args, code=None, timeout=60):
    lead = code or "import sys; from sewfmu.cli import main; sys.exit(main(sys.argv[1:]))"
    return subprocess.run([sys.executable, "-c", lead, *args], capture_output=True, text=True,
                          timeout=timeout)


@pytest.mark.parametrize("port", ["0", "65536", "http", "-1"])
def test_a_bad_port_is_one_line(port):
    done = _sewfmu("app", "--port", port)
    assert done.returncode == 1 and "--port" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


@pytest.mark.slow
def test_a_port_in_use_is_one_line_and_exit_1():
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        done = _sewfmu("app", "--port", str(taken.getsockname()[1]))
    assert done.returncode == 1, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and "--port" in done.stderr
    assert "http://" not in done.stdout


def test_without_the_extra_the_command_says_how_to_install_it():
    code = ("import sys; sys.modules['dash'] = None; from sewfmu.cli import main; "
            "sys.exit(main(sys.argv[1:]))")
    done = _sewfmu("app", "--port", str(_free_port()), code=code)
    assert done.returncode == 1
    line = done.stderr.strip()
    assert len(line.splitlines()) == 1 and "pip install" in line and "[app]" in line


@pytest.mark.slow
def test_a_scenario_file_that_cannot_load_is_one_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("this is not toml [")
    done = _sewfmu("app", str(bad), "--port", str(_free_port()))
    assert done.returncode == 1 and len(done.stderr.strip().splitlines()) == 1


def test_sewfmu_app_is_callable_as_the_package_and_as_the_name():
    import sewfmu.app as package

    assert callable(sewfmu.app) and callable(package)
    with pytest.raises(sewfmu.Error, match="port"):
        sewfmu.app(port=70000)
    with pytest.raises(sewfmu.Error, match="port"):
        package(port="8050")


@pytest.mark.slow
def test_another_host_is_warned_of_and_sigterm_ends_the_server_with_0(tmp_path):
    import os
    import signal

    server = subprocess.Popen([sys.executable, "-m", "sewfmu", "app", "--host", "127.0.0.2",
                               "--port", str(_free_port())], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True,
                              env={**os.environ, "TMPDIR": str(tmp_path)})
    try:
        line = server.stdout.readline()
        assert line.startswith("sewfmu app: http://127.0.0.2:"), line
        assert list(tmp_path.glob("sewfmu_app_*"))
    finally:
        server.send_signal(signal.SIGTERM)
        code = server.wait(60)
    warning = server.stderr.read().strip().splitlines()
    assert code == 0 and len(warning) == 1 and "anyone who reaches" in warning[0]
    assert not list(tmp_path.glob("sewfmu_app_*"))


@pytest.mark.slow
def test_report_html_is_made_into_the_run_s_folder_when_asked_for(tmp_path):
    jobs = Jobs(tmp_path)
    try:
        run = jobs.start("run", _request(SHORT))
        _wait(jobs, run)
        assert "report.html" not in files.present(tmp_path, run)
        report = jobs.start("report", jobs.get(run).request, folder=run)
        _wait(jobs, report, timeout=300)
        assert jobs.get(report).status == "done", jobs.get(report).error
        assert "report.html" in files.present(tmp_path, run)
        assert sorted(p.name for p in tmp_path.iterdir()) == [run]      # nothing else left
    finally:
        jobs.shutdown()


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads Linux's /proc")
def test_cancel_of_a_sweep_ends_its_workers_too(tmp_path):
    jobs = Jobs(tmp_path)
    try:
        grid = {"shaft.omega0": [100.0, 150.0, 200.0, 250.0]}
        job_id = jobs.start("sweep", {**_request({"experiment.revolutions": "300"}),
                                      "grid": grid, "workers": 2, "points": [0] * 4})
        job = jobs.get(job_id)
        end = time.monotonic() + 60
        while len(processes_in("group", job.process.pid)) < 3:    # the job, its fork server, a worker
            assert time.monotonic() < end and job.status == "running", job.error
            time.sleep(0.1)
        assert jobs.cancel(job_id) and job.status == "cancelled"
        end = time.monotonic() + 30
        while processes_in("group", job.process.pid) and time.monotonic() < end:
            time.sleep(0.1)
        assert processes_in("group", job.process.pid) == []
    finally:
        jobs.shutdown()


def test_a_value_outside_its_declared_range_starts_nothing(tmp_path):
    """Refused when Run is clicked, with the range the FMU declares, as a run would refuse it:
    not a job that starts and then fails."""
    from sewfmu.app.serve import Page

    page = Page({"punch_drive": "punch_drive"}, tmp_path)
    try:
        defaults = _defaults()
        for name, text in (("punch.c2", "-5"), ("shaft.omega0", "1e6 rpm")):
            with pytest.raises(sewfmu.ScenarioError, match="outside the range") as bad:
                page.check("punch_drive", {**defaults, name: text}, defaults)
            assert name in str(bad.value) and "\n" not in str(bad.value)
        assert page.jobs._jobs == {}
    finally:
        page.jobs.shutdown()


def test_dash_s_script_route_answers_a_path_that_is_not_one_with_404(tmp_path):
    """Dash raises on a traversal or an unknown package under its script route; Flask would
    answer 500 with a traceback on the terminal."""
    from sewfmu.app.serve import Page, create

    page = Page({"punch_drive": "punch_drive"}, tmp_path)
    try:
        client = create(page).server.test_client()
        for path in ("/_dash-component-suites/dash/..%2f..%2f..%2fetc%2fpasswd",
                     "/_dash-component-suites/dash/deps/..%2f..%2fsetup.py",
                     "/_dash-component-suites/nothing/x.js",
                     "/assets/..%2f..%2fetc%2fpasswd"):
            answer = client.get(path)
            assert answer.status_code == 404, path
            assert b"root:" not in answer.data
    finally:
        page.jobs.shutdown()


def test_a_run_goes_to_the_process_made_ready_for_it_and_gives_the_api_s_figures(tmp_path):
    """The spare process (warmed on the scenario) takes the first run; the next spare is made
    when that run ends; the figures are sewfmu.run's; shutdown ends the spare too."""
    jobs = Jobs(tmp_path, warm="punch_drive")
    try:
        end = time.monotonic() + 60
        while jobs._spare is None:
            assert time.monotonic() < end
            time.sleep(0.02)
        spare = jobs._spare[0]
        first = jobs.start("run", _request({**SHORT, "shaft.omega0": "955 rpm"}))
        assert jobs.get(first).process is spare
        _wait(jobs, first)
        job = jobs.get(first)
        assert job.status == "done", job.error
        want = sewfmu.run("punch_drive", set={**SHORT, "shaft.omega0": "955 rpm"}).figures
        got = job.result["variants"][0]["figures"]
        for key in ("F2_peak", "F2_weld_mean", "contact_onset_deg"):
            assert got[key] == pytest.approx(want[key], rel=1e-12), key
        assert job.ended.wait(10)
        while jobs._spare is None:
            assert time.monotonic() < end
            time.sleep(0.02)
        second = jobs._spare[0]
        assert second is not spare and second.is_alive()
    finally:
        jobs.shutdown()
    second.join(10)
    assert not second.is_alive()


def test_the_spare_s_warm_up_of_a_study_or_a_bad_file_is_left_to_the_job(tmp_path):
    """A scenario that cannot be warmed (a study; a file broken after the app started) leaves the
    spare cold, and the job then says what is wrong in its one line."""
    broken = tmp_path / "mine.toml"
    broken.write_text(sewfmu.show("punch_drive"))
    jobs = Jobs(tmp_path / "runs", warm=str(broken))
    try:
        broken.write_text("[experiment\n")
        job_id = jobs.start("run", {**_request({}), "source": str(broken), "toml": None})
        _wait(jobs, job_id)
        job = jobs.get(job_id)
        assert job.status == "error" and "mine.toml" in job.error and "\n" not in job.error
        assert values.short_run("takeup_tolerance") is None
    finally:
        jobs.shutdown()


@pytest.mark.slow
def test_a_study_on_the_page_gives_its_figures_and_study_json(tmp_path):
    """The catalogue's studies are on the page too: computed (no series, no drawing), their key
    figures those of sewfmu.run with the same value, study.json served beside summary.json."""
    jobs = Jobs(tmp_path)
    try:
        request = {**_request({"takeup.L_AB": "10.5 mm"}), "source": "takeup_tolerance",
                   "scenario": "takeup_tolerance", "toml": sewfmu.show("takeup_tolerance")}
        job_id = jobs.start("run", request)
        _wait(jobs, job_id)
        job = jobs.get(job_id)
        assert job.status == "done", job.error
        variant = job.result["variants"][0]
        want = sewfmu.run("takeup_tolerance", set={"takeup.L_AB": "10.5 mm"})
        assert variant["figures"]["nominal_stroke_mm"] == \
            pytest.approx(want.figures["nominal_stroke_mm"], rel=1e-12)
        assert variant["series"] == {} and variant["mechanism"] is None
        assert sorted(files.present(tmp_path, job_id)) == \
            ["command.txt", "scenario.toml", "study.json", "summary.json"]
    finally:
        jobs.shutdown()


def test_under_runs_only_a_run_s_file_is_answered_the_rest_is_404(tmp_path):
    """Dash answers any other path with the page itself; under /runs/ that read as a file."""
    from sewfmu.app.serve import Page, create

    page = Page({"punch_drive": "punch_drive"}, tmp_path)
    try:
        client = create(page).server.test_client()
        for path in ("/runs/", "/runs/0123456789abcdef/", "/runs/0123456789abcdef/results.csv/",
                     "/runs/../../etc/passwd", "/runs/a/b/c"):
            assert client.get(path).status_code == 404, path
        assert client.get("/").status_code == 200
    finally:
        page.jobs.shutdown()


def test_a_number_typed_as_the_scenario_has_it_is_no_change():
    defaults = _defaults()
    typed = {**defaults, "shaft.omega0": "100.0", "experiment.revolutions": "10.0"}
    assert defaults["shaft.omega0"] == "100"
    assert values.changed_values("punch_drive", typed, defaults) == {}
