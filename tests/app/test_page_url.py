"""The address `sewfmu app` prints is one a browser opens: an IPv6 address in brackets
(`--host ::1` printed http://::1:P/, which no browser reads as a host and a port), every
address as its loopback. The slow test serves on ::1 and fetches the printed address."""
import os
import signal
import socket
import subprocess
import urllib.parse
import urllib.request

import pytest

pytest.importorskip("dash", reason="the extra app (pip install -e '.[app]') is not installed")

from sewfmu.app.serve import page_url  # noqa: E402
from tests.runs.test_current_folder import SEWFMU  # noqa: E402


@pytest.mark.parametrize("host, url", [
    ("::1", "http://[::1]:8050/"), ("[::1]", "http://[::1]:8050/"),
    ("fe80::1", "http://[fe80::1]:8050/"), ("2001:db8::7", "http://[2001:db8::7]:8050/"),
    ("::ffff:127.0.0.1", "http://[::ffff:127.0.0.1]:8050/"),
    ("fe80::1%eth0", "http://[fe80::1%25eth0]:8050/"), ("::", "http://[::1]:8050/"),
    ("0.0.0.0", "http://127.0.0.1:8050/"), ("", "http://127.0.0.1:8050/"),
    ("127.0.0.1", "http://127.0.0.1:8050/"), ("myhost.lan", "http://myhost.lan:8050/")])
def test_the_printed_address_is_one_a_url_parser_reads_back(host, url):
    printed = page_url(host, 8050)
    assert printed == url
    parsed = urllib.parse.urlsplit(printed)
    assert parsed.port == 8050 and parsed.hostname is not None


def _ipv6_loopback() -> bool:
    try:
        with socket.socket(socket.AF_INET6) as s:
            s.bind(("::1", 0))
        return True
    except OSError:
        return False


@pytest.mark.slow          # a server of its own: about 3 s
@pytest.mark.skipif(not _ipv6_loopback(), reason="no IPv6 loopback on this machine")
@pytest.mark.skipif(not SEWFMU.exists(), reason="no console script sewfmu beside this Python")
@pytest.mark.parametrize("host", ["::1", "[::1]"])
def test_served_on_ipv6_the_printed_address_answers(tmp_path, host):
    with socket.socket(socket.AF_INET6) as s:
        s.bind(("::1", 0))
        port = s.getsockname()[1]
    server = subprocess.Popen([str(SEWFMU), "app", "--host", host, "--port", str(port)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              env={**os.environ, "TMPDIR": str(tmp_path)},
                              start_new_session=True)
    try:
        line = server.stdout.readline()
        assert f"http://[::1]:{port}/" in line, line + server.stderr.read()
        url = line.split()[2]
        with urllib.request.urlopen(url, timeout=60) as answer:
            assert answer.status == 200 and b"<html" in answer.read().lower()
    finally:
        server.send_signal(signal.SIGTERM)
        try:
            assert server.wait(60) == 0
        except subprocess.TimeoutExpired:
            os.killpg(server.pid, signal.SIGKILL)
            raise
