"""The only files the page serves: a run's own, by its run id and one of a few fixed names, from
the one temporary folder the app made. Nothing the page sends is ever taken as a path."""
from __future__ import annotations

import re
from pathlib import Path

# study.json: what a study scenario (computed, not co-simulated) gives instead of results.csv
FILES = ("results.csv", "summary.json", "study.json", "report.html", "scenario.toml",
         "command.txt")
RUN_ID = re.compile(r"[0-9a-f]{16}")     # secrets.token_hex(8), as jobs.py makes them


def result_file(root: Path, run_id, name) -> Path | None:
    """The file `name` of run `run_id` under root, or None: an id that is not one the app makes,
    a name not in FILES, or a file that is not (yet) there."""
    if not isinstance(run_id, str) or not RUN_ID.fullmatch(run_id):
        return None
    if not isinstance(name, str) or name not in FILES:
        return None
    path = Path(root) / run_id / name
    return path if path.is_file() else None


def present(root: Path, run_id: str) -> list[str]:
    """The names of FILES that run `run_id` has written so far."""
    return [name for name in FILES if result_file(root, run_id, name) is not None]
