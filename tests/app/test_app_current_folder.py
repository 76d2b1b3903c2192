"""`sewfmu app` started in a folder that holds a numpy.py and a folder named sewfmu: its job
processes (the fork server that preloads sewfmu.app.worker, the run's process) import neither,
and a Run clicked on the page writes its run. Before, the fork server ran the planted numpy.py,
and every Run ended in "module 'sewfmu' has no attribute 'run'" (sewfmu/processes.py). The
sweep's workers: tests/runs/test_current_folder.py."""
import http.client
import json
import os
import signal
import socket
import subprocess
import time

import pytest

from tests.app.page_requests import answered, click
from tests.runs.test_current_folder import SEWFMU, plant

pytest.importorskip("dash", reason="the extra app (pip install -e '.[app]') is not installed")
pytestmark = [pytest.mark.slow,           # a server and a run in its own process: about 5 s
              pytest.mark.skipif(not SEWFMU.exists(),
                                 reason="no console script sewfmu beside this Python")]
WAIT = 120          # s: generous; waited for, never timed


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _request(port: int, path: str, body: bytes | None = None) -> tuple[int, bytes]:
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=WAIT)
    try:
        headers = {"Origin": f"http://127.0.0.1:{port}", "Content-Type": "application/json"}
        connection.request("POST" if body is not None else "GET", path, body, headers)
        answer = connection.getresponse()
        return answer.status, answer.read()
    finally:
        connection.close()


def test_a_run_from_the_page_imports_nothing_from_the_current_folder(tmp_path):
    marker = tmp_path / "imported.txt"
    here = plant(tmp_path / "here", marker)
    port = _free_port()
    server = subprocess.Popen([str(SEWFMU), "app", "--port", str(port)], cwd=here,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              env={**os.environ, "TMPDIR": str(tmp_path)},
                              start_new_session=True)
    try:
        line = server.stdout.readline()
        assert "http://" in line, line + server.stderr.read()
        status, deps = _request(port, "/_dash-dependencies")
        assert status == 200
        body = click(json.loads(deps), "run", {"experiment.revolutions": "1"},
                     {"scenario": "punch_drive", "runs": [], "defaults": {}})
        status, answer = _request(port, "/_dash-update-component", body)
        assert status == 200, answer[:300]
        got = answered(answer)
        job = got.get("job", {}).get("data")
        assert job, got                 # the alert says why the run did not start
        # the run's folder appears whole when the run has written its files, never on a failure
        end = time.monotonic() + WAIT
        while not list(tmp_path.glob(f"sewfmu_app_*/{job}/summary.json")):
            assert time.monotonic() < end, "the run wrote nothing"
            time.sleep(0.2)
    finally:
        server.send_signal(signal.SIGTERM)
        try:
            server.wait(60)
        except subprocess.TimeoutExpired:
            os.killpg(server.pid, signal.SIGKILL)
    assert not marker.exists(), marker.read_text()
    assert "Traceback" not in server.stderr.read()
