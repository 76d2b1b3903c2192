"""The checks every request to `sewfmu app` passes (sewfmu/app/guard.py; docs/app.md, Security),
on a stand-in WSGI app that counts what reaches it: a Host the server was not started to answer
is refused (DNS rebinding), a request that changes something from another site is refused
(CSRF), a body past the limit is refused before a byte is read (memory), and every answer
carries the headers that keep another site from reading or framing it. Fast: no server, no
Dash. The same through the real page: tests/app/test_page_refusals.py; over real HTTP to a
running server: tests/app/test_server_security.py."""
import io

import pytest
from werkzeug.test import Client, EnvironBuilder, run_wsgi_app

pytest.importorskip("werkzeug", reason="the extra app (pip install -e '.[app]') is not installed")

from sewfmu.app.guard import HEADERS, Guard, allowed_hosts, split_host  # noqa: E402

PORT = 8050
LIMIT = 1000


class Counting:
    """A WSGI app that says which requests reached it, and reads the body it is sent."""

    def __init__(self, extra_headers=()):
        self.calls = []
        self.extra = list(extra_headers)

    def __call__(self, environ, start_response):
        body = environ["wsgi.input"].read(int(environ.get("CONTENT_LENGTH") or 0))
        self.calls.append((environ["REQUEST_METHOD"], environ["PATH_INFO"], len(body)))
        start_response("200 OK", [("Content-Type", "text/plain"), *self.extra])
        return [b"reached"]


def _client(*allow, host="127.0.0.1", app=None):
    app = app or Counting()
    return Client(Guard(app, allowed_hosts(host, PORT, allow), LIMIT)), app


@pytest.mark.parametrize("host", [
    "evil.example", f"evil.example:{PORT}", f"127.0.0.1.evil.example:{PORT}", f"0.0.0.0:{PORT}",
    f"127.0.0.2:{PORT}", f"localhost.:{PORT}", f"127.0.0.1:{PORT + 1}", f"[::2]:{PORT}",
    "", "127.0.0.1:8050/x", "user@127.0.0.1:8050", "127.0.0.1:0", "127.0.0.1:99999",
    "evil.example,127.0.0.1:8050", "[::1"])
def test_a_host_the_server_does_not_answer_to_is_refused_on_every_method(host):
    client, app = _client()
    for method in ("GET", "HEAD", "POST", "OPTIONS"):
        answer = client.open("/", method=method, headers={"Host": host})
        assert answer.status_code == 403, (host, method)
        if method != "HEAD":
            assert answer.data.startswith(b"refused:") and answer.data.count(b"\n") == 1
    assert app.calls == []


@pytest.mark.parametrize("host", [f"127.0.0.1:{PORT}", f"localhost:{PORT}", f"[::1]:{PORT}",
                                  f"LocalHost:{PORT}", "127.0.0.1", "localhost"])
def test_the_loopback_names_on_the_server_s_port_are_answered(host):
    client, app = _client()
    answer = client.get("/x", headers={"Host": host})
    assert answer.status_code == 200 and answer.data == b"reached"
    assert app.calls == [("GET", "/x", 0)]


def test_what_host_and_allow_host_name_is_answered_and_nothing_more():
    client, _ = _client("myhost.lan", "proxy.example:443", host="192.168.1.10")
    for host, code in ((f"192.168.1.10:{PORT}", 200), (f"myhost.lan:{PORT}", 200),
                       ("myhost.lan:9000", 200),        # a name without a port: any port
                       ("proxy.example:443", 200), ("proxy.example", 200),
                       (f"proxy.example:{PORT}", 403), (f"192.168.1.11:{PORT}", 403),
                       (f"otherhost.lan:{PORT}", 403), (f"127.0.0.1:{PORT}", 200)):
        assert client.get("/", headers={"Host": host}).status_code == code, host
    # every address is no name a browser sends: only the loopback names and --allow-host
    client, _ = _client("myhost.lan", host="0.0.0.0")
    assert client.get("/", headers={"Host": f"0.0.0.0:{PORT}"}).status_code == 403
    assert client.get("/", headers={"Host": f"myhost.lan:{PORT}"}).status_code == 200


@pytest.mark.parametrize("text, name, port", [
    ("127.0.0.1:8050", "127.0.0.1", 8050), ("[::1]:8050", "::1", 8050), ("LOCALHOST", "localhost", None),
    ("[fe80::1]", "fe80::1", None), ("my-host.lan:443", "my-host.lan", 443)])
def test_a_host_is_read_as_its_name_and_port(text, name, port):
    assert split_host(text) == (name, port)


@pytest.mark.parametrize("text", ["http://myhost", "myhost/x", "[nothex]:1", "a:b", "", "a b",
                                  "myhost:70000", "*"])
def test_a_host_that_is_not_one_is_refused_by_the_reader(text):
    with pytest.raises(ValueError):
        split_host(text)


ME = {"Host": f"127.0.0.1:{PORT}"}


@pytest.mark.parametrize("method", ["POST", "PUT", "DELETE", "PATCH"])
@pytest.mark.parametrize("header, value", [
    ("Origin", "http://evil.example"), ("Origin", f"http://evil.example:{PORT}"),
    ("Origin", "null"), ("Origin", f"http://127.0.0.1:{PORT + 1}"),   # another app on this machine
    ("Origin", "http://127.0.0.1"), ("Origin", f"file://127.0.0.1:{PORT}"), ("Origin", ""),
    ("Origin", f"http://127.0.0.1:{PORT}@evil.example"), ("Origin", "http://[::1"),
    ("Referer", "http://evil.example/attack.html"),
    ("Referer", f"http://localhost.evil.example:{PORT}/")])
def test_a_change_from_another_site_is_refused_before_it_reaches_the_page(method, header, value):
    client, app = _client()
    answer = client.open("/_dash-update-component", method=method, data=b"{}",
                         headers={**ME, header: value, "Content-Type": "application/json"})
    assert answer.status_code == 403 and b"another site" in answer.data
    assert app.calls == []


def test_origin_is_judged_before_referer_and_a_same_site_change_reaches_the_page():
    client, app = _client()
    same = f"http://127.0.0.1:{PORT}"
    for headers in ({"Origin": same}, {"Origin": f"http://localhost:{PORT}"},
                    {"Origin": f"http://[::1]:{PORT}"}, {"Referer": f"{same}/?scenario=feed"},
                    {"Origin": same, "Referer": "http://evil.example/"},
                    {}):                # no browser sends a POST without Origin: a script's
        assert client.post("/p", data=b"{}", headers={**ME, **headers}).status_code == 200
    assert len(app.calls) == 6
    answer = client.post("/p", data=b"{}", headers={**ME, "Origin": "http://evil.example",
                                                    "Referer": f"{same}/"})
    assert answer.status_code == 403 and len(app.calls) == 6


def test_reading_is_not_changing_a_get_from_another_site_gets_no_cors_grant():
    client, app = _client(app=Counting([("Access-Control-Allow-Origin", "*"),
                                        ("access-control-allow-credentials", "true")]))
    answer = client.get("/runs/0123456789abcdef/summary.json",
                        headers={**ME, "Origin": "http://evil.example"})
    assert answer.status_code == 200
    assert not [k for k in answer.headers.keys() if k.lower().startswith("access-control")]


class Unreadable(io.RawIOBase):
    """A body that must not be read."""

    def readable(self):
        return True

    def readinto(self, _buffer):
        raise AssertionError("the body was read")


def _unread(method, **environ):
    """(status, body) of a request whose body must not be read, the app it did not reach."""
    app = Counting()
    guard = Guard(app, allowed_hosts("127.0.0.1", PORT), LIMIT)
    built = EnvironBuilder(path="/_dash-update-component", method=method, headers=ME)
    body, status, _ = run_wsgi_app(guard, {**built.get_environ(), "wsgi.input": Unreadable(),
                                           **environ})
    return status, b"".join(body), app


@pytest.mark.parametrize("method", ["POST", "GET", "PUT"])
def test_a_body_past_the_limit_is_refused_unread(method):
    status, body, app = _unread(method, CONTENT_LENGTH=str(300 * 2**20))
    assert status.startswith("413") and str(LIMIT).encode() in body
    assert app.calls == []


def test_the_limit_itself_is_read_and_a_byte_more_is_not():
    client, app = _client()
    assert client.post("/", data=b"x" * LIMIT, headers=ME).status_code == 200
    assert app.calls == [("POST", "/", LIMIT)]
    assert client.post("/", data=b"x" * (LIMIT + 1), headers=ME).status_code == 413
    assert len(app.calls) == 1


@pytest.mark.parametrize("length", ["-1", "1e9", "0x10", "99999999999999999999999", "1, 2"])
def test_a_length_that_is_no_number_of_bytes_is_refused(length):
    status, _, app = _unread("POST", CONTENT_LENGTH=length)
    assert status.startswith("400") and app.calls == []


def test_a_body_of_no_stated_length_is_refused_unread():
    status, _, app = _unread("POST", HTTP_TRANSFER_ENCODING="chunked",
                             **{"wsgi.input_terminated": True})
    assert status.startswith("411") and app.calls == []


def test_every_answer_says_it_is_not_another_site_s_to_read_or_frame():
    client, _ = _client()
    for answer in (client.get("/", headers=ME), client.get("/", headers={"Host": "evil"}),
                   client.post("/", headers={**ME, "Origin": "http://evil.example"}),
                   client.post("/", headers={**ME, "Content-Length": "99999999"})):
        for key, value in HEADERS:
            assert answer.headers.get(key) == value, (answer.status, key)
    assert dict(HEADERS)["X-Content-Type-Options"] == "nosniff"
    assert dict(HEADERS)["Cross-Origin-Resource-Policy"] == "same-origin"
