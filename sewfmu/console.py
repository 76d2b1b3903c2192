"""What the command line prints: key figures with their units and estimated errors, tables side
by side, a sweep's failed points, and any error as one line that says what was wrong; and the
count type its options share (whole_number)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from sewfmu.extras import EXTRAS, install_command  # noqa: F401  (install_command: the app's and the CLI's)
from sewfmu.scenarios.files.outputs import written_by_last_run
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
        width = max([24] + [len(k) for k in physics])
        for key, value in physics.items():
            unit = each.units.get(key, "").replace("1", "") if each.units.get(key) == "1" \
                else each.units.get(key, "")
            error = errors.get("figures", {}).get(key)
            spread = f"  ± {fmt(error)} {unit}".rstrip() if error is not None else \
                "  no ±" if key in errors.get("untrusted", {}) else ""
            print(f"    {key:{width}s} {fmt(value):>12s} {unit:4s}{spread}")
        done = {k: v for k, v in each.figures.items() if k not in physics}
        if errors.get("none"):
            print(f"    (no coupling error estimated: {errors['none']})")
        elif errors.get("failed"):
            print(f"    (no ±, no bound of the coupling error: {errors['failed']})")
        elif errors:
            print(f"    (± : a bound of the coupling error, from {errors['method']})")
        for key, why in errors.get("untrusted", {}).items():
            print(f"    (no ± for {key}: {why})")
        if done:
            print("    " + ", ".join(f"{k} = {fmt(v)}" for k, v in done.items()))
    written = written_by_last_run(out)        # what this run wrote, not the user's own files
    if written:
        print(f"  files: {', '.join(sorted(written))}")


def print_sweep(name: str, rows: list[dict], out: Path) -> None:
    failed = [r for r in rows if r["status"] != "ok"]
    print(f"{name}: {len(rows)} points, {len(failed)} failed; table in {out}/sweep.csv")
    for row in failed:                  # a failed row: its index, key, swept values, error
        values = ",".join(label_of(k, v) for k, v in row.items()
                          if k not in ("index", "key", "status", "error"))
        print(f"  failed: {values}: {row['error']}")
    # the sweep's own files (its record, table, plot, report), not the user's beside them
    written = [n for n in ("sweep.csv", "points.jsonl", f"{name}_sweep.png", "report.html")
               if (out / n).is_file()] + (["points/"] if (out / "points").is_dir() else [])
    if written:
        print(f"  files: {', '.join(written)}")


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


def at_least(least: int):
    """An argparse type: a whole number of at least `least`."""
    def count(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number >= {least}, got "
                                             f"{text!r}") from None
        if value < least:
            raise argparse.ArgumentTypeError(f"expected a whole number >= {least}, got {value}")
        return value
    return count


# a count of at least 1 (workers, evaluations)
whole_number = at_least(1)


def max_runs_option(parser) -> None:
    """--max-runs, the bound on a sweep's or a study's runs (scenarios/runs/budget.py)."""
    parser.add_argument("--max-runs", type=whole_number, metavar="N",
                        help="refuse more runs than this, counted before the first (default "
                             "10000, or SEWFMU_MAX_RUNS)")
