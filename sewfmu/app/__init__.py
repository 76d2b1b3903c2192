"""`sewfmu app`: a local web page to set a mechanism's values, run it, watch it move and compare
runs (docs/app.md). A client of the public API only (sewfmu.parameters, load, run, sweep,
Run.mechanism): it adds no second way to run a scenario.

    import sewfmu
    sewfmu.app()                       # serves http://127.0.0.1:8050/ until Ctrl-C

The page needs the extra `app` (Dash, Plotly); this package loads them only when it serves.
"""
from __future__ import annotations

import sys
import types


def app(scenarios=(), port: int = 8050, host: str = "127.0.0.1", open_browser: bool = False,
        scheduler: str | None = None, workers: int | None = None, allow_hosts=(),
        max_request_mb: float = 4.0) -> None:
    """Serve the page until Ctrl-C or SIGTERM: the catalogue's scenarios and the files named in
    `scenarios`; only on 127.0.0.1 unless `host` says otherwise. Sweeps run on `workers` local
    processes or on the Dask `scheduler`. It answers only requests that name it by a loopback
    name, `host`, or one of `allow_hosts` (NAME or NAME:PORT), and reads bodies of at most
    `max_request_mb` MiB (docs/app.md, Security)."""
    from sewfmu.app.guard import check_hosts  # standard library only: no extra needed

    check_port(port)
    allow_hosts = check_hosts(host, allow_hosts)
    max_request_mb = check_size(max_request_mb)
    try:
        from sewfmu.app.serve import serve  # optional extra (app): dash, plotly
    except ModuleNotFoundError as err:
        if err.name and err.name.split(".")[0] in ("dash", "plotly", "flask", "werkzeug"):
            from sewfmu.console import install_command  # only to say how to install it

            raise MissingApp(f"`sewfmu app` needs the optional package {err.name}: "
                             f"{install_command('app')}", name=err.name) from None
        raise
    serve(list(scenarios), port, host, open_browser, scheduler, workers,
          allow_hosts=allow_hosts, max_request_mb=max_request_mb)


def check_port(port) -> int:
    import sewfmu  # the error family (the package is loaded already)

    if isinstance(port, bool) or not isinstance(port, int) or not 1 <= port <= 65535:
        raise sewfmu.ScenarioError(f"port: expected a whole number from 1 to 65535, got "
                                   f"{port!r}")
    return port


def check_size(megabytes) -> float:
    import sewfmu  # the error family (the package is loaded already)

    if isinstance(megabytes, bool) or not isinstance(megabytes, (int, float)) or \
            not 0 < megabytes <= 1024:
        raise sewfmu.ScenarioError(f"--max-request-mb: expected a number of MiB above 0, at "
                                   f"most 1024, got {megabytes!r}")
    return float(megabytes)


class MissingApp(ModuleNotFoundError):
    """The extra `app` is not installed (its message is the one line that says how)."""


class _Callable(types.ModuleType):
    """`sewfmu.app(...)` serves whether `sewfmu.app` is this package or its function."""

    def __call__(self, *args, **kwargs):
        return app(*args, **kwargs)


sys.modules[__name__].__class__ = _Callable
