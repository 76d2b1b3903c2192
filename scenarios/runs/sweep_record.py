"""A sweep's record in its output folder: points.jsonl, every finished point appended as one JSON
line (what a sweep run again into the folder resumes from), and the table sweep.csv beside it;
which of those files are a sweep's (never appended to or replaced where they are the user's),
and the points an earlier sweep finished there."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from sewfmu.scenarios.files.outputs import OutputError, drop_torn_line

POINTS_FILE = "points.jsonl"
TABLE_FILE = "sweep.csv"


def warn(message: str) -> None:
    print(f"sewfmu: warning: {message}", file=sys.stderr)


def finished_points(out_dir: Path) -> dict[str, dict]:
    """Points that an earlier (perhaps interrupted) run finished well, by key. Damaged lines (torn
    by a kill, emptied, not a point) are skipped with a warning; failed points are left out, so
    that they are tried again."""
    done, damaged = {}, []
    path = out_dir / POINTS_FILE
    if not path.exists():
        return done
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            if not line.strip():
                continue
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                row = None
            if not isinstance(row, dict) or not isinstance(row.get("key"), str) \
                    or "status" not in row:
                damaged.append(number)
                continue
            if row["status"] == "ok":
                done[row["key"]] = row
    if damaged:
        shown = ", ".join(map(str, damaged[:10])) + (" ..." if len(damaged) > 10 else "")
        warn(f"{path}: skipped {len(damaged)} damaged line(s) ({shown}); those points run again")
    return done


def refuse_files_not_ours(out_dir: Path) -> None:
    """A sweep appends to points.jsonl and rewrites sweep.csv: files of those names that are not
    a sweep's (the user's own) are refused, never appended to or replaced."""
    record, table = out_dir / POINTS_FILE, out_dir / TABLE_FILE
    theirs = []
    if record.is_file() and record.stat().st_size:
        with open(record, encoding="utf-8", errors="replace") as f:
            first = next((line for line in f if line.strip()), "")
        try:
            ours = isinstance(json.loads(first), dict) and "key" in json.loads(first)
        except ValueError:
            ours = False
        if not ours:
            theirs.append(POINTS_FILE)
    if table.is_file() and table.stat().st_size:
        with open(table, encoding="utf-8", errors="replace") as f:
            if not f.readline().startswith("index,"):
                theirs.append(TABLE_FILE)
    if theirs:
        raise OutputError(f"output folder {out_dir}: {' and '.join(theirs)} there "
                          f"{'is' if len(theirs) == 1 else 'are'} not a sewfmu sweep's, and a "
                          f"sweep would write into {'it' if len(theirs) == 1 else 'them'}: give "
                          f"another output folder, or move {'it' if len(theirs) == 1 else 'them'}"
                          f" away")


def open_log(path: Path):
    """points.jsonl for appending, starting on a fresh line (after a torn last line, the next
    row must not be glued onto it)."""
    if path.exists():
        drop_torn_line(path)
    return open(path, "ab")


def is_a_sweeps(out_dir: Path, name: str) -> bool:
    """A file of a sweep's made before folders kept a manifest: its record, its table, a
    point's results beside a record that is a sweep's."""
    if name.startswith("points/"):
        name = POINTS_FILE
    try:
        refuse_files_not_ours(out_dir)
    except OutputError:
        return False
    return name in (POINTS_FILE, TABLE_FILE) and (out_dir / name).is_file()
