"""What every request to the page passes before Flask or Dash sees it (docs/app.md, Security):

- its Host must be one the server was started to answer (loopback names, what --host names,
  --allow-host): a page elsewhere that rebinds its own name to 127.0.0.1 sends its own name;
- a request that can change something (any method but GET, HEAD, OPTIONS) must come from the
  page itself: its Origin, or its Referer where a client sends no Origin, names an allowed host
  (a page on another site that posts a Run sends its own; a client that sends neither is no
  browser, which always sends Origin with a POST, and could as well send any header it likes);
- its body is at most `max_body` bytes: a longer Content-Length is refused before a byte is
  read, and so is a body of no stated length (chunked), or a length that is not ASCII digits;
- a body the app names a check for (Dash's callback route: callback_body.py) is read and
  checked before the app reads it, and refused 400 in one line if it is not what that route
  takes;
- every answer says how a browser may use it: not as another site's resource, nor in a frame.

A WSGI middleware, so that it holds for every route: the page, its assets, Dash's routes, the
files of runs, and the 404s."""
from __future__ import annotations

import io
import ipaddress
import re
import socket
from dataclasses import dataclass, field

import sewfmu

LOOPBACK = ("127.0.0.1", "localhost", "::1")
EVERY_ADDRESS = ("0.0.0.0", "::", "")        # --host values that are no name a browser sends
SAFE_METHODS = ("GET", "HEAD", "OPTIONS")    # nothing of the page's changes on these
MAX_BODY_MB = 4.0     # a callback's request is a few kB; a sweep's 400 points about 100 kB
# on every answer: no sniffing a file into a script, no reading it as another site's resource
# (a <script> or <img> there), no showing the page in another site's frame (a click taken there)
HEADERS = [("X-Content-Type-Options", "nosniff"),
           ("Cross-Origin-Resource-Policy", "same-origin"),
           ("X-Frame-Options", "DENY"),
           ("Content-Security-Policy", "frame-ancestors 'none'"),
           ("Referrer-Policy", "same-origin")]
# ASCII only ([0-9], not \d nor str.isdigit: "²".isdigit() is True and int("²") raises)
_HOST = re.compile(r"(\[[0-9a-fA-F:.]+\]|[A-Za-z0-9._-]+)(?::([0-9]{1,5}))?")
# an Origin (scheme://host[:port]) or a Referer (the same, then its path): no user, no spaces
_ORIGIN = re.compile(r"(https?)://([^/?#@\s]+)([/?#].*)?", re.DOTALL)
_LENGTH = re.compile(r"[0-9]{1,18}")
_OWS = " \t"          # the only blanks HTTP allows around a header's value


@dataclass(frozen=True)
class Allowed:
    """The hosts a request may name: `names` on the server's `port` (None: on any, as for a
    test client), `anywhere` on any port (--allow-host NAME, e.g. a proxy's), `exact` (name,
    port) pairs (--allow-host NAME:PORT). A Host header without a port (the client's default
    port: a port-forward or a proxy may have changed it) passes on its name alone.

    An origin is a site: its scheme, name and port (80 or 443 where it names none) all count.
    `names` and `anywhere` are origins only as http on the server's own port (another port of
    the same name is another program, another site); an `exact` pair on its port, http or
    https (a proxy's)."""
    names: frozenset
    port: int | None = None
    anywhere: frozenset = field(default_factory=frozenset)
    exact: frozenset = field(default_factory=frozenset)

    def admits(self, name: str, port: int | None) -> bool:
        if port is None:
            return name in self.names or name in self.anywhere or \
                any(name == n for n, _ in self.exact)
        return (name in self.names and (self.port is None or port == self.port)) or \
            name in self.anywhere or (name, port) in self.exact

    def admits_origin(self, url: str) -> bool:
        """An Origin or Referer that is this server's own site, or an --allow-host NAME:PORT
        (see the class): ASCII as browsers send it, scheme http or https."""
        found = _ORIGIN.fullmatch(url) if url.isascii() else None
        if found is None:
            return False
        scheme = found.group(1)
        try:
            name, port = split_host(found.group(2), blanks="")
        except ValueError:
            return False
        port = port if port is not None else {"http": 80, "https": 443}[scheme]
        if (name, port) in self.exact:
            return True
        return scheme == "http" and (name in self.names or name in self.anywhere) and \
            (self.port is None or port == self.port)


def allowed_hosts(host: str, port: int | None, allow: list[str] | tuple = ()) -> Allowed:
    """The hosts a server started on `host`:`port` answers: the loopback names, `host` itself
    (unless it is every address), and each of `allow` (NAME or NAME:PORT, checked by
    check_hosts)."""
    names = set(LOOPBACK)
    if host not in EVERY_ADDRESS:
        names.add(_bare(host.lower()))
    anywhere, exact = set(), set()
    for item in allow:
        name, given = split_host(item)
        if given is None:
            anywhere.add(name)
        else:
            exact.add((name, given))
    return Allowed(frozenset(names), port, frozenset(anywhere), frozenset(exact))


def check_hosts(host, names) -> list[str]:
    """--allow-host's names, each a host name or address, with a port or without; at least one
    where `host` is every address (0.0.0.0), which is no name a browser sends."""
    if not isinstance(host, str):
        raise sewfmu.ScenarioError(f"--host: expected an address or a host name, got {host!r}")
    if isinstance(names, str):
        names = [names]
    if names is not None and not isinstance(names, (list, tuple)):
        raise sewfmu.ScenarioError(f"allow_hosts: expected a list of host names, got {names!r}")
    if host in EVERY_ADDRESS and not names:
        raise sewfmu.ScenarioError(
            f"--host {host or repr('')} serves on every address of this machine: name those a "
            f"browser will use with --allow-host NAME (this machine: {own_names()})")
    checked = []
    for name in names or ():
        try:
            split_host(name)
        except (ValueError, TypeError, AttributeError):
            raise sewfmu.ScenarioError(
                f"--allow-host: expected a host name or address like myhost.lan, 192.168.1.10 "
                f"or [fe80::1], with :PORT or without, got {name!r}") from None
        checked.append(name)
    return checked


def is_loopback(host: str) -> bool:
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(_bare(host)).is_loopback
    except ValueError:
        return False


def split_host(text: str, blanks: str = _OWS) -> tuple[str, int | None]:
    """A Host header (or --allow-host) as (name, port or None): the name lowercase, an IPv6
    address without its brackets. ValueError for anything else (a path, a scheme, a port that
    is not 1 to 65535 in ASCII digits). `blanks`: what may stand around it."""
    found = _HOST.fullmatch(text.strip(blanks))
    if not found or (found.group(2) is not None and not 1 <= int(found.group(2)) <= 65535):
        raise ValueError(text)
    name = found.group(1).lower()
    if name.startswith("["):
        ipaddress.IPv6Address(name[1:-1])        # ValueError if it is not an address
    return _bare(name), int(found.group(2)) if found.group(2) else None


def own_names() -> str:
    """This machine's name and addresses, as a refusal suggests them for --allow-host."""
    name = socket.gethostname()
    try:
        found = {i[4][0] for i in socket.getaddrinfo(name, None, proto=socket.IPPROTO_TCP)}
    except OSError:                       # a name that does not resolve: the name alone
        found = set()
    return ", ".join([name, *sorted(a for a in found if not is_loopback(a))])


def _bare(name: str) -> str:
    return name[1:-1] if name.startswith("[") and name.endswith("]") else name


class Guard:
    """The WSGI app `app` behind the checks above. `bodies`: path -> check(body, content
    type) of a POST's body to that path, giving the line that refuses it or None."""

    def __init__(self, app, allowed: Allowed, max_body: int, bodies: dict | None = None):
        self.app = app
        self.allowed = allowed
        self.max_body = max_body
        self.bodies = dict(bodies or {})

    def __call__(self, environ, start_response):
        # the server's hook (serve._Quiet): the client's input is read no further after the
        # answer, but for a moment and a bounded amount, where werkzeug reads on to 10 GB
        stop = environ.get("sewfmu.stop_reading", _nothing)
        refused = self.refusal(environ) or self.body_refusal(environ)
        if refused is not None:
            stop()
            status, line = refused
            body = (line + "\n").encode()
            start_response(status, [("Content-Type", "text/plain; charset=utf-8"),
                                    ("Content-Length", str(len(body))), *HEADERS])
            return [body]

        def start(status, headers, exc_info=None):
            # no header that would let another site read an answer (CORS), ours added
            kept = [(k, v) for k, v in headers if not k.lower().startswith("access-control-")
                    and k.lower() not in {h.lower() for h, _ in HEADERS}]
            return start_response(status, kept + HEADERS, exc_info)
        return _then(self.app(environ, start), stop)

    def refusal(self, environ) -> tuple[str, str] | None:
        """(status, one line) for a request refused, or None."""
        try:
            name, port = split_host(environ.get("HTTP_HOST", ""))
        except ValueError:
            return "403 Forbidden", "refused: no Host header this server answers"
        if not self.allowed.admits(name, port):
            return "403 Forbidden", (f"refused: this server does not answer to the host "
                                     f"{environ['HTTP_HOST'][:80]!r}; start it with "
                                     f"--allow-host NAME[:PORT] to name another")
        if environ.get("REQUEST_METHOD", "GET").upper() not in SAFE_METHODS:
            origin = environ.get("HTTP_ORIGIN")
            which = "Origin" if origin is not None else "Referer"
            came = origin if origin is not None else environ.get("HTTP_REFERER")
            if came is not None and not self.allowed.admits_origin(came):
                return "403 Forbidden", (f"refused: a request from another site ({which} "
                                         f"{came[:80]!r}) may not change anything here")
        if "chunked" in environ.get("HTTP_TRANSFER_ENCODING", "").lower():
            # a body of no stated length: neither the page nor Dash sends one, and the server's
            # reading of it (werkzeug's) reads a chunk's size line without a bound
            return "411 Length Required", ("refused: a body without Content-Length "
                                           "(chunked); send it with its length")
        length = environ.get("CONTENT_LENGTH", "").strip(_OWS)
        if length:
            if not _LENGTH.fullmatch(length):      # "²", "+1", "1e9", 19 digits and more
                return "400 Bad Request", "refused: Content-Length is not a number of bytes"
            if int(length) > self.max_body:
                return "413 Request Entity Too Large", (
                    f"refused: a body of {int(length)} bytes; this server reads at most "
                    f"{self.max_body} (sewfmu app --max-request-mb)")
        return None

    def body_refusal(self, environ) -> tuple[str, str] | None:
        """(400, one line) for a POST whose body its path's check refuses, or None; the body
        read (refusal() has bounded its length) and put back for the app."""
        check = self.bodies.get(environ.get("PATH_INFO", ""))
        if check is None or environ.get("REQUEST_METHOD", "GET").upper() != "POST":
            return None
        length = int(environ.get("CONTENT_LENGTH", "").strip(_OWS) or 0)
        data = environ["wsgi.input"].read(length) if length else b""
        environ["wsgi.input"] = io.BytesIO(data)
        environ["CONTENT_LENGTH"] = str(len(data))
        line = check(data, environ.get("CONTENT_TYPE", ""))
        return None if line is None else ("400 Bad Request", line)


def _then(answer, stop):
    """The app's answer, then `stop` (before the server would drain the client's input)."""
    try:
        yield from answer
    finally:
        close = getattr(answer, "close", None)
        if close is not None:
            close()
        stop()


def _nothing() -> None:
    pass
