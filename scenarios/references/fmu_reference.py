"""Regression references of any co-simulation FMU (FMI 2.0 or 3.0, made by sewfmu or not):
recorded, read and checked.

Two layouts are read and written:
- FMI Cross-Check (a folder of the user's, and sewfmu's own shipped references):
  `<Model>/<Model>_ref.csv` (time and the outputs), `<Model>_ref.opt` (StartTime, StopTime,
  StepSize, RelTol) and `<Model>_in.csv` (the inputs over time) where the run had inputs;
- fmi-ls-ref, inside the FMU (as the Modelica Reference-FMUs carry it): a manifest naming the
  CSV output of the FMU's default experiment (scenarios/fmu_build/carried_reference.py writes it for
  sewfmu's FMUs).

A check runs the FMU as the reference was made (its time grid, its inputs) and compares every
variable of the reference: a variable deviates where |value - reference| exceeds
atol + rtol · (largest |reference| of that variable), and the first such time is reported with
both values. An FMU is judged by its outputs, whatever its version or build hash says.

Every file read, and every name or number taken from inside an FMU, is checked as user input
first (reference_files.py): one line naming the file and what is wrong, never a run that fails
without saying why, runs for ever, or writes outside the folder given.
"""
from __future__ import annotations

import csv
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np

from sewfmu.scenarios.cosim import (
    guardian,
    interrupt,
    watchdog,
)
from sewfmu.scenarios.cosim.fmi_calls import LogCollector, Status
from sewfmu.scenarios.cosim.instances import open_instance
from sewfmu.scenarios.files.matplotlib_home import pyplot
from sewfmu.scenarios.format.fmu_file import model_description
from sewfmu.scenarios.format.values import ScenarioError
from sewfmu.scenarios.references.reference_files import (
    check_experiment,
    inside,
    number,
    parse_csv,
    plain_name,
    read_options,
    shown,
)

LS_REF = "extra/org.fmi-standard.fmi-ls-ref"
MANIFEST = f"{LS_REF}/fmi-ls-manifest.xml"
DEFAULT_RTOL = 1e-6
DEFAULT_ATOL = 1e-12


@dataclass
class Experiment:
    """How the FMU runs for a reference: from start to stop, its outputs every `step`, its
    inputs (a structured array with a time column) or none (start values)."""
    start: float
    stop: float
    step: float
    inputs: np.ndarray | None = None
    rel_tol: float = DEFAULT_RTOL


@dataclass
class Reference:
    model: str
    source: str                               # where it was read, for messages
    columns: dict[str, np.ndarray]            # "time" and each variable, as numbers
    experiment: Experiment
    not_compared: list[str] = field(default_factory=list)   # text columns (String, Binary)


@dataclass
class Deviation:
    model: str
    variable: str
    time: float | None = None
    value: float | None = None
    expected: float | None = None
    allowed: float | None = None
    why: str = ""

    def __str__(self) -> str:
        if self.why:
            return f"{self.model}: {self.variable}: {self.why}"
        return (f"{self.model}: {self.variable} leaves the tolerance at t = {self.time:g} s: "
                f"{self.value:.10g}, the reference {self.expected:.10g} "
                f"(allowed ±{self.allowed:.3g})")


# --- reading ----------------------------------------------------------------------------------
def _table(columns: dict[str, np.ndarray]) -> np.ndarray:
    table = np.zeros(len(columns["time"]), dtype=[(n, float) for n in columns])
    for name, values in columns.items():
        table[name] = values
    return table


def cross_check_folder(refs: Path, model: str) -> Path:
    """Where a model's reference lives in a Cross-Check folder: refs/<Model>/, or refs itself
    when it holds <Model>_ref.csv directly."""
    refs = Path(refs)
    model = plain_name(model, refs)
    return refs if (refs / f"{model}_ref.csv").is_file() else refs / model


def read_cross_check(refs: Path, model: str) -> Reference | None:
    """The reference recorded in refs for the model, every file checked (reference_files.py);
    None if there is none."""
    folder = cross_check_folder(refs, model)
    result = folder / f"{model}_ref.csv"
    if not result.is_file():
        return None
    columns, skipped = parse_csv(result.read_bytes(), result)
    opt = folder / f"{model}_ref.opt"
    options = read_options(opt) if opt.is_file() else {}
    times = columns["time"]
    inputs_file = folder / f"{model}_in.csv"
    inputs = _table(parse_csv(inputs_file.read_bytes(), inputs_file, inputs=True)[0]) \
        if inputs_file.is_file() else None
    experiment = Experiment(options.get("StartTime", float(times[0])),
                            options.get("StopTime", float(times[-1])),
                            options.get("StepSize", _grid_step(times)), inputs,
                            options.get("RelTol", DEFAULT_RTOL))
    check_experiment(f"{opt} (with {result.name})" if opt.is_file() else result,
                     experiment.start, experiment.stop, experiment.step, experiment.rel_tol, times)
    return Reference(model, str(result), columns, experiment, skipped)


def _attribute(fmu: Path, name: str, text) -> float | None:
    """A DefaultExperiment attribute (fmpy gives the XML's text), None where it is not given."""
    if text is None or not str(text).strip():
        return None
    value = number(str(text))
    if value is None:
        raise ScenarioError(f"{fmu}: modelDescription.xml: DefaultExperiment {name}="
                            f"{shown(str(text))}; a number")
    return value


def read_carried(fmu: Path) -> Reference | None:
    """The reference an FMU carries (fmi-ls-ref), run as its default experiment; None if it
    carries none."""
    try:
        with zipfile.ZipFile(fmu) as archive:
            if MANIFEST not in archive.namelist():
                return None
            root = ET.fromstring(archive.read(MANIFEST))
            sources = [r.get("source") for r in root.iter() if r.tag.endswith("Related")
                       and r.get("role") == "result"
                       and (r.get("type") or "text/csv") == "text/csv"]
            if not sources or f"{LS_REF}/{sources[0]}" not in archive.namelist():
                return None
            raw = archive.read(f"{LS_REF}/{sources[0]}")
    except ET.ParseError as err:
        raise ScenarioError(f"{fmu}: {MANIFEST}: not XML ({err})") from None
    except (zipfile.BadZipFile, zlib.error, EOFError, OSError) as err:
        raise ScenarioError(f"{fmu}: its reference cannot be read from the archive "
                            f"({' '.join(str(err).split())})") from None
    where = f"{fmu}: {shown(sources[0], 80)}"
    columns, skipped = parse_csv(raw, where)
    md = model_description(fmu, "", validate=False)
    times = columns["time"]
    default = md.defaultExperiment
    step = _attribute(fmu, "stepSize", default.stepSize if default is not None else None)
    experiment = Experiment(float(times[0]), float(times[-1]),
                            _grid_step(times) if step is None else step)
    check_experiment(f"{where} with the DefaultExperiment's stepSize", experiment.start,
                     experiment.stop, experiment.step, experiment.rel_tol, times)
    return Reference(md.modelName, f"{fmu.name} ({sources[0]}, fmi-ls-ref)", columns, experiment,
                     skipped)


def _grid_step(times: np.ndarray) -> float:
    steps = np.diff(times)
    return float(np.median(steps[steps > 0])) if np.any(steps > 0) else 1.0


# --- running and comparing --------------------------------------------------------------------
def simulate(fmu: Path, experiment: Experiment, variables: list[str] | None = None) -> dict:
    """The FMU run as the experiment says: {"time": ..., variable: ...}. The instance is made
    and freed by sewfmu (fmpy would unload the library, unsafe for pythonfmu's)."""
    from fmpy import simulate_fmu  # fmpy: only when an FMU file is read


    log = LogCollector()
    instance = open_instance("reference", Path(fmu), log)
    known = {v.name for v in instance.md.modelVariables}
    wanted = [v for v in (variables or [v.name for v in instance.md.modelVariables
                                        if v.causality == "output"]) if v in known]
    instance.prepare()
    # Ctrl-C stops the run between two steps, as a scenario's; a call that never returns is the
    # watchdog's (any FMU, a supplier's too)
    steps = watchdog.Steps(experiment.start)

    def step_finished(time: float, recorder) -> bool:
        steps.t, steps.k = time, steps.k + 1
        # where the run is, for the guardian of a process whose FMU holds the GIL
        paper = watchdog.board()
        if steps.k == 1:
            paper.names(["reference"])
        paper.q[guardian.BEAT] += 1
        paper.q[guardian.WHERE], paper.d[guardian.T] = guardian.CODE["doStep"], time
        interrupt.raise_pending()
        return True

    try:
        instance.instantiate()
        with interrupt.deferred(), watchdog.watching(steps):
            result = simulate_fmu(str(fmu), start_time=experiment.start,
                                  stop_time=experiment.stop, output_interval=experiment.step,
                                  step_size=experiment.step, input=experiment.inputs,
                                  output=wanted, validate=False, fmu_instance=instance.fmu,
                                  terminate=False, step_finished=step_finished)
    except Exception as err:      # noqa: BLE001 - a failed run is a finding, said in one line
        # after Fatal (fmpy's own calls raise fmpy's exception) no call may follow, not even
        # freeing the instance
        instance.failed = instance.failed or getattr(err, "status", 0) >= Status.FATAL
        errors = [line for line in log.lines if line.startswith(("[ERROR]", "[FATAL]"))]
        raise ScenarioError(f"{instance.md.modelName}: the run for its reference failed: "
                            f"{errors[-1] if errors else err}") from None
    finally:
        if instance.instantiated and not instance.failed:
            instance.release()
    return {name: np.asarray(result[name], dtype=float) for name in result.dtype.names}


def compare(model: str, got: dict, reference: Reference, rtol: float | None = None,
            atol: float = DEFAULT_ATOL) -> list[Deviation]:
    """Every variable of the reference that the run does not reproduce within the tolerance."""
    rtol = reference.experiment.rel_tol if rtol is None else rtol
    deviations = []
    t_ref, t_got = reference.columns["time"], got["time"]
    same_grid = len(t_got) == len(t_ref) and np.allclose(t_got, t_ref, rtol=0,
                                                         atol=1e-9 * max(1.0, abs(t_ref[-1])))
    for name, expected in reference.columns.items():
        if name == "time":
            continue
        if name not in got:
            deviations.append(Deviation(model, name, why="the FMU has no such variable now"))
            continue
        value = got[name] if same_grid else np.interp(t_ref, t_got, got[name])
        if np.any(off := _off(value, expected, rtol, atol)):
            allowed = _allowed(expected, rtol, atol)
            k = int(np.argmax(off))
            deviations.append(Deviation(model, name, float(t_ref[k]), float(value[k]),
                                        float(expected[k]), allowed))
    return deviations


def _allowed(expected: np.ndarray, rtol: float, atol: float) -> float:
    # the scale is the largest finite |reference|: one nan or inf in the reference would make
    # the tolerance nan or inf, and then no difference anywhere would exceed it
    finite = expected[np.isfinite(expected)]
    return atol + rtol * (float(np.max(np.abs(finite))) if len(finite) else 0.0)


def _off(value: np.ndarray, expected: np.ndarray, rtol: float, atol: float) -> np.ndarray:
    """Where the value leaves the tolerance. A nan or inf of the reference is a value to
    reproduce: only nan matches nan, only the same inf matches inf (a nan of the reference where
    the FMU gives a number is a deviation, not a gap in the comparison)."""
    with np.errstate(invalid="ignore", over="ignore"):
        differs = np.abs(value - expected) > _allowed(expected, rtol, atol)
        same = (value == expected) | (np.isnan(value) & np.isnan(expected))
    return np.where(np.isfinite(value) & np.isfinite(expected), differs, ~same)


def run_and_compare(fmu: Path, reference: Reference, rtol: float | None = None,
                    atol: float = DEFAULT_ATOL) -> tuple[dict, list[Deviation]]:
    """The FMU run as the reference was made, and its deviations from it."""
    variables = [n for n in reference.columns if n != "time"]
    got = simulate(fmu, reference.experiment, variables)
    return got, compare(reference.model, got, reference, rtol, atol)


def check(fmu: Path, reference: Reference, rtol: float | None = None,
          atol: float = DEFAULT_ATOL) -> list[Deviation]:
    return run_and_compare(fmu, reference, rtol, atol)[1]


# --- recording --------------------------------------------------------------------------------
def default_experiment(fmu: Path) -> Experiment:
    """The FMU's DefaultExperiment (a step of a 500th of the run where it gives none)."""
    md = model_description(fmu, "", validate=False)
    default = md.defaultExperiment
    given = {name: _attribute(fmu, name, getattr(default, name, None))
             for name in ("startTime", "stopTime", "stepSize")}
    start = 0.0 if given["startTime"] is None else given["startTime"]
    stop = 1.0 if given["stopTime"] is None else given["stopTime"]
    step = (stop - start) / 500 if given["stepSize"] is None else given["stepSize"]
    # the numbers come from inside the FMU: a stopTime of 1e12 would run for ever
    check_experiment(f"{fmu}: modelDescription.xml: DefaultExperiment", start, stop, step,
                     DEFAULT_RTOL)
    return Experiment(start, stop, step)


def write_csv(path: Path, columns: dict[str, np.ndarray]) -> None:
    names = list(columns)
    with open(path, "w", newline="", encoding="utf-8") as out:
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(names)
        for row in zip(*(columns[n] for n in names)):
            writer.writerow([repr(float(x)) for x in row])


def record(fmu: Path, refs: Path, experiment: Experiment | None = None,
           model: str | None = None) -> Path:
    """Run the FMU (its DefaultExperiment, or `experiment`) and write its reference into
    refs/<Model>/ in the Cross-Check layout."""
    # the modelName is data from inside the FMU, never a path: a plain name, and every file
    # checked to stay inside refs before anything runs or is written
    refs = Path(refs)
    model = plain_name(model or model_description(fmu, "", validate=False).modelName, fmu)
    experiment = experiment or default_experiment(fmu)
    check_experiment(f"{fmu}: the run to record", experiment.start, experiment.stop,
                     experiment.step, experiment.rel_tol)
    folder = inside(refs, refs / model, fmu)
    result, inputs, options = (inside(refs, folder / f"{model}{suffix}", fmu)
                               for suffix in ("_ref.csv", "_in.csv", "_ref.opt"))
    got = simulate(fmu, experiment)
    folder.mkdir(parents=True, exist_ok=True)
    write_csv(result, got)
    if experiment.inputs is not None:
        write_csv(inputs, {n: experiment.inputs[n] for n in experiment.inputs.dtype.names})
    options.write_text(f"StartTime, {experiment.start!r}\nStopTime, {experiment.stop!r}\n"
                       f"StepSize, {experiment.step!r}\nRelTol, {experiment.rel_tol!r}\n",
                       encoding="utf-8")
    return folder


def plot_file(folder: Path, model: str, where) -> Path:
    """Where the picture of a model's deviations goes: inside `folder`, whatever the modelName
    (from inside the FMU) says."""
    return inside(folder, Path(folder) / f"{plain_name(model, where)}_differences.png", where)


def plot(fmu_name: str, got: dict, reference: Reference, deviations: list[Deviation],
         path: Path) -> Path:
    """The deviating variables against their reference, and the differences."""
    plt = pyplot()          # matplotlib, its files out of the user's home

    names = [d.variable for d in deviations if not d.why][:6]
    fig, axes = plt.subplots(len(names), 2, figsize=(10, 2.6 * len(names)), squeeze=False)
    t = reference.columns["time"]
    for (left, right), name in zip(axes, names):
        value = np.interp(t, got["time"], got[name])
        left.plot(t, reference.columns[name], label="reference")
        left.plot(t, value, "--", label=fmu_name)
        left.set_ylabel(name)
        left.legend(fontsize=7)
        right.plot(t, value - reference.columns[name])
        right.set_ylabel(f"{name}: difference")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path
