"""`sewfmu app`'s options for the command line (sewfmu/cli.py adds the command from here)."""
from __future__ import annotations

import argparse

from sewfmu.app import app
from sewfmu.console import whole_number


def add_command(sub) -> None:
    p = sub.add_parser("app", help="the page: set, run, watch and compare a mechanism in the "
                                   "browser (docs/app.md)")
    p.add_argument("scenario", nargs="*", metavar="SCENARIO_OR_FILE",
                   help="scenario files (TOML, SSP) to offer beside the catalogue, or catalogue "
                        "names; the first is the one the page opens on")
    p.add_argument("--port", type=_port, default=8050, help="the port (default 8050)")
    p.add_argument("--host", default="127.0.0.1",
                   help="the address to serve on (default 127.0.0.1: this machine only)")
    p.add_argument("--allow-host", action="append", default=[], metavar="NAME[:PORT]",
                   help="answer requests that name this host too (a name or address of this "
                        "machine, or a proxy's); repeatable. Needed with --host 0.0.0.0. NAME "
                        "alone: read on any port, changed (Run) only from http://NAME on --port; "
                        "a proxy's origin as NAME:PORT (e.g. NAME:443)")
    p.add_argument("--max-request-mb", type=_megabytes, default=4.0, metavar="MB",
                   help="the largest request body read, in MiB (default 4)")
    p.add_argument("--open", action="store_true", help="open the page in the browser")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run sweeps on a Dask cluster, e.g. tcp://127.0.0.1:8786")
    p.add_argument("--workers", type=whole_number,
                   help="local worker processes of a sweep (default: all cores)")
    p.set_defaults(func=run_command)


def run_command(args) -> None:

    app(args.scenario, port=args.port, host=args.host, open_browser=args.open,
        scheduler=args.scheduler, workers=args.workers, allow_hosts=args.allow_host,
        max_request_mb=args.max_request_mb)


def _port(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a port number from 1 to 65535, got "
                                         f"{text!r}") from None
    if not 1 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"expected a port number from 1 to 65535, got {value}")
    return value


def _megabytes(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = None
    if value is None or not 0 < value <= 1024:
        raise argparse.ArgumentTypeError(f"expected a number of MiB above 0, at most 1024, got "
                                         f"{text!r}")
    return value
