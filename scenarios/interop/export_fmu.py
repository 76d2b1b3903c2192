"""A scenario as one co-simulation FMU, for FMI tools that know neither Python FMUs nor SSP: the
punch drive dropped in as one block.

Built on fmpy's container FMU: its C library (binaries/) instantiates the scenario's FMUs, found
under resources/, steps them at one fixed internal step and passes every connected output to its
input after each step, in the order of the connections (a direct-feedthrough output reaches the
next FMU within the same step, as sewfmu's Jacobi master does). The container exposes, under
`instance.variable` names, every parameter of every instance (start: the scenario's value, else
the FMU's default) and the scenario's recorded outputs; its DefaultExperiment is the scenario's,
a whole number of even steps.

With experiment.fmus = "native" the FMUs inside are sewfmu's native FMUs (compiled C, of the
container's FMI version): the container then holds no Python code at all, and its host needs no
Python (checked here before it is written: `_refuse_python_inside`).

Otherwise the FMUs inside are sewfmu's Python FMUs: a host needs what they need (libpython
loaded, a Python home; docs/fmi.md). They are their FMI 3.0 builds whatever the container's
version: the
container library hands an FMI 2.0 component the address of a callbacks struct on its own stack,
which pythonfmu keeps and calls through at its next log line, after the struct is gone (the
segmentation fault of every bad parameter with logging on; FMI 3.0 passes the callback by
value). Inside the container they log their errors with logging off too: it is their only way
to the host (components/fmi3_layer.py).

Nothing is exported that `sewfmu run` refuses: the scenario's parameters are checked against the
declared ranges, and the scenario is then run once by sewfmu's own master on the very FMUs the
container holds (a bad parameter an FMU itself refuses, a Jacobi step that diverges). The
container steps at a fixed step, as the Jacobi master does: scenarios run by the iterative or
adaptive master are refused unless exported for Jacobi.
"""
from __future__ import annotations

import html
import json
import shutil
import sys
import tempfile
import uuid
import zipfile
from pathlib import Path
from xml.etree import ElementTree

from sewfmu.components.registry import FMUS
from sewfmu.errors import Error
from sewfmu.scenarios.cosim.algorithms import FIXED_STEP
from sewfmu.scenarios.cosim.fmi_calls import kind_of
from sewfmu.scenarios.cosim.master import run
from sewfmu.scenarios.cosim.system import check_parameters
from sewfmu.scenarios.files.outputs import OutputError
from sewfmu.scenarios.fmu_build.native_current import build_of, without_windows_line
from sewfmu.scenarios.fmu_build.sources import current_version
from sewfmu.scenarios.fmu_build.up_to_date import fmus_for_names
from sewfmu.scenarios.format.fmu_file import model_description
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import ScenarioError

# FMI 3.0's words for FMI 2.0's types (the container's library uses them whatever its version)
_FMI3_TYPES = {"Real": "Float64", "Integer": "Int32"}


def export_fmu(scenario: Scenario, output: Path, fmu_paths: dict[str, Path],
               fmi: int = 2) -> Path:
    """Write the scenario as one co-simulation FMU (FMI 2.0, or 3.0) to `output`."""
    from fmpy.container_fmu.cli import create_container_fmu  # fmpy: only when an FMU file is read
    from fmpy.container_fmu.config import (  # fmpy: only when an FMU file is read
        Component,
        Configuration,
        Connection,
    )

    output = _checked_output(Path(output))
    if scenario.master not in FIXED_STEP:
        raise ScenarioError(f"{scenario.source}: the exported FMU steps its components at a "
                            f"fixed step (Jacobi); this scenario runs with the {scenario.master} "
                            f"master: export it with --set experiment.master=\"jacobi\" (and a "
                            f"step it is stable at)")
    if fmi not in (2, 3):
        raise ScenarioError(f"--fmi: the FMI version of the exported FMU, 2 or 3, got {fmi!r}")
    n, h = scenario.even_steps()
    stop = scenario.end_time()
    if scenario.fmus == "native":
        _refuse_python_inside(scenario, fmu_paths)
    inside = _components_inside(scenario, fmu_paths)
    if scenario.fmus == "native" and (line := without_windows_line(inside, "export-fmu")):
        print(f"sewfmu: {line}", file=sys.stderr)
    described = {name: model_description(path, "", validate=False)
                 for name, path in inside.items()}
    # what `sewfmu run` refuses before any FMU runs, then what it refuses running
    check_parameters(scenario, {i.name: described[i.fmu] for i in scenario.instances.values()})
    _refused_by_run(scenario, inside)
    components, variables, units = {}, {}, {}
    for inst in scenario.instances.values():
        md = described[inst.fmu]
        components[inst.name] = Component(name=inst.name, filename=Path(inside[inst.fmu]),
                                          modelDescription=md)
        variables[inst.name] = {v.name: v for v in md.modelVariables}
        units.update({u.name: u for u in md.unitDefinitions})
    exposed, mappings = _exposed(scenario, components, variables, fmi)
    connections = [Connection(components[c.src], [variables[c.src][c.src_var]],
                              components[c.dst], [variables[c.dst][c.dst_var]])
                   for c in scenario.connections]
    description = _description(scenario, fmi, stop, h, exposed, list(units.values()))
    config = Configuration(parallelDoStep=False, modelDescription=description,
                           components=list(components.values()), connections=connections,
                           variableMappings=mappings)
    with tempfile.TemporaryDirectory(prefix="sewfmu_export_") as work:
        built, tree = Path(work) / "container.fmu", Path(work) / "tree"
        tree.mkdir()                     # fmpy removes and makes it again
        create_container_fmu(config, tree, built)
        try:
            _finish(built, output, scenario, exposed)
        except OSError as err:             # the folder named: not the temporary beside it
            raise OutputError(f"-o {output}: cannot write there: {err.strerror or err}") \
                from None
    return output


def _components_inside(scenario: Scenario, fmu_paths: dict[str, Path]) -> dict[str, Path]:
    """The FMU file of each FMU type the container holds: FMI 3.0 ones, as given, or sewfmu's
    FMI 3.0 build of a sewfmu FMI 2.0 FMU (built beside it, in fmi3/, where missing). An FMI 2.0
    FMU of pythonfmu's crashes the container's host at its first log line with logging on (see
    the module docstring): one of another version of sewfmu, or not sewfmu's, is refused."""
    inside = {}
    for name in sorted({inst.fmu for inst in scenario.instances.values()}):
        path = Path(fmu_paths[name])
        md = model_description(path, "", validate=False)
        if md.fmiVersion.startswith("3") or \
                not (md.generationTool or "").startswith("PythonFMU"):
            inside[name] = path
        elif name in FMUS and md.version == current_version():
            inside[name] = fmus_for_names([name], path.parent, fmi=3)[name]
        else:
            raise ScenarioError(f"{scenario.source}: {name} ({path}) is an FMI 2.0 FMU made with "
                                f"pythonfmu, not this sewfmu's: fmpy's container FMU would crash "
                                f"its host at the FMU's first log line with logging on "
                                f"(docs/fmi.md); give the FMI 3.0 version of the FMU")
    return inside


def _refuse_python_inside(scenario: Scenario, inside: dict[str, Path]) -> None:
    """A container of native FMUs needs no Python: one FMU in it that carries Python code (an
    FMU file the scenario names itself) is refused in one line, before anything is written."""
    python = [name for name, path in sorted(inside.items()) if build_of(path) != "native"]
    if python:
        raise ScenarioError(f"{scenario.source}: experiment.fmus = \"native\" exports a "
                            f"container that needs no Python, but {python[0]} "
                            f"({inside[python[0]]}) carries Python code")


def _refused_by_run(scenario: Scenario, fmu_paths: dict[str, Path]) -> None:
    """Run the scenario once with sewfmu's own master on the container's FMUs: what that run
    refuses (a parameter an FMU refuses at initialization, a Jacobi step at which a feedback
    loop diverges), the export refuses, in the run's words. The whole run, not a few steps: a
    coupling diverges when it does (punch_split at a 2 ms step: after 19 steps), and the
    catalogue's scenarios run in under a second."""
    try:
        run(scenario, fmu_paths)
    except Error as err:
        raise ScenarioError(f"{scenario.source}: not exported, `sewfmu run` refuses it: "
                            f"{err}") from None


def _checked_output(output: Path) -> Path:
    if output.suffix != ".fmu":
        raise ScenarioError(f"-o {output}: the exported file is an FMU: give a name ending in .fmu")
    if output.is_dir():
        raise ScenarioError(f"-o {output}: is a folder")
    if not output.parent.exists():
        raise ScenarioError(f"-o {output}: the folder {output.parent} does not exist")
    return output


def _exposed(scenario: Scenario, components: dict, variables: dict, fmi: int):
    """The container's variables (besides time) and what each maps to: every parameter of every
    instance, every input no connection sets, and the recorded outputs."""
    from fmpy.model_description import ModelVariable  # fmpy: only when an FMU file is read

    exposed, mappings = [], {}

    def expose(instance: str, v, kind: str, **role) -> None:
        # the component's declared range goes with its parameters and inputs: a host that
        # checks min and max refuses a bad value before the component has to
        limits = {} if role["causality"] == "output" else {"min": v.min, "max": v.max}
        var = ModelVariable(name=f"{instance}.{v.name}", type=_typed(kind, fmi), unit=v.unit,
                            description=v.description, **limits, **role)
        exposed.append(var)
        mappings[var] = [(components[instance], v)]

    connected = {(c.dst, c.dst_var) for c in scenario.connections}
    for name in scenario.instances:
        given = scenario.instances[name].parameters
        for v in variables[name].values():
            kind = kind_of(v)
            if v.causality == "input" and (name, v.name) not in connected and kind == "Real":
                # an input the scenario leaves unconnected: the FMU's input, starting at the
                # scenario's value (or the FMU's start), for the host to drive
                expose(name, v, kind, causality="input", variability="continuous",
                       start=_start(given.get(v.name, v.start), kind))
            elif v.causality == "parameter" and kind in ("Real", "Integer"):
                expose(name, v, kind, causality="parameter", variability="fixed",
                       initial="exact", start=_start(given.get(v.name, v.start), kind))
    for column in _recorded(scenario, variables):
        name, _, var_name = column.partition(".")
        v = variables[name][var_name]
        kind = kind_of(v)
        expose(name, v, kind, causality="output", initial="calculated",
               variability="discrete" if kind == "Boolean" else "continuous")
    return exposed, mappings


def _typed(kind: str, fmi: int) -> str:
    """A type in the words of the container's FMI version (FMI 3.0: Float64, Int32)."""
    return _FMI3_TYPES.get(kind, kind) if fmi == 3 else kind


def _recorded(scenario: Scenario, variables: dict) -> list[str]:
    if scenario.record is not None:
        return list(scenario.record)
    return [f"{name}.{v.name}" for name, vs in variables.items() for v in vs.values()
            if v.causality == "output" and kind_of(v) in ("Real", "Integer", "Boolean")]


def _start(value, kind: str) -> str:
    return repr(int(float(value))) if kind == "Integer" else repr(float(value))


def _description(scenario: Scenario, fmi: int, stop: float, step: float, exposed: list,
                 units: list):
    from fmpy.model_description import (
        CoSimulation,
        DefaultExperiment,
        ModelDescription,
        ModelVariable,
        Unknown,
    )  # fmpy: only when an FMU file is read

    # the container's value reference 0 is the time; FMI 2.0 has no independent variable in
    # co-simulation (and FMI Library refuses one without a start), so there it is a local
    time = ModelVariable(name="time", type=_typed("Real", fmi), variability="continuous",
                         description="simulation time",
                         **({"causality": "independent"} if fmi == 3 else
                            {"causality": "local", "initial": "calculated"}))
    token = "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, f"sewfmu:{scenario.name}:"
                                                     f"{scenario.digest}:{stop!r}:{step!r}")) + "}"
    outputs = [v for v in exposed if v.causality == "output"]
    return ModelDescription(
        fmiVersion="3.0" if fmi == 3 else "2.0", modelName=scenario.name,
        outputs=[Unknown(variable=v) for v in outputs],
        initialUnknowns=[Unknown(variable=v) for v in outputs],
        instantiationToken=token, description=scenario.description or scenario.name,
        generationTool="sewfmu export-fmu (fmpy container FMU)",
        defaultExperiment=DefaultExperiment(startTime="0.0", stopTime=repr(stop),
                                            stepSize=repr(step)),
        coSimulation=CoSimulation(fixedInternalStepSize=step), unitDefinitions=units,
        modelVariables=[time, *exposed])


def _finish(built: Path, output: Path, scenario: Scenario, exposed: list) -> None:
    """The container's configuration in the container library's types (fmpy writes FMI 2.0
    components' connections as Real), its variables with their declared ranges (fmpy writes
    an FMI 3.0 variable's min and max not), without the stray archive fmpy leaves in it;
    written next to `output` first and then moved, so that a reader never sees half a file."""
    staged = output.with_name(f".{output.name}.partial")
    with zipfile.ZipFile(built) as source, \
            zipfile.ZipFile(staged, "w", zipfile.ZIP_DEFLATED) as target:
        for item in source.infolist():
            if item.filename == "Container.zip":
                continue
            data = source.read(item)
            if item.filename == "modelDescription.xml":
                data = _with_ranges(data, exposed)
            if item.filename == "resources/container.json":
                config = json.loads(data)
                for key in ("connections", "variables"):
                    for entry in config[key]:
                        entry["variableType"] = _typed(entry["variableType"], 3)
                data = json.dumps(config, indent=1).encode()
            target.writestr(item, data)
        target.writestr("documentation/index.html", _documentation(scenario))
    shutil.move(staged, output)


def _with_ranges(xml: bytes, exposed: list) -> bytes:
    """The modelDescription with every exposed variable's min and max where fmpy left them
    out (an FMI 2.0 one has them already: unchanged)."""
    limits = {v.name: (v.min, v.max) for v in exposed if v.min is not None or v.max is not None}
    root = ElementTree.fromstring(xml)
    if root.get("fmiVersion", "").startswith("2"):     # on the ScalarVariable's type element
        return xml
    missing = [e for e in root.find("ModelVariables")
               if e.get("name") in limits and e.get("min") is None and e.get("max") is None]
    if not missing:
        return xml
    for element in missing:
        for key, value in zip(("min", "max"), limits[element.get("name")]):
            if value is not None:
                element.set(key, str(value))
    return ElementTree.tostring(root, encoding="UTF-8", xml_declaration=True)


def _documentation(scenario: Scenario) -> str:
    # every text of the scenario is escaped: a description is the user's text, and a page
    # a browser opens runs whatever <script> it holds
    name = html.escape(scenario.name)
    fmus = html.escape(", ".join(sorted({i.fmu for i in scenario.instances.values()})))
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{name}</title>"
            f"</head><body><h1>{name}</h1><p>{html.escape(scenario.description or '')}</p>"
            f"<p>sewfmu's scenario {name} as one co-simulation FMU (fmpy's container "
            f"FMU): {fmus} stepped at a fixed step. {_needs(scenario)}</p>"
            f"</body></html>\n")


def _needs(scenario: Scenario) -> str:
    """What the container's host needs, by the build of the FMUs inside."""
    if scenario.fmus == "native":
        return ("The FMUs inside are native FMUs (compiled C, binaries for Linux x86-64 and "
                "Windows x86-64): the host needs no Python.")
    return ("The FMUs inside are Python FMUs (pythonfmu3): the host process needs libpython "
            "loaded and a Python home (3.10 to 3.13, the standard library only), on Linux "
            "x86-64 (win64 binaries untried).")
