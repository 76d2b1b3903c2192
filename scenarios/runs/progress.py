"""A run's progress on a terminal: steps done and the time left, on one line of stderr.

Shown only when stderr is a terminal and the run has taken more than a second (a short run stays
silent); redrawn at most a few times a second; the line is cleared when the run ends.
"""
from __future__ import annotations

import sys
import time


class TerminalProgress:
    QUIET_FOR = 1.0        # s: runs shorter than this show nothing
    REDRAW_EVERY = 0.2     # s

    def __init__(self, name: str, stream=None):
        self.name = name
        self.stream = stream or sys.stderr
        self.enabled = bool(getattr(self.stream, "isatty", lambda: False)())
        self.started = time.monotonic()
        self.drawn_at = 0.0
        self.shown = False

    def __call__(self, label: str, done: int, total: int) -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        elapsed = now - self.started
        if elapsed < self.QUIET_FOR or now - self.drawn_at < self.REDRAW_EVERY:
            return
        self.drawn_at = now
        left = elapsed / done * (total - done) if done else float("nan")
        what = f"{self.name} {label}".strip()
        self.stream.write(f"\r\033[K{what}: step {done:,} of {total:,} "
                          f"({100 * done / total:.0f} %), about {_duration(left)} left")
        self.stream.flush()
        self.shown = True

    def close(self) -> None:
        if self.shown:
            self.stream.write("\r\033[K")
            self.stream.flush()
            self.shown = False


def _duration(seconds: float) -> str:
    if seconds != seconds:
        return "? s"
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"
