"""Every header the page's guard reads (sewfmu/app/guard.py): Host, Origin, Referer,
Content-Length, Transfer-Encoding, whatever their text (non-ASCII digits, signs, blanks, huge
numbers, anything hypothesis draws), is answered by the guard in one line with its security
headers, never by a 500: Content-Length "²" was `"²".isdigit()` true and `int("²")` a
ValueError. And an origin is a site (scheme, name, port): `--allow-host NAME` lets Host name
NAME on any port, but a change (POST) comes only from http://NAME on the server's own port;
http://NAME:3000 is another program on that machine. Fast: no server, no Dash."""
import io

import pytest
from hypothesis import given
from hypothesis import strategies as st
from werkzeug.test import EnvironBuilder, run_wsgi_app

pytest.importorskip("werkzeug", reason="the extra app (pip install -e '.[app]') is not installed")

from sewfmu.app.guard import HEADERS, Guard, allowed_hosts  # noqa: E402
from tests.app.test_guard import Counting  # noqa: E402

PORT = 18660
LIMIT = 1000
ME = f"127.0.0.1:{PORT}"


def _answer(allow=(), host="127.0.0.1", method="POST", **environ):
    """(status, headers, body, calls that reached the app) of one request to a Guard, its WSGI
    environ given as is (the headers as a server would pass them, however odd)."""
    app = Counting()
    guard = Guard(app, allowed_hosts(host, PORT, list(allow)), LIMIT)
    built = EnvironBuilder(path="/_dash-update-component", method=method).get_environ()
    built.update({"HTTP_HOST": ME, "CONTENT_LENGTH": "0", "wsgi.input": io.BytesIO(b"x" * 2000)})
    built.update(environ)
    body, status, headers = run_wsgi_app(guard, built)
    return status, headers, b"".join(body), app.calls


def _one_line_with_headers(status, headers, body):
    assert not status.startswith("5"), (status, body)
    assert body.startswith(b"refused:") and body.count(b"\n") == 1, body
    for key, value in HEADERS:
        assert headers.get(key) == value, key


@pytest.mark.parametrize("length", ["²", "³", "¹", "٣", "٣٢", "+5", "-0", "0x10", "1_000", "1e3",
                                    "5\x85", "\xa05", "5.0", "9" * 19, "1,2", "5 5"])
def test_a_length_that_is_not_ascii_digits_is_400_from_the_guard_itself(length):
    status, headers, body, calls = _answer(CONTENT_LENGTH=length)
    assert status.startswith("400"), (length, status)
    assert body == b"refused: Content-Length is not a number of bytes\n"
    _one_line_with_headers(status, headers, body)
    assert calls == []


@pytest.mark.parametrize("length, code", [(" 5", "200"), ("5\t", "200"), ("0005", "200"),
                                          (str(LIMIT), "200"), (str(LIMIT + 1), "413"),
                                          ("9" * 18, "413")])
def test_a_length_in_ascii_digits_is_read_as_its_number(length, code):
    status, _, _, _ = _answer(method="PUT", CONTENT_LENGTH=length)
    assert status.startswith(code), (length, status)


@pytest.mark.parametrize("host", [f"127.0.0.1:{'²' * 2}", "127.0.0.1:٨٠٥٠", "127.0.0.1:+18660",
                                  "127.0.0.1: 18660", "127.0.0.1:-1", "127.0.0.1:0",
                                  "127.0.0.1:" + "9" * 30, f"{ME}\x85", f"\xa0{ME}",
                                  "ⅼocalhost:18660", "127.0.0.1:18660:1"])
def test_a_host_whose_port_is_not_ascii_digits_is_refused_in_one_line(host):
    status, headers, body, calls = _answer(method="GET", HTTP_HOST=host)
    assert status.startswith("403"), (host, status)
    _one_line_with_headers(status, headers, body)
    assert calls == []


@pytest.mark.parametrize("origin", [f"http://127.0.0.1:{'²'}", "http://127.0.0.1:٨٠٥٠",
                                    f"http://127.0.0.1:+{PORT}", f"http://127.0.0.1: {PORT}",
                                    f"http://127.0.0.1:-{PORT}", "http://127.0.0.1:" + "9" * 30,
                                    f"http://{ME}\x85", f"http://{ME}\t", f" http://{ME}",
                                    f"http://ⅼocalhost:{PORT}", f"http://u:p@{ME}",
                                    f"http://{ME}@evil.example", f"http://[::1]:{PORT}%",
                                    f"http://127.0.0.1:{PORT}:80", "http://", "http:///",
                                    f"HTTP://{ME}", f"ftp://{ME}", f"//{ME}", ME])
def test_an_origin_that_is_not_exactly_the_page_s_is_refused_in_one_line(origin):
    for header in ("HTTP_ORIGIN", "HTTP_REFERER"):
        status, headers, body, calls = _answer(**{header: origin})
        assert status.startswith("403"), (header, origin, status)
        _one_line_with_headers(status, headers, body)
        assert calls == []


@pytest.mark.parametrize("origin", [f"http://{ME}", f"http://localhost:{PORT}",
                                    f"http://[::1]:{PORT}", f"http://LocalHost:{PORT}",
                                    f"http://{ME}/?scenario=feed#x", f"http://{ME}?a=b"])
def test_the_page_s_own_origin_passes(origin):
    header = "HTTP_REFERER" if origin.count("/") > 2 or "?" in origin else "HTTP_ORIGIN"
    assert _answer(**{header: origin})[0].startswith("200"), origin


SERVER = f"http://myhost.lan:{PORT}"


@pytest.mark.parametrize("origin, code", [
    (SERVER, "200"),                              # the page, reached by that name
    ("http://myhost.lan:3000", "403"),            # another program on that machine
    ("http://myhost.lan", "403"), ("https://myhost.lan", "403"),
    (f"https://myhost.lan:{PORT}", "403"),        # this server speaks no TLS: not the page
    ("http://myhost.lan:8443", "403"),
    ("https://proxy.test", "200"), ("http://proxy.test:443", "200"),     # --allow-host NAME:PORT
    ("https://proxy.test:8443", "403"), (f"http://proxy.test:{PORT}", "403")])
def test_allow_host_without_a_port_is_a_site_on_the_server_s_port_only(origin, code):
    status, _, _, _ = _answer(allow=("myhost.lan", "proxy.test:443"),
                              HTTP_HOST=f"myhost.lan:{PORT}", HTTP_ORIGIN=origin)
    assert status.startswith(code), (origin, status)


def test_allow_host_without_a_port_still_answers_its_name_on_any_port():
    """A proxy or a port forward changes the port a browser names in Host: reading is allowed."""
    for host in ("myhost.lan:3000", "myhost.lan", f"myhost.lan:{PORT}"):
        assert _answer(allow=("myhost.lan",), method="GET", HTTP_HOST=host)[0] == "200 OK", host


def test_the_address_served_on_is_a_site_on_its_port_only():
    for origin, code in ((f"http://192.168.1.10:{PORT}", "200"), ("http://192.168.1.10", "403"),
                         ("http://192.168.1.10:3000", "403")):
        status = _answer(host="192.168.1.10", HTTP_HOST=f"192.168.1.10:{PORT}",
                         HTTP_ORIGIN=origin)[0]
        assert status.startswith(code), origin


HEADER_TEXT = st.one_of(st.sampled_from(["²", "³", "٣", "+1", "-1", " 1", "9" * 20, "",
                                         f"{ME}²", f"http://{ME}²"]),
                        st.text(max_size=40),
                        st.text(alphabet="0123456789²³¹٣+-:. \t[]:abcf", max_size=25),
                        st.from_regex(r"https?://[a-z0-9.:\[\]²٣+ -]{0,30}", fullmatch=True))


@pytest.mark.slow
@given(host=HEADER_TEXT, origin=st.none() | HEADER_TEXT, referer=st.none() | HEADER_TEXT,
       length=HEADER_TEXT, encoding=st.none() | HEADER_TEXT,
       method=st.sampled_from(["GET", "POST", "PUT", "HEAD"]))
def test_whatever_the_headers_say_the_guard_answers_them_without_failing(host, origin, referer,
                                                                         length, encoding,
                                                                         method):
    environ = {"HTTP_HOST": host, "CONTENT_LENGTH": length}
    for key, value in (("HTTP_ORIGIN", origin), ("HTTP_REFERER", referer),
                       ("HTTP_TRANSFER_ENCODING", encoding)):
        if value is not None:
            environ[key] = value
    status, headers, body, _ = _answer(method=method, **environ)
    assert status[:3] in ("200", "400", "403", "411", "413"), status
    for key, value in HEADERS:
        assert headers.get(key) == value
    if not status.startswith("200") and method != "HEAD":
        assert body.startswith(b"refused:") and body.count(b"\n") == 1
