"""What the API's verbs give back (sewfmu/api.py): a Run (one co-simulation, or a study computed
from a scenario's parameters), a Sweep (its points), and the two refusals that carry what was
done (InaccurateRun, SweepFailed)."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from sewfmu.arguments import whole
from sewfmu.errors import Error
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import ScenarioError
from sewfmu.scenarios.mechanisms.base import figures_of


@dataclass
class Run:
    """One co-simulation: key figures, their units, the recorded time series.

    summary: what summary.json holds (key figures, master, step, provenance...).
    series: numpy structured array, a `time` field and one `instance.variable` field per
    recorded output; units: the unit of every column and key figure ("" for none).
    A study scenario (carriage_resonance, feed_ratio, takeup_tolerance) is computed, not
    co-simulated: its headline figures are the key figures, `study` holds all of it (what
    study.json holds) and there is no time series."""
    name: str
    summary: dict
    series: Any
    units: dict[str, str]
    out: Path | None = None
    runs: dict[str, "Run"] = field(default_factory=dict)    # [compare]: one Run per label
    shaft: str | None = None                  # the MainShaft whose turns revolution() counts
    study: dict | None = None                 # a study scenario's whole result
    scenario: Scenario | None = field(default=None, repr=False)    # as run, values applied

    def _recorded(self, what: str):
        if self.series is None:
            raise ScenarioError(f"{self.name} is a study, computed rather than co-simulated: "
                                f"it has no time series for {what}; Run.study holds its result")
        return self.series

    @property
    def figures(self) -> dict:
        """The key figures alone (what `sewfmu run` prints)."""
        return figures_of(self.summary)

    @property
    def provenance(self) -> dict:
        return self.summary.get("provenance", {})

    def to_pandas(self):
        """The time series as a pandas DataFrame indexed by time (pandas must be installed)."""
        return _frame(self._recorded("to_pandas()"), index="time")

    def revolution(self, k: int = -1):
        """The k-th whole revolution of the shaft (k=-1 the last): a structured array with
        `crank_deg` in [0, 360), increasing (no wrap-around), and the recorded fields."""
        from sewfmu.scenarios.runs.revolution import revolution  # numpy: not at `import sewfmu`

        return revolution(self._recorded("revolution()"), f"{self.shaft or 'shaft'}.phi",
                          whole(k, "revolution(k)"), self.name)

    def mechanism(self, frames: int = 36) -> dict:
        """The mechanism at `frames` equally spaced crank angles of the last revolution, as
        numbers (what --animate draws): {"crank_deg", "time", "samples", "points": {name:
        [(x, y) mm per frame]}, "chains": [[names joined by bars]], "tracked" (the recorded
        point), "xlim", "ylim"}. A scenario whose analysis has no drawing is a ScenarioError."""
        from sewfmu.scenarios.cosim.master import RunResult
        from sewfmu.scenarios.mechanisms.animation import linkage

        frames = whole(frames, "mechanism(frames)", 2, 3600)     # 0.1 degree apart at most
        if self.scenario is None or self.series is None:
            raise ScenarioError(f"{self.name}: no recorded run to draw (a [compare] run: take "
                                f"one of run.runs)")
        columns = {n: self.series[n] for n in self.series.dtype.names if n != "time"}
        result = RunResult(self.scenario, self.series["time"], columns, 0.0)
        try:
            return linkage(result, frames)
        except Error as err:
            raise ScenarioError(f"{self.name}: {err}") from None

    def __repr__(self) -> str:
        if self.runs:
            return f"<sewfmu.Run {self.name}: {len(self.runs)} runs {list(self.runs)}>"
        shown = ", ".join(f"{k}={_short(v)}" for k, v in list(self.figures.items())[:4])
        what = "a study" if self.series is None else f"{len(self.series)} samples"
        return f"<sewfmu.Run {self.name}: {what}; {shown}>"


@dataclass
class Sweep:
    """A sweep's points: `rows` as in sweep.csv (the swept values, status, key figures, error);
    `table` the same as a numpy structured array (numbers; NaN where a point failed)."""
    name: str
    swept: list[str]
    rows: list[dict]
    units: dict[str, str]
    out: Path | None = None

    @property
    def failed(self) -> list[dict]:
        return [r for r in self.rows if r["status"] != "ok"]

    @property
    def table(self):
        import numpy as np  # numpy: not at `import sewfmu`

        columns = self.swept + [k for k in self.units if k not in self.swept]
        data = np.full(len(self.rows), np.nan, dtype=[(c, "f8") for c in columns])
        for i, row in enumerate(self.rows):
            for c in columns:
                value = row.get(c)
                if isinstance(value, (int, float)):
                    data[c][i] = value
        return data

    def to_pandas(self):
        """The rows as a pandas DataFrame (pandas must be installed)."""
        return _pandas().DataFrame(self.rows).drop(columns=["key"], errors="ignore")

    def __repr__(self) -> str:
        return (f"<sewfmu.Sweep {self.name}: {len(self.rows)} points over "
                f"{', '.join(self.swept)}; {len(self.failed)} failed>")


class InaccurateRun(Error):
    """A run whose estimated coupling error exceeds experiment.accuracy: `run` holds what it
    gave (its files are written where out= was given)."""

    def __init__(self, message: str, run: "Run"):
        super().__init__(message)
        self.run = run


class SweepFailed(ScenarioError):
    """Every point of a sweep failed: `rows` holds each with its error."""

    def __init__(self, message: str, rows: list[dict]):
        super().__init__(message)
        self.rows = rows


def _run_of(name: str, result, summary: dict, out: Path | None, shaft: str | None) -> Run:
    import numpy as np  # numpy: not at `import sewfmu`

    names = list(result.columns)
    series = np.empty(len(result.time), dtype=[("time", "f8")] + [(n, "f8") for n in names])
    series["time"] = result.time
    for n in names:
        series[n] = result.columns[n]
    units = {"time": "s", **{n: result.units.get(n, "") for n in names},
             **summary.get("units", {})}
    return Run(name, summary, series, units, out, shaft=shaft, scenario=result.scenario)


def _pandas():
    """pandas, or one line that says how to install it."""
    from sewfmu.extras import require  # light; pandas itself only when asked for

    return require("pandas", "to_pandas()")


def _frame(series, index: str):
    return _pandas().DataFrame(series).set_index(index)


def _short(value) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)
