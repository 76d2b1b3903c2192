"""The design studies on the command line: `sewfmu optimize`, `sewfmu fit`, `sewfmu sensitivity`.
Their options (ranges, goals, constraints, budgets) and what they print (optima, estimates with
their standard errors, indices), each calling the API's function of its verb (sewfmu/api.py);
sewfmu/cli.py's main adds them to its commands."""
from __future__ import annotations

import sys
from pathlib import Path

from sewfmu import api
from sewfmu.console import at_least, max_runs_option, whole_number
from sewfmu.scenarios.format.values import ScenarioError, parse_value


def _ranges(items: list[str], option: str) -> dict[str, str]:
    """`instance.parameter=LO..HI unit` options as {name: "LO..HI unit"}."""
    out = {}
    for item in items or []:
        name, eq, text = item.partition("=")
        if not eq or not name.strip() or not text.strip():
            raise ScenarioError(f"{option} {item}: expected instance.parameter=LO..HI with an "
                                f"optional unit, like \"shaft.omega0=800..1200 rpm\"")
        if name.strip() in out:
            raise ScenarioError(f"{option} {name.strip()}: given twice")
        out[name.strip()] = text.strip()
    return out


def _sets(items: list[str]) -> dict:
    out = {}
    for item in items or []:
        target, eq, text = item.partition("=")
        if not eq:
            raise ScenarioError(f"--set {item}: expected instance.parameter=value")
        out[target.strip()] = parse_value(text.strip(), f"--set {item}")
    return out


def _quantity(value, unit: str) -> str:
    text = f"{value:.6g}" if isinstance(value, float) else str(value)
    return f"{text} {unit}" if unit and unit != "1" else text


def _warn(message: str) -> None:
    print(f"sewfmu: warning: {message}", file=sys.stderr)


def cmd_optimize(args) -> None:
    out = Path(args.out) if args.out else Path("results") / f"{Path(args.scenario).stem}_optimize"
    target = dict(item.partition("=")[::2] for item in args.target) if args.target else None
    if target and len(target) < len(args.target):     # the second would replace the first
        names = [item.partition("=")[0].strip() for item in args.target]
        twice = next(n for n in names if names.count(n) > 1)
        raise ScenarioError(f"--target {twice}: given twice (one target per figure)")
    if target and any(not v.strip() for v in target.values()):
        raise ScenarioError(f"--target {' '.join(args.target)}: expected FIGURE=VALUE with an "
                            f"optional unit, like \"F2_weld_mean=25 N\"")
    o = api.optimize(args.scenario, _ranges(args.vary, "--vary"), minimize=args.minimize,
                     maximize=args.maximize,
                     target={k.strip(): v.strip() for k, v in target.items()} if target else None,
                     constraints=args.constraint, set=_sets(args.set), method=args.method,
                     workers=args.workers, out=out, plot=args.plot,
                     max_evaluations=args.max_evaluations, progress=not args.quiet,
                     max_runs=args.max_runs)
    if not o.feasible:
        _warn("no evaluated point meets every constraint: the one closest to meeting them "
              "is shown")
    if not o.converged:
        _warn(f"the {o.algorithm} search did not converge ({o.message}); the best point "
              f"evaluated is shown")
    why = "within the ranges it cannot be reached" if o.converged else "the search stopped first"
    for figure, miss in o.summary.get("misses", {}).items():
        goal = o.summary["target"][figure]
        if miss is not None and abs(miss) > 1e-3 * (abs(goal) or 1.0):
            unit = o.units.get(figure, "")
            _warn(f"{figure} = {_quantity(goal + miss, unit)} misses its target "
                  f"{_quantity(goal, unit)} ({why}); the closest point is shown")
    print(f"{o.scenario}: best of {len(o.evaluations)} evaluations ({o.computed} run now; "
          f"{o.algorithm}); results in {out}/")
    print("  best point:")
    for name, value in o.best.items():
        print(f"    {name:24s} {_quantity(value, o.units.get(name, ''))}")
    print("  its key figures:")
    for name, value in o.figures.items():
        print(f"    {name:24s} {_quantity(value, o.units.get(name, ''))}")


def cmd_fit(args) -> None:
    out = Path(args.out) if args.out else Path("results") / f"{Path(args.scenario).stem}_fit"
    f = api.fit(args.scenario, args.data, _ranges(args.free, "--free"), set=_sets(args.set),
                out=out, max_evaluations=args.max_evaluations, progress=not args.quiet,
                max_runs=args.max_runs)
    if not f.converged:
        _warn(f"least_squares did not converge ({f.message})")
    for note in f.summary.get("warnings", []):
        _warn(note)
    print(f"{f.scenario}: fit to {args.data} in {f.evaluations} runs "
          f"({f.summary['computed']} made now); results in {out}/")
    for name, value in f.estimates.items():
        unit = f.units.get(name, "")
        print(f"  {name} = {_quantity(value, unit)} ± {_quantity(f.standard_errors[name], unit)}")
    print("  residual rms: " + ", ".join(f"{c} {_quantity(v, f.units.get(c, ''))}"
                                         for c, v in f.residual_rms.items()))


def cmd_sensitivity(args) -> None:
    out = Path(args.out) if args.out else \
        Path("results") / f"{Path(args.scenario).stem}_sensitivity"
    s = api.sensitivity(args.scenario, _ranges(args.vary, "--vary"), args.figure,
                        set=_sets(args.set), method=args.method, samples=args.samples,
                        workers=args.workers, out=out, progress=not args.quiet,
                        max_runs=args.max_runs)
    if s.failed:
        _warn(f"{s.failed} of {s.runs} samples failed (see {out}/sweep.csv); their groups are "
              f"left out of the indices")
    print(f"{s.scenario}: {s.method} indices from {s.runs} runs; results in {out}/")
    shown = ("S1", "ST") if s.method == "sobol" else ("mu_star", "sigma")
    for figure, by_parameter in s.indices.items():
        print(f"  {figure}:")
        for name, entry in by_parameter.items():
            cells = ", ".join(f"{k} = {_index(entry[k])} ± {_index(entry.get(k + '_conf'))}"
                              if entry.get(k + "_conf") is not None else
                              f"{k} = {_index(entry[k])}" for k in shown)
            print(f"    {name}: {cells}")


def _index(value) -> str:
    return "n/a" if value is None else f"{value:.3g}"


def add_commands(sub) -> None:
    """The three commands, on the command line's subparsers."""
    p = sub.add_parser("optimize", help="the parameters that meet a goal on a key figure")
    p.add_argument("scenario", help="catalogue name or path to a .toml file")
    p.add_argument("--vary", action="append", required=True, metavar="INSTANCE.PARAM=LO..HI",
                   help="a parameter and its range, with a unit where wanted (\"800..1200 rpm\"); "
                        "repeatable")
    goal = p.add_mutually_exclusive_group(required=True)
    goal.add_argument("--minimize", metavar="FIGURE")
    goal.add_argument("--maximize", metavar="FIGURE")
    goal.add_argument("--target", action="append", metavar="FIGURE=VALUE",
                      help="a value to reach, with its unit where wanted (\"F2_weld_mean=25 N\")")
    p.add_argument("--constraint", action="append", metavar="FIGURE>=VALUE",
                   help="FIGURE>=VALUE or FIGURE<=VALUE, with a unit where wanted; repeatable")
    p.add_argument("--set", action="append", metavar="INSTANCE.PARAM=VALUE",
                   help="override a parameter (or experiment.*) for every evaluation")
    p.add_argument("--method", choices=("local", "global"), default="local",
                   help="local: brentq, bounded scalar, Nelder-Mead or SLSQP (default); "
                        "global: differential evolution, in parallel")
    p.add_argument("--workers", type=whole_number, metavar="N",
                   help="worker processes of the global method (default: all cores)")
    p.add_argument("--max-evaluations", type=whole_number, metavar="N",
                   help="stop after this many evaluations (default 200 local, 400 global)")
    p.add_argument("--out", metavar="DIR",
                   help="output folder (default: results/SCENARIO_optimize/); a study "
                                 "run again into it resumes")
    p.add_argument("--plot", action="store_true", help="convergence.png")
    max_runs_option(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_optimize)
    p = sub.add_parser("fit", help="parameters learnt from measured time series")
    p.add_argument("scenario", help="catalogue name or path to a .toml file")
    p.add_argument("--data", required=True, metavar="FILE.csv",
                   help="a time column and columns named like recorded outputs (punch.F2)")
    p.add_argument("--free", action="append", required=True, metavar="INSTANCE.PARAM=LO..HI",
                   help="a parameter to fit and its range; repeatable")
    p.add_argument("--set", action="append", metavar="INSTANCE.PARAM=VALUE")
    p.add_argument("--max-evaluations", type=whole_number, metavar="N",
                   help="least_squares' max_nfev (default 100): evaluations of the residuals, "
                        "besides the n runs of each finite-difference Jacobian")
    p.add_argument("--out", metavar="DIR", help="output folder (default: results/SCENARIO_fit/); "
                                                "a fit run again into it resumes")
    max_runs_option(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_fit)
    p = sub.add_parser("sensitivity", help="which parameters matter to key figures (SALib)")
    p.add_argument("scenario", help="catalogue name or path to a .toml file")
    p.add_argument("--vary", action="append", required=True, metavar="INSTANCE.PARAM=LO..HI",
                   help="a parameter and its range; repeatable")
    p.add_argument("--figure", action="append", required=True, metavar="FIGURE",
                   help="a key figure to analyze; repeatable")
    p.add_argument("--set", action="append", metavar="INSTANCE.PARAM=VALUE")
    p.add_argument("--method", choices=("sobol", "morris"), default="sobol")
    p.add_argument("--samples", type=at_least(2), metavar="N",
                   help="Sobol: base samples N, a power of 2 "
                                                  "(N·(D+2) runs; default 64); Morris: "
                                                  "trajectories (N·(D+1) runs; default 16)")
    p.add_argument("--workers", type=whole_number, metavar="N",
                   help="local worker processes (default: all cores)")
    p.add_argument("--out", metavar="DIR",
                   help="output folder (default: results/SCENARIO_sensitivity/); a "
                                 "study run again into it resumes")
    max_runs_option(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_sensitivity)
