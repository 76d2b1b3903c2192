"""Progress on a terminal, one line of stderr drawn by tqdm, for a run's steps, a sweep's points
and a study's runs alike.

Shown only when stderr is a terminal (tqdm's `disable=None`) and the work has taken more than a
second (`delay`: a short run stays silent); redrawn at most a few times a second; the line is
cleared when the work ends. tqdm is loaded only when a line is about to be drawn.
"""
from __future__ import annotations

import os
import sys
import time

QUIET_FOR = 1.0        # s: work shorter than this shows nothing
REDRAW_EVERY = 0.2     # s


class _NoBar:
    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass


def bar(total: int | None, what: str, unit: str, initial: int = 0, enabled: bool = True):
    """A progress line of `total` items (`update(n)`, `close()`); a silent one where not
    `enabled`."""
    if not enabled:
        return _NoBar()
    from tqdm import tqdm  # only when a line may be drawn (start-up time)

    columns, rows = _size(sys.stderr)
    return tqdm(total=total, initial=initial, desc=what, unit=unit, disable=None, leave=False,
                delay=QUIET_FOR, mininterval=REDRAW_EVERY, file=sys.stderr, ncols=columns,
                nrows=rows)


class TerminalProgress:
    """A run's progress callback (`progress(label, done, total)` from the master's loop): its
    line appears once the run has taken QUIET_FOR; before that not even tqdm is loaded."""

    def __init__(self, name: str, stream=None):
        self.name = name
        self.stream = stream or sys.stderr
        self.enabled = bool(getattr(self.stream, "isatty", lambda: False)())
        self.started = time.monotonic()
        self.line = None

    def __call__(self, label: str, done: int, total: int) -> None:
        if not self.enabled:
            return
        if self.line is None:
            if time.monotonic() - self.started < QUIET_FOR:
                return
            from tqdm import tqdm  # only once a line is drawn (start-up time)

            columns, rows = _size(self.stream)
            self.line = tqdm(total=total, desc=f"{self.name} {label}".strip(), unit="step",
                             leave=False, mininterval=REDRAW_EVERY, file=self.stream,
                             ncols=columns, nrows=rows, bar_format=RUN_LINE)
        self.line.update(done - self.line.n)

    def close(self) -> None:
        if self.line is not None:
            self.line.close()
            self.stream.write("\r\033[K")       # the line cleared, whatever width tqdm assumed
            self.stream.flush()
            self.line = None


# a run's line in words, as it was before tqdm drew it
RUN_LINE = "{desc}: step {n_fmt} of {total_fmt} ({percentage:.0f} %), about {remaining} left"


def _size(stream) -> tuple[int, int]:
    """The terminal's columns and rows, 80 x 24 where it says 0: a pseudo-terminal no one has
    sized (tqdm then counts -1 rows and draws nothing)."""
    try:
        size = os.get_terminal_size(stream.fileno())
    except (OSError, ValueError, AttributeError):
        return 80, 24
    return size.columns or 80, size.lines or 24
