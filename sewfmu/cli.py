"""`sewfmu`: the command line. Each command parses its options, calls the API's function of
the same verb where it has one (sewfmu/api.py: run, sweep, compare, build, show, load), and prints
what it returns; the commands for other tools (export, references, host-env, crosscheck) call
their wing. Errors become one line (`explain`)."""
from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import sys
import warnings
from pathlib import Path

from sewfmu import api, console
from sewfmu._version import __version__
from sewfmu.components.registry import FMUS
from sewfmu.scenarios.cosim import watchdog
from sewfmu.scenarios.cosim.guardian import guard_a_child
from sewfmu.scenarios.cosim.interrupt import Interrupted, interrupt_on_signals, settled
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.format.values import ScenarioError, parse_value


def _set_values(sets: list[str]) -> dict:
    """--set options as {instance.parameter: value} (the last of one name wins)."""
    values = {}
    for item in sets or []:
        target, eq, text = item.partition("=")
        if not eq:
            raise ScenarioError(f"--set {item}: expected instance.parameter=value")
        values[target.strip()] = parse_value(text.strip(), f"--set {item}")
    return values


def _load_with_sets(name: str, sets: list[str]):
    values = _set_values(sets)
    if len({"experiment.revolutions", "experiment.stop_time"} & set(values)) == 2:
        from sewfmu.scenarios.runs.sweep import refuse_two_lengths  # only when both are given

        refuse_two_lengths({k: "--set" for k in values})
    scenario = load(name)
    for target, value in values.items():
        scenario.set_value(target, value)
    return scenario


def cmd_build(args) -> None:
    for path in api.build(args.fmi, args.dest, native=args.native):
        print(path)


def cmd_list(args) -> None:
    print("components (FMUs):")
    for name, (module, slave) in FMUS.items():
        doc = getattr(importlib.import_module(f"sewfmu.components.{module}"), slave).__doc__
        print(f"  {name:14s} {doc.strip().splitlines()[0]}")
    print("scenarios:")
    for name in api.catalogue():
        print(f"  {name:18s} {api.load(name).description}")


def cmd_run(args) -> None:
    from sewfmu.scenarios.runs.results import keep_unfinished

    scenario = _load_with_sets(args.scenario, args.set)
    out = Path(args.out) if args.out else Path("results") / scenario.name

    def keep(result, reason: str) -> str:
        """What a run that did not finish recorded, into OUT/interrupted/ (results.py)."""
        return keep_unfinished(result, reason, out)

    try:
        with watchdog.keeping(keep):          # a run the watchdog ends keeps its record too
            run = api.run(scenario, out=out, plot=args.plot, animate=args.animate,
                          report=args.report, progress=True)
    except api.InaccurateRun as err:
        console.print_run(scenario.name, err.run, out)
        raise
    except Interrupted as err:
        if err.result is not None and err.kept is None:
            try:          # (a second signal now is not raised over this one: interrupt.py)
                err.kept = keep(err.result, err.reason)
            except Exception as why:     # unwritable, or a user's file in the way: said why
                err.kept = f"its record was not written: {console.explain(why, 'run')}"
        raise
    console.print_run(scenario.name, run, out)


def cmd_compare(args) -> None:
    scenario = _load_with_sets(args.scenario, args.set)
    figures = api.compare(scenario, rtol=args.rtol)
    print(f"{scenario.name} ({scenario.master}, step {scenario.step:g} s): "
          f"co-simulation vs monolithic solution")
    if args.rtol is None:
        console.print_side_by_side([(k, f["cosim"], f["monolithic"], f["difference"])
                             for k, f in figures.items()], "co-simulation", "monolithic")
        return
    loose = f"rtol {args.rtol:g}"
    print(f"  {'figure':22s} {'co-simulation':>14s} {loose:>14s} {'tight':>14s} "
          f"{'co-sim error':>13s} {loose + ' error':>17s}")
    for key, f in figures.items():
        print(f"  {key:22s} {console.cell(f['cosim'], 14)} {console.cell(f['monolithic_rtol'], 14)} "
              f"{console.cell(f['monolithic'], 14)} {console.cell(f['difference'], 13)} "
              f"{console.cell(f['rtol_error'], 17)}")


def cmd_sweep(args) -> None:
    from sewfmu.scenarios.runs.sweep import parse_grid_option

    scenario = _load_with_sets(args.scenario, args.set)
    grid = dict(parse_grid_option(g) for g in args.grid or [])
    out = Path(args.out) if args.out else Path("results") / f"{scenario.name}_sweep"
    try:
        sweep = api.sweep(scenario, grid, _set_values(args.set), workers=args.workers,
                          scheduler=args.scheduler, out=out, plot=args.plot, report=args.report,
                          progress=not args.quiet, results=args.results,
                          max_runs=args.max_runs)
        rows = sweep.rows
    except api.SweepFailed as err:
        rows = err.rows
        console.print_sweep(scenario.name, rows, out)
        raise
    console.print_sweep(scenario.name, rows, out)


def cmd_show(args) -> None:
    if args.parameters:
        sys.stdout.write(str(api.parameters(args.scenario)))
        return
    sys.stdout.write(api.show(args.scenario))


def cmd_export_ssp(args) -> None:
    from sewfmu.scenarios.interop.ssp_export import export

    scenario = _load_with_sets(args.scenario, args.set)
    print(export(scenario, Path(args.output)))


def cmd_export_fmu(args) -> None:
    from sewfmu.scenarios.fmu_build.up_to_date import fmus_for
    from sewfmu.scenarios.interop.export_fmu import export_fmu

    scenario = _load_with_sets(args.scenario, args.set)
    scenario.fmi = args.fmi            # the components of the FMI version of the container
    print(export_fmu(scenario, Path(args.output), fmus_for(scenario), fmi=args.fmi))


def cmd_references(args) -> None:
    if args.fmu:
        return _references_of_files(args)
    from sewfmu.scenarios.fmu_build.up_to_date import fmus_for_names
    from sewfmu.scenarios.references import regression as references

    paths = fmus_for_names(list(FMUS), fmi=args.fmi)
    folder = Path(args.refs) if args.refs else references.REFERENCE_DIR
    if args.regenerate:
        if args.fmi != 2:
            raise ScenarioError("--regenerate: the references are made with the FMI 2.0 FMUs "
                                "(the FMI 3.0 ones are checked against the same references)")
        for written in references.regenerate(paths, folder):
            print(f"wrote {written}")
        return
    from sewfmu.scenarios.references.reference_check import tolerance
    rtol, atol = tolerance(args.rtol, "--rtol"), tolerance(args.atol, "--atol")
    problems = [p for name in FMUS for p in references.check(name, paths[name], folder, rtol, atol)]
    for line in problems:
        print(line)
    if problems:
        raise ScenarioError(f"{len(problems)} differences from the regression references")
    print(f"all {len(FMUS)} FMI {args.fmi}.0 FMUs match their references")


def _references_of_files(args) -> None:
    """`sewfmu references --fmu PATH ...`: any FMU against its references (reference_check.py)."""
    from sewfmu.scenarios.references import (
        fmu_reference,
        reference_check,
    )

    if args.regenerate:
        if not args.refs:
            raise ScenarioError("--regenerate with --fmu writes into --refs DIR (sewfmu's own "
                                "references are rewritten by `sewfmu references --regenerate` "
                                "alone)")
        for fmu in args.fmu:
            print(f"wrote {reference_check.record(Path(fmu), Path(args.refs))}")
        return
    failing, drawn = 0, []
    for fmu in args.fmu:
        for outcome in reference_check.check(Path(fmu), args.refs, args.rtol, args.atol):
            for deviation in outcome.deviations:
                print(deviation)
            failing += len(outcome.deviations)
            if not outcome.deviations:
                print(f"{Path(fmu).name}: matches {outcome.reference.source}")
            elif args.plot:
                drawn.append((fmu, outcome))
    if drawn:
        from sewfmu.scenarios.files.outputs import replacing  # only when drawing

        folder = Path(args.plot)
        # in place of the last pictures written there, never over a file sewfmu did not write
        with replacing(folder) as staging:
            pictures = [fmu_reference.plot(Path(fmu).name, outcome.got, outcome.reference,
                                           outcome.deviations, fmu_reference.plot_file(
                                               staging, outcome.reference.model, fmu))
                        for fmu, outcome in drawn]
        for picture in pictures:
            print(f"wrote {folder / Path(picture).name}")
    if failing:
        raise ScenarioError(f"{failing} variables deviate from their references")


def cmd_host_env(args) -> None:
    from sewfmu.scenarios.interop.hosts import (
        check_host_environment,
        host_environment,
    )

    env = host_environment()
    print("# what a host that is not a Python process (the ecos tool, an FMI tool in C++ or")
    print("# Java) needs in its environment to run sewfmu's FMUs:")
    for key, value in env.items():
        print(f"export {key}={value}")
    if args.check:
        checked = dict(os.environ)
        checked.update({k: v for k, v in (("PYTHONHOME", args.home), ("LD_PRELOAD", args.preload))
                        if v})
        problems = check_host_environment(checked)
        if problems:
            raise ScenarioError("this environment cannot host the FMUs outside Python: "
                                + "; ".join(problems))
        print("# this environment has all of it")


def cmd_crosscheck(args) -> None:
    from sewfmu.scenarios.interop.cross_check import crosscheck

    scenario = _load_with_sets(args.scenario, args.set)
    out = Path(args.out) if args.out else Path("results") / f"{scenario.name}_{args.host}"
    rows = crosscheck(scenario, args.host, out)
    print(f"{scenario.name} (step {scenario.step:g} s): sewfmu's master beside {args.host}; "
          f"results in {out}/")
    console.print_side_by_side(rows, "sewfmu", args.host)


class _OneLineParser(argparse.ArgumentParser):
    """A bad option is one line and exit status 1, as every other refusal (argparse would print
    its usage block and exit 2); `sewfmu COMMAND --help` shows the usage."""

    def error(self, message: str):
        command = self.prog.removeprefix("sewfmu").strip()
        where = f"{command}: " if command else ""
        self.exit(1, f"sewfmu: error: {where}{message} (`sewfmu {command + ' ' if command else ''}"
                     f"--help` shows the options)\n")


# the commands that may call an FMU in this process (a sweep or study with one worker too)
GUARDED = {"run", "compare", "references", "crosscheck", "sweep", "optimize", "fit",
           "sensitivity"}


def main(argv=None, guard=None) -> int:
    """The command line. `guard` (the `sewfmu` console script's, sewfmu/__main__.py): run the
    command in a child this process waits for and guards (cosim/guardian.py); `guard` is what a
    signal does in the child until the command's own handlers are in place."""
    parser = _OneLineParser(prog="sewfmu", description="Sewing-machine mechanisms as "
                                     "FMI 2.0 and 3.0 co-simulation FMUs, and scenarios that connect them.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    parser.add_argument("--version", action="version", version=f"sewfmu {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("build", help="build every FMU into fmus/ (FMI 3.0: fmus/fmi3/)")
    p.add_argument("--dest", help="output folder (default: fmus/; with --fmi 3 its fmi3/)")
    p.add_argument("--fmi", type=_fmi_version, default=2,
                   help="FMI version of the FMUs (default 2)")
    p.add_argument("--native", action="store_true",
                   help="the native FMUs (C, no Python needed) into fmus/native/ (FMI 3.0: "
                        "fmus/native/fmi3/)")
    p.set_defaults(func=cmd_build)
    p = sub.add_parser("list", help="components and scenarios, one line each")
    p.set_defaults(func=cmd_list)
    for name, func, text in (("run", cmd_run, "run a scenario"),
                             ("compare", cmd_compare,
                              "co-simulation against the monolithic solution")):
        p = sub.add_parser(name, help=text)
        p.add_argument("scenario", help="catalogue name or path to a .toml file")
        p.add_argument("--set", action="append", metavar="INSTANCE.PARAM=VALUE",
                       help="override a parameter (or experiment.step, experiment.master, ...)")
        p.set_defaults(func=func)
        if name == "compare":
            p.add_argument("--rtol", type=_positive_number,
                           help="also run the monolithic solver at this relative tolerance, "
                                "both against a tight monolithic solution")
        if name == "run":
            p.add_argument("--out", help="output folder (default: results/SCENARIO/)")
            p.add_argument("--plot", action="store_true", help="write PNG figures")
            p.add_argument("--animate", action="store_true",
                           help="an animated GIF of the mechanism moving (last revolution)")
            p.add_argument("--report", action="store_true",
                           help="report.html: one self-contained page with figures, plots, "
                                "the animation and what was run")
    p = sub.add_parser("show", help="print a catalogue scenario as TOML, to save and change; "
                                    "or one of sewfmu's FMUs (PunchContact)")
    p.add_argument("scenario", help="catalogue name, path to a .toml file, or an FMU's name")
    p.add_argument("--parameters", action="store_true",
                   help="a table of the parameters: instance, parameter, default, value, unit, "
                        "declared range, meaning")
    p.set_defaults(func=cmd_show)
    p = sub.add_parser("export-ssp", help="the scenario as an SSP 1.0 archive for other tools")
    p.add_argument("scenario", help="catalogue name or path to a .toml file")
    p.add_argument("-o", "--output", required=True, help="the .ssp file to write")
    p.add_argument("--set", action="append", metavar="INSTANCE.PARAM=VALUE")
    p.set_defaults(func=cmd_export_ssp)
    p = sub.add_parser("export-fmu", help="the scenario as one co-simulation FMU for any FMI "
                                          "tool")
    p.add_argument("scenario")
    p.add_argument("-o", "--output", required=True, help="the FMU file to write (X.fmu)")
    p.add_argument("--fmi", type=_fmi_version, default=2,
                   help="the FMI version of the exported FMU and of the FMUs inside (default 2)")
    p.add_argument("--set", action="append", metavar="INSTANCE.PARAM=VALUE")
    p.set_defaults(func=cmd_export_fmu)
    p = sub.add_parser("crosscheck", help="run the scenario in another FMI host and compare")
    p.add_argument("scenario", help="catalogue name or path to a .toml file")
    p.add_argument("--host", required=True, choices=["libcosim", "ecos", "ecos-cli"],
                   help="libcosim and ecos in a child Python process; ecos-cli: the ecos "
                        "command-line tool, a host that is not Python")
    p.add_argument("--out", help="output folder (default: results/SCENARIO_HOST/)")
    p.add_argument("--set", action="append", metavar="INSTANCE.PARAM=VALUE")
    p.set_defaults(func=cmd_crosscheck)
    p = sub.add_parser("references", help="check FMUs against their regression references "
                                          "(sewfmu's own, or any FMU with --fmu)")
    p.add_argument("--fmu", action="append", metavar="PATH",
                   help="an FMU file (FMI 2.0 or 3.0, made by sewfmu or not); repeatable")
    p.add_argument("--refs", metavar="DIR",
                   help="a folder of references in the Cross-Check layout (<Model>/<Model>_ref.csv, "
                        "_ref.opt, _in.csv); without it: sewfmu's shipped references and the "
                        "reference the FMU carries (fmi-ls-ref)")
    p.add_argument("--regenerate", action="store_true",
                   help="record the references (with --fmu: into --refs DIR) instead of "
                        "checking them")
    p.add_argument("--rtol", type=float,
                   help="relative tolerance, of each variable's largest magnitude (default: "
                        "the reference's RelTol, else 1e-6)")
    p.add_argument("--atol", type=float, help="absolute tolerance (default 1e-12)")
    p.add_argument("--plot", nargs="?", const="results/references", metavar="DIR",
                   help="draw each deviating FMU's differences into DIR "
                        "(default results/references)")
    p.add_argument("--fmi", type=_fmi_version, default=2,
                   help="without --fmu: check sewfmu's FMUs of this FMI version (default 2)")
    p.set_defaults(func=cmd_references)
    p = sub.add_parser("host-env", help="the environment a non-Python FMI host needs")
    p.add_argument("--check", action="store_true",
                   help="check the current environment (or --home and --preload); one clear "
                        "line if something is missing")
    p.add_argument("--home", help="with --check: the Python home a host will be given (a home "
                                  "of another Python version cannot be exported to sewfmu's "
                                  "own process: Python would not start)")
    p.add_argument("--preload", help="with --check: the libpython a host will preload")
    p.set_defaults(func=cmd_host_env)
    p = sub.add_parser("sweep", help="a grid of co-simulations, in parallel")
    p.add_argument("scenario", help="catalogue name or path to a .toml file")
    p.add_argument("--set", action="append", metavar="INSTANCE.PARAM=VALUE",
                   help="override a parameter for every point")
    p.add_argument("--grid", action="append", metavar="INSTANCE.PARAM=V1,V2,...",
                   help="sweep this parameter over these values (adds to the file's grid); a "
                        "unit after the last applies to all (\"100,200 rpm\")")
    p.add_argument("--workers", type=console.whole_number, help="local worker processes (default: all "
                                                         "cores)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run on a Dask cluster, e.g. tcp://127.0.0.1:8786")
    p.add_argument("--out", help="output folder (default: results/SCENARIO_sweep/); an "
                                 "interrupted sweep into the same folder resumes")
    p.add_argument("--results", action="store_true", help="also keep each point's results.csv")
    console.max_runs_option(p)
    p.add_argument("--plot", action="store_true", help="plot the figures against the parameters")
    p.add_argument("--report", action="store_true",
                   help="report.html: what was run, the table of points and the plot")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_sweep)
    # the design studies' commands and the page's are added (their modules imported) unless the
    # command line names one of the commands above: `sewfmu run` does not load them; the
    # help, a misspelt command and their own commands find them all
    words = sys.argv[1:] if argv is None else list(argv)
    if next((w for w in words if not w.startswith("-")), None) not in sub.choices:
        _design_commands(sub)
    for stream in (sys.stdout, sys.stderr):
        # a terminal that is not UTF-8 gets escapes for ω or °, not a UnicodeEncodeError
        if hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")
    args = parser.parse_args(argv)
    if args.command == "run":
        _one_blas_thread()
    if guard is not None and args.command in GUARDED:
        # an FMU whose code holds the interpreter lock for ever leaves no thread of this process
        # able to end it: the `sewfmu` process the shell waits for does (and gives 130 or 143)
        watchdog.guarded_by_parent(guard_a_child(guard))
    # from here a signal stops the command cleanly (the start-up's handlers: sewfmu/__main__.py)
    interrupt_on_signals()
    # an FMU call that never returns: the watchdog ends this process with this command's line
    watchdog.end_process_with(lambda err: _end_stuck(err, args.command))
    # a warning (an SSP input that nothing sets) is one line, as errors are
    warnings.showwarning = lambda message, *_, **__: print(f"sewfmu: warning: {message}",
                                                           file=sys.stderr)
    try:
        args.func(args)
        sys.stdout.flush()
    except KeyboardInterrupt as err:
        settled()                           # said here: main() called by a process that goes on
        print(_interrupted_line(err, args.command), file=sys.stderr)
        return err.exit_status if isinstance(err, Interrupted) else 130
    except BrokenPipeError:
        # the reader went away (`sewfmu list | head -1`): stop quietly, as other tools do
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except Exception as err:        # one clear line for the user; --debug for the traceback
        if args.debug:
            raise
        print(f"sewfmu: error: {console.explain(err, args.command)}", file=sys.stderr)
        return 1
    finally:
        watchdog.end_process_with(None)     # main() called by a process that goes on
    return 0


def _interrupted_line(err: KeyboardInterrupt, command: str) -> str:
    """`sewfmu: interrupted (SIGINT) at t = 0.25 s; the record up to … is in …`: the signal, where
    the run was, and what is kept."""
    reason = err.reason if isinstance(err, Interrupted) else "interrupted (SIGINT)"
    kept = getattr(err, "kept", None) or (
        "the points finished so far are kept: the same command resumes"
        if command in ("sweep", "optimize", "fit", "sensitivity")
        else "nothing of the interrupted run was written")
    return f"sewfmu: {reason}; {kept}"


def _end_stuck(err: BaseException, command: str) -> None:
    """The watchdog's way out of an FMU call that never returns (scenarios/cosim/watchdog.py):
    the line this command says for `err` (an Interrupted, or a step beyond
    experiment.step_timeout), then the process ends at once (the call cannot be unwound)."""
    if getattr(sys.stderr, "isatty", lambda: False)():
        sys.stderr.write("\r\033[K")            # over a progress line
    if isinstance(err, Interrupted):
        line, status = _interrupted_line(err, command), err.exit_status
    else:
        line, status = f"sewfmu: error: {console.explain(err, command)}", 1
    sys.stderr.write(line + "\n")
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(status)


# what a user sets to choose OpenBLAS's threads (numpy's and scipy's BLAS)
BLAS_THREAD_SETTINGS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "GOTO_NUM_THREADS")


def _one_blas_thread() -> None:
    """numpy's OpenBLAS starts a thread per core when numpy is imported, and each busy-waits
    for work about 0.1 s of CPU; a run does no linear algebra (its models are plain Python, its
    figures interpolations of the records), so it asks for one thread, before the run path
    imports numpy, unless the user chose."""
    if "numpy" not in sys.modules and not any(k in os.environ for k in BLAS_THREAD_SETTINGS):
        os.environ["OPENBLAS_NUM_THREADS"] = "1"


def _fmi_version(text: str) -> int:
    if text.strip() in ("2", "2.0", "3", "3.0"):
        return int(float(text))
    raise argparse.ArgumentTypeError(f"the FMI version is 2 or 3, got {text!r}")


def _positive_number(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not 0.0 < value < 1.0:
        raise argparse.ArgumentTypeError(f"expected a relative tolerance between 0 and 1, "
                                         f"got {text}")
    return value


def _design_commands(sub) -> None:
    """optimize, fit, sensitivity (sewfmu/design_cli.py); app, the page (sewfmu/app/command.py)."""
    from sewfmu.design_cli import add_commands  # a module of their own: this one's size

    add_commands(sub)
    from sewfmu.app.command import add_command  # the page's command: its own package

    add_command(sub)


if __name__ == "__main__":
    sys.exit(main())
