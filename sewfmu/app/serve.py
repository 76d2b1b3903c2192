"""The app's server: the page (Dash, on Flask), its own assets, and the files of its own runs by
run id and fixed name; it serves until Ctrl-C or SIGTERM, then ends every job's process and
removes the one temporary folder all runs were written under."""
from __future__ import annotations

import html
import io
import shutil
import signal
import socket
import sys
import tempfile
import threading
import time
import webbrowser
from functools import partial
from pathlib import Path

import dash
from dash.exceptions import DependencyException
from flask import abort, send_file
from werkzeug.serving import WSGIRequestHandler, make_server

import sewfmu
from sewfmu.app.callback_body import ROUTE
from sewfmu.app.callback_body import refusal as callback_refusal
from sewfmu.app.callbacks import failed, register, values_of_choice
from sewfmu.app.files import result_file
from sewfmu.app.guard import MAX_BODY_MB, Allowed, Guard, allowed_hosts, check_hosts, is_loopback
from sewfmu.app.jobs import Jobs
from sewfmu.app.layout import page as page_layout
from sewfmu.app.values import changed_values, check_points, command_line, short_run

ASSETS = Path(__file__).resolve().parent / "assets"


class Page:
    """What every tab's callbacks share: the scenarios on offer, the jobs, the results folder."""

    def __init__(self, choices: dict[str, str], root: Path, scheduler: str | None = None,
                 workers: int | None = None):
        self.choices = choices                # label on the page -> catalogue name or path
        self.root = root
        # one check at a time in this process: two at once (the warm-up and a first click, two
        # tabs) extract the same FMU into the cache under the same process's scratch name
        self._checking = threading.Lock()
        first = next(iter(choices.values()), None)      # the scenario the page shows first
        # the first run's process made ready now; a sweep's points checked before it starts
        self.jobs = Jobs(root, warm=first, check=self.check_job)
        if first is not None:         # the first check of a value (FMUs' descriptions, units)
            threading.Thread(target=_warm_checks, args=(first, self._checking),
                             daemon=True).start()
        self.scheduler = scheduler
        self.workers = workers
        self._lock = threading.Lock()

    def check(self, label, typed: dict, defaults) -> dict:
        if not isinstance(label, str) or label not in self.choices:
            raise sewfmu.ScenarioError(f"unknown scenario {label!r:.80}")
        with self._checking:
            return changed_values(self.choices[label], typed,
                                  defaults if isinstance(defaults, dict) else {})

    def check_job(self, kind: str, request: dict) -> None:
        """Before a job's process starts: a sweep's every point, as Run checks its values (a
        sweep's bad point would otherwise start a process that ends in its error)."""
        if kind == "sweep":
            with self._checking:
                check_points(request["source"], request["changed"], request["grid"])

    def request(self, label: str, changed: dict) -> dict:
        source = self.choices[label]
        toml = None
        if not source.lower().endswith(".ssp"):
            try:
                toml = Path(source).read_text(encoding="utf-8-sig") \
                    if source.lower().endswith(".toml") else sewfmu.show(source)
            except (OSError, UnicodeDecodeError) as err:    # moved or changed since the start
                raise sewfmu.ScenarioError(f"{source}: cannot be read now ({err})") from None
        return {"source": source, "scenario": label, "changed": changed, "toml": toml,
                "command": command_line(label, changed)}

    def entries(self, job, runs: list) -> list[dict]:
        """The rows a finished run adds to its tab's table: one per variant ([compare])."""
        number = 1 + len({r["id"] for r in runs})
        out = []
        for k, variant in enumerate(job.result["variants"]):
            label = f"#{number}" + (f" {variant['label']}" if variant["label"] else "")
            out.append({"id": job.id, "key": f"{job.id}:{k}", "variant": k, "label": label,
                        "scenario": job.request["scenario"], "changed": job.request["changed"],
                        "figures": variant["figures"], "units": variant["units"],
                        "command": job.request["command"], "files": []})
        return out

    def report(self, job) -> str:
        """A page that waits for report.html, which is made (once) when first asked for."""
        with self._lock:
            maker = self.jobs.get(job.report)
            if maker is None or maker.status in ("error", "cancelled"):
                if maker is not None and maker.status == "error":
                    return f"<p>report.html could not be made: {html.escape(maker.error)}</p>"
                job.report = self.jobs.start("report", job.request, folder=job.id)
        return ("<meta http-equiv='refresh' content='2'><p>report.html is being made (the run "
                "again, with its plots and animation); this page reloads until it is there</p>")

    def variant(self, entry: dict) -> dict:
        job = self.jobs.get(entry.get("id"))
        if job is None or job.result is None:
            return {"series": {}, "units": {}, "figures": {}, "mechanism": None}
        return job.result["variants"][entry["variant"]]


def _warm_checks(source: str, checking: threading.Lock) -> None:
    """A value checked once, as a click on Run checks the user's: the first click then answers
    at once (reading the FMUs' descriptions and building the unit registry take about a second)."""
    try:
        short = short_run(source)
        if short is not None:
            with checking:
                sewfmu.check(source, set=short)
    except Exception:           # a scenario that cannot be checked so: its first click says why
        pass


def create(page: Page, allowed: Allowed | None = None, max_body_mb: float = MAX_BODY_MB) \
        -> dash.Dash:
    """The page, every request to it through the Guard (guard.py): `allowed` the hosts it
    answers (default: the loopback names, on any port), bodies of at most `max_body_mb` MiB."""
    app = dash.Dash("sewfmu", title="sewfmu", assets_folder=str(ASSETS), update_title=None,
                    serve_locally=True, on_error=failed)
    max_body = int(max_body_mb * 2**20)
    # Flask's own limit too, for any body the Guard has let through (it checks the same length)
    app.server.config["MAX_CONTENT_LENGTH"] = max_body
    # a callback's body checked against the page's callbacks (callback_body.py) before Dash
    # reads it: Dash answers a malformed one 500, its traceback on the terminal
    app.server.wsgi_app = Guard(app.server.wsgi_app, allowed or allowed_hosts("127.0.0.1", None),
                                max_body, {ROUTE: partial(_callback_refusal, app)})
    first = next(iter(page.choices), None)
    app.layout = page_layout(list(page.choices), values_of_choice(page, first))
    register(app, page)

    @app.server.errorhandler(DependencyException)
    def not_a_dependency(_error):
        # Dash's route for its own scripts, asked for a path that is not one (a traversal, an
        # unknown package): Dash raises, which Flask would answer 500 with a traceback
        return "not found", 404

    @app.server.route("/runs/")
    @app.server.route("/runs/<path:_anything>")
    def not_a_file(_anything=""):
        # under /runs/ only a run's file by its id and name (below); Dash would answer the rest
        # with the page itself
        abort(404)

    @app.server.route("/runs/<run_id>/<name>")
    def result(run_id, name):
        path = result_file(page.root, run_id, name)
        if path is None:
            job = page.jobs.get(run_id)
            if name != "report.html" or job is None or job.kind != "run" or \
                    job.status != "done":
                abort(404)
            return page.report(job)
        return send_file(path, mimetype=_MIME.get(path.suffix, "text/plain"),
                         as_attachment=name != "report.html", download_name=name)
    return app


def _callback_refusal(app: dash.Dash, data: bytes, content_type: str) -> str | None:
    return callback_refusal(data, content_type, app.callback_map)


_MIME = {".csv": "text/csv", ".json": "application/json", ".html": "text/html",
         ".toml": "text/plain", ".txt": "text/plain"}


def choices_of(named: list[str]) -> dict[str, str]:
    """The scenarios on offer: the files named (each checked now), then the catalogue, the
    default scenario (punch_drive, as `sewfmu run`'s README example) first."""
    chosen = {}
    for item in named:
        sewfmu.load(item)                      # a bad file is one line now, not on the page
        chosen[item] = item
    for name in sorted(sewfmu.catalogue(), key=lambda n: n != "punch_drive"):
        chosen.setdefault(name, name)
    return chosen


def serve(scenarios=(), port: int = 8050, host: str = "127.0.0.1", open_browser: bool = False,
          scheduler: str | None = None, workers: int | None = None, ready=None,
          allow_hosts=(), max_request_mb: float = MAX_BODY_MB) -> None:
    """Serve the page until SIGINT or SIGTERM."""
    allowed = allowed_hosts(host, port, check_hosts(host, allow_hosts))
    host = host[1:-1] if host.startswith("[") and host.endswith("]") else host   # [::1]: ::1
    choices = choices_of(list(scenarios))
    root = Path(tempfile.mkdtemp(prefix="sewfmu_app_"))
    page = Page(choices, root, scheduler, workers)
    try:
        try:
            _free(host, port)
            server = make_server(host, port, create(page, allowed, max_request_mb).server,
                                 threaded=True, request_handler=_Quiet)
        except OSError as err:
            raise PortTaken(f"{host}:{port}: cannot serve there ({err.strerror or err}); "
                            f"--port takes another") from None
        stop = threading.Event()
        before = {s: signal.signal(s, lambda *_: stop.set())
                  for s in (signal.SIGINT, signal.SIGTERM)}
        url = page_url(host, server.port)
        if host not in ("127.0.0.1", "localhost", "::1"):
            where = "" if is_loopback(host) else f" (from {_names(allowed)})"
            print(f"sewfmu: warning: serving on {host}: anyone who reaches port {server.port}"
                  f"{where} can run simulations on this machine", file=sys.stderr, flush=True)
        print(f"sewfmu app: {url} (Ctrl-C stops it)", flush=True)
        thread = threading.Thread(target=server.serve_forever, name="sewfmu-app", daemon=True)
        thread.start()
        if open_browser:
            webbrowser.open(url)
        if ready is not None:
            ready(url)
        try:
            while not stop.wait(0.5):
                pass
        finally:
            for s, handler in before.items():
                signal.signal(s, handler)
            server.shutdown()
            thread.join(10)
    finally:
        page.jobs.shutdown()
        shutil.rmtree(root, ignore_errors=True)
    print("sewfmu app: stopped; every run's process ended", flush=True)


def page_url(host: str, port: int) -> str:
    """The page's address for a browser on this machine: an IPv6 address in brackets (a zone's
    % as %25), every address as its loopback."""
    host = host[1:-1] if host.startswith("[") and host.endswith("]") else host
    host = {"0.0.0.0": "127.0.0.1", "": "127.0.0.1", "::": "::1"}.get(host, host)
    if ":" in host:
        host = f"[{host.replace('%', '%25')}]"
    return f"http://{host}:{port}/"


def _free(host: str, port: int) -> None:
    """Raise OSError if the port is taken (werkzeug would print two lines and exit)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        probe.bind((host, port))


def _names(allowed: Allowed) -> str:
    def named(name: str) -> str:            # an IPv6 address as a browser's address bar has it
        return f"[{name}]" if ":" in name else name
    return ", ".join(sorted({*map(named, allowed.names), *map(named, allowed.anywhere),
                             *(f"{named(n)}:{p}" for n, p in allowed.exact)}))


class _Quiet(WSGIRequestHandler):
    """No line per request on the terminal: the URL line and errors only.

    After its answer, werkzeug reads whatever the client still sends, 10 MB a read, up to 10 GB
    (so that a client sees a 413 rather than a reset): a client that announces a large body
    and sends it slowly, or never, holds a thread and 10 MB each. Here the Guard (guard.py)
    stops the reading once the answer is out (`sewfmu.stop_reading`), and what is left is
    read for a moment and dropped (at most LINGER bytes, LINGER_S seconds) before the
    connection closes: closed at once with unread bytes, the kernel resets it, and the client
    may lose the answer. One request per connection (werkzeug sends Connection: close)."""

    LINGER = 2**20            # bytes
    LINGER_S = 1.0
    _input = None             # the client's input, once the Guard has stopped its reading

    def log_request(self, *args, **kwargs) -> None:
        pass

    def make_environ(self):
        environ = super().make_environ()
        environ["sewfmu.stop_reading"] = self._stop_reading
        return environ

    def _stop_reading(self) -> None:
        if self._input is None:
            self._input, self.rfile = self.rfile, io.BytesIO()   # werkzeug's drain: nothing

    def handle(self) -> None:
        try:
            super().handle()
        finally:
            getattr(self, "environ", {}).pop("sewfmu.stop_reading", None)    # no cycle left
            if self._input is not None:
                _linger(self.connection, self.LINGER, self.LINGER_S)
                # closed here, as finish() closes only the rfile it finds: the socket itself
                # closes only when every file made from it is closed
                self._input.close()


def _linger(connection, most: int, seconds: float) -> None:
    """Half-close, then read and drop what comes until the client closes, `most` bytes or
    `seconds` have passed (Apache's lingering close)."""
    try:
        connection.shutdown(socket.SHUT_WR)
        connection.settimeout(seconds)
        end, left = time.monotonic() + seconds, most
        while left > 0 and time.monotonic() < end:
            data = connection.recv(min(left, 65536))
            if not data:
                break
            left -= len(data)
    except OSError:             # the client is gone, or took longer: close as it is
        pass


class PortTaken(sewfmu.Error):
    """The port asked for is taken (or not ours to take)."""

