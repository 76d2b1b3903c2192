"""A sweep's record in its output folder: points.jsonl, every finished point appended as one JSON
line (what a sweep run again into the folder resumes from), and the table sweep.csv beside it;
the points an earlier sweep finished there. Whether the files there are a sweep's is the
folder's manifest's word alone (files/outputs.py), never what a file holds."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from sewfmu.scenarios.files.outputs import Record, drop_torn_line

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


def open_log(path: Path):
    """points.jsonl for appending, starting on a fresh line (after a torn last line, the next
    row must not be glued onto it)."""
    if path.exists():
        drop_torn_line(path)
    return Record(path)
