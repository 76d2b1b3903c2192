"""What the command line prints: key figures with their units and estimated errors, tables side
by side, a sweep's failed points, and any error as one line that says what was wrong; and the
count type its options share (whole_number)."""
from __future__ import annotations

import argparse
import json
import sys
from importlib import metadata
from pathlib import Path
from urllib.parse import unquote, urlparse

from sewfmu.scenarios.format.values import label_of


def print_run(name: str, run, out: Path) -> None:
    """The key figures with their units and estimated coupling errors, a line each; what the
    master did and the wall time apart; the files written."""
    print(f"{name}: results in {out}/")
    runs = run.runs or {"": run}
    for label, each in runs.items():
        if each.summary.get("master_unconverged_steps"):
            print(f"sewfmu: warning: {label + ': ' if label else ''}the iterative coupling did "
                  f"not converge in {each.summary['master_unconverged_steps']} steps (a shorter "
                  f"step or a looser experiment.tolerance helps)", file=sys.stderr)
    for label, each in runs.items():
        if label:
            print(f"  {label}")
        errors = each.summary.get("coupling_error") or {}
        physics = {k: v for k, v in each.figures.items()
                   if k != "wall_time_s" and not k.startswith("master_")}
        for key, value in physics.items():
            unit = each.units.get(key, "").replace("1", "") if each.units.get(key) == "1" \
                else each.units.get(key, "")
            error = errors.get("figures", {}).get(key)
            spread = f"  ± {fmt(error)} {unit}".rstrip() if error is not None else ""
            print(f"    {key:24s} {fmt(value):>12s} {unit:4s}{spread}")
        done = {k: v for k, v in each.figures.items() if k not in physics}
        if errors.get("none"):
            print(f"    (no coupling error estimated: {errors['none']})")
        elif errors:
            how = f"no estimate ({errors['failed']})" if errors.get("failed") else \
                f"from {errors['method']}"
            print(f"    (± : the estimated coupling error, {how})")
        print("    " + ", ".join(f"{k} = {fmt(v)}" for k, v in done.items()))
    if out.is_dir():
        written = sorted(str(p.relative_to(out)) for p in out.rglob("*")
                         if p.is_file() and not p.name.startswith("."))
        print(f"  files: {', '.join(written)}")


def print_sweep(name: str, rows: list[dict], out: Path) -> None:
    failed = [r for r in rows if r["status"] != "ok"]
    print(f"{name}: {len(rows)} points, {len(failed)} failed; table in {out}/sweep.csv")
    for row in failed:                  # a failed row: its index, key, swept values, error
        values = ",".join(label_of(k, v) for k, v in row.items()
                          if k not in ("index", "key", "status", "error"))
        print(f"  failed: {values}: {row['error']}")


def print_side_by_side(rows, left: str, right: str) -> None:
    """Rows (figure, left value, right value, difference) as an aligned table."""
    print(f"  {'figure':22s} {left:>14s} {right:>14s} {'difference':>12s}")
    for key, a, b, d in rows:
        print(f"  {key:22s} {cell(a, 14)} {cell(b, 14)} {cell(d, 12)}")


def cell(value, width: int) -> str:
    """A value right-aligned in its column; nothing for a difference that has none."""
    return f"{fmt(value) if value is not None else '':>{width}s}"


def fmt(value) -> str:
    if isinstance(value, float):
        return f"{value:.4f}"
    return str(value)


def explain(err: Exception, command: str) -> str:
    """An error as one line that says what was wrong and where."""
    from sewfmu.errors import Error  # light: the base of every refusal

    if isinstance(err, Error):
        return " ".join(str(err).split())
    if isinstance(err, ModuleNotFoundError) and err.name:
        extra = EXTRAS.get(err.name.split(".")[0])
        if extra:
            return (f"`sewfmu {command}` needs the optional package {err.name.split('.')[0]}: "
                    f"{install_command(extra)}")
    if isinstance(err, OSError) and err.strerror:
        where = f"{err.filename}: " if err.filename else ""
        return f"{where}{err.strerror}"
    if isinstance(err, MemoryError):
        return f"out of memory during `sewfmu {command}` (a smaller experiment.record_every " \
               f"or a shorter run needs less)"
    return (f"unexpected {type(err).__name__} during `sewfmu {command}`: {err} "
            f"(a bug in sewfmu: please report it; --debug shows where)")


# the optional packages and the extra of pyproject.toml that installs each
EXTRAS = {"distributed": "dask", "dask": "dask", "libcosimpy": "interop", "ecospy": "interop",
          "pyssp_standard": "interop", "fmu_manipulation_toolbox": "interop", "tbb": "interop",
          "pandas": "pandas", "SALib": "design", "dash": "app", "plotly": "app"}


def install_command(extra: str) -> str:
    """The pip command that adds an extra to this sewfmu, from where it was installed: its
    checkout (editable or not), its wheel, or the package index."""
    # (a build's sewfmu.egg-info in the working folder is a distribution too, without origin)
    found = [d.read_text("direct_url.json") for d in metadata.distributions(name="sewfmu")]
    try:
        origin = json.loads(next((t for t in found if t), "{}")) if found else None
    except ValueError:
        origin = {}
    if origin is None:                    # not installed: running from a checkout
        return f"pip install -e \".[{extra}]\" in sewfmu's checkout"
    url = origin.get("url", "")
    if not url.startswith("file://"):
        return f"pip install \"sewfmu[{extra}]\""
    where = unquote(urlparse(url).path)
    editable = "-e " if origin.get("dir_info", {}).get("editable") else ""
    return f"pip install {editable}\"{where}[{extra}]\""


def whole_number(text: str) -> int:
    """An argparse type: a count of at least 1 (workers, samples, evaluations)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {value}")
    return value
