"""Read an SSP 1.0 system (an .ssp archive, or an .ssd file beside its FMUs) as a scenario, whoever
wrote it, so that `sewfmu run`, `sweep` and `compare` run it as they run a TOML scenario.

- components: each ssd:Component with an FMU source (in the archive, or relative to the .ssd);
  any FMU runs, sewfmu's or not. An instance's FMU type is the FMU's modelName, so a system
  holding sewfmu's FMUs gets their analysis (a PunchContact, a PunchLinkage and a MainShaft: the
  punch figures) whatever its components are called.
- connections: ssd:Connection between two components' connectors; the master checks them as it
  checks a TOML scenario's (the variables exist, inputs have one source, units agree).
- parameters: every ssd:ParameterBinding of a component, inline (ssv:ParameterSet, any name) or
  from a referenced .ssv file, with its prefix if it has one.
- time: the DefaultExperiment's stopTime is the run's end; the communication step comes from the
  annotation sewfmu writes (ssc:Annotation type="org.sewfmu.experiment", attribute step) or from
  `--set experiment.step=…`.
"""
from __future__ import annotations

import atexit
import hashlib
import os
import re
import shutil
import stat
import tempfile
from pathlib import Path
from xml.etree import ElementTree as ET

from sewfmu.components.parameters import did_you_mean
from sewfmu.scenarios.files import archives
from sewfmu.scenarios.format.experiment import EXPERIMENT_KEYS
from sewfmu.scenarios.format.fmu_file import model_description
from sewfmu.scenarios.format.parse import check_one_source, check_record
from sewfmu.scenarios.format.scenario import Connection, Instance, Scenario
from sewfmu.scenarios.format.values import ScenarioError, check_instance_name, parse_value
from sewfmu.scenarios.mechanisms import RoleError, mechanisms

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
# sewfmu's annotation of the DefaultExperiment (its step, master, settings, record), as
# scenarios/interop/ssp_export.py writes it
ANNOTATION = "org.sewfmu.experiment"
SEWFMU = "https://github.com/sewfmu/ssp-annotation"
SSD_NAME = "SystemStructure.ssd"


def _q(ns: str, tag: str) -> str:
    return f"{{{ns}}}{tag}"


def load_ssp(path: Path) -> Scenario:
    """The system of an .ssp or .ssd file as a scenario (its FMUs in scenario.fmu_files)."""
    path = Path(path)
    if not path.is_file():
        raise ScenarioError(f"SSP file {path} does not exist or is not a regular file")
    if path.stat().st_size > MAX_ARCHIVE_BYTES:
        raise ScenarioError(f"{path}: {path.stat().st_size / 2**20:.0f} MiB is more than an SSP "
                            f"system of FMUs needs (at most {MAX_ARCHIVE_BYTES / 2**20:.0f} MiB)")
    digest = _digest(path)
    if path.suffix.lower() == ".ssp":
        base = _unpacked(path, digest)
        ssd = base / SSD_NAME
        if not ssd.is_file():
            raise ScenarioError(f"{path}: no {SSD_NAME} at the archive's root")
    else:
        base, ssd = path.parent, path
    root = _xml(ssd, path)
    system = root.find(_q(SSD, "System"))
    if root.tag != _q(SSD, "SystemStructureDescription") or system is None:
        raise ScenarioError(f"{path}: not an SSP 1.0 system structure (expected "
                            f"ssd:SystemStructureDescription with an ssd:System)")
    where = f"{path}"
    instances, files, versions = {}, {}, {}
    for comp in system.iterfind(f"{_q(SSD, 'Elements')}/{_q(SSD, 'Component')}"):
        name, source = comp.get("name"), comp.get("source")
        if not name or not source:
            raise ScenarioError(f"{where}: a component without name or source")
        if name in instances:
            raise ScenarioError(f"{where}: component {name!r} appears twice")
        try:
            check_instance_name(name)
        except ValueError as err:
            raise ScenarioError(f"{where}: component {name!r}: {err}") from None
        fmu = _inside(base, source)
        if fmu is None:
            raise ScenarioError(f"{where}: component {name}: its FMU {source} is not in the "
                                f"{'archive' if path.suffix.lower() == '.ssp' else 'folder'}")
        kind = _fmu_type(fmu, files, versions, where, name)
        instances[name] = Instance(name, kind, _parameters(comp, base, f"{where}: component "
                                                                       f"{name}"))
    if not instances:
        raise ScenarioError(f"{where}: the system has no components")
    connections = [_connection(c, instances, where)
                   for c in system.iterfind(f"{_q(SSD, 'Connections')}/{_q(SSD, 'Connection')}")]
    analysis, roles = _analysis_of({n: i.fmu for n, i in instances.items()})
    settings, record = _annotation(root, where)
    scenario = Scenario(
        name=path.stem, source=str(path), description=system.get("description", ""),
        analysis=analysis, instances=instances, connections=connections, record=None,
        step=0.0, master="jacobi", stop_time=_stop_time(root, where), revolutions=None,
        shaft=None, compare=None, roles=roles)
    # sewfmu's annotation, checked as `--set experiment.KEY=TEXT` is (in the keys' order: the
    # master before a tolerance, which is for it); where the file gives no step, 0: the run
    # then asks for one
    origin = f"{where}: sewfmu's annotation:"
    for key, text in settings.items():
        scenario.set_value(f"experiment.{key}", parse_value(text, origin), origin=origin)
    if "tolerance" in settings:
        scenario.tolerance_master = scenario.master
    if record is not None:
        check_record(record, f"{where}: sewfmu's annotation")
        scenario.record = record
    # the FMI version of the FMUs it runs, where they agree (the provenance's experiment.fmi)
    if len(set(versions.values())) == 1:
        scenario.fmi = 3 if next(iter(versions.values())).startswith("3") else 2
    scenario.fmu_files = files
    scenario.digest = digest
    check_one_source(connections, where)
    return scenario


# --- reading: nothing outside the archive, nothing unbounded --------------------------------
# An .ssp may come from anyone: its members and references are confined to it, only regular
# files are read, and what it may unpack to is bounded (a 5 MB zip can hold gigabytes).
MAX_ARCHIVE_BYTES = 1 << 30          # the .ssp itself
MAX_UNPACKED_BYTES = 2 << 30         # everything it unpacks to
MAX_MEMBERS = 10_000
MAX_XML_BYTES = 64 << 20             # an .ssd or .ssv
_UNPACKED: dict[str, Path] = {}
_TEMP_PREFIX = "sewfmu-ssp-"
_TEMP = re.compile(r"sewfmu-ssp-(?P<pid>\d+)-[A-Za-z0-9_]+")     # tempfile.mkdtemp's suffix


def _digest(path: Path) -> str:
    """sha256 of a file, read in chunks (never whole into memory)."""
    sha = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            sha.update(chunk)
    return sha.hexdigest()


def _inside(base: Path, reference: str) -> Path | None:
    """The regular file `reference` names inside `base`, or None if it names anything else
    (a path outside, a device, a FIFO, a folder, nothing)."""
    target = (base / reference).resolve()
    root = base.resolve()
    if target != root and root not in target.parents:
        return None
    try:
        return target if stat.S_ISREG(target.stat().st_mode) else None
    except OSError:
        return None


def _unpacked(path: Path, key: str) -> Path:
    """The archive unpacked once per process (the FMUs stay there for the run's workers)."""
    if key not in _UNPACKED:
        # a killed process cannot remove its unpacked archives: the next one does
        archives.remove_dead_scratch(Path(tempfile.gettempdir()), _TEMP)
        folder = Path(tempfile.mkdtemp(prefix=f"{_TEMP_PREFIX}{os.getpid()}-"))
        atexit.register(shutil.rmtree, folder, True)
        try:
            _extract(path, folder)
        except BaseException:
            shutil.rmtree(folder, ignore_errors=True)
            raise
        _UNPACKED[key] = folder
    return _UNPACKED[key]


def _extract(path: Path, folder: Path) -> None:
    """Unpack the regular files of the archive into folder: refused from its directory's sizes
    before a byte is written, and counted while writing (the sizes it claims may lie)."""
    # the limits are read here, at the call, so that a test may lower them
    limits = archives.Limits(MAX_UNPACKED_BYTES, MAX_UNPACKED_BYTES, MAX_MEMBERS, "SSP archive")
    try:
        archives.extract(path, folder, limits)
    except archives.ArchiveError as err:
        raise ScenarioError(str(err)) from None


def _xml(file: Path, where: Path) -> ET.Element:
    try:
        if file.stat().st_size > MAX_XML_BYTES:
            raise ScenarioError(f"{where}: {file.name} is larger than {MAX_XML_BYTES >> 20} MiB")
        return ET.fromstring(file.read_bytes())
    except ET.ParseError as err:
        raise ScenarioError(f"{where}: {file.name} is not well-formed XML: {err}") from None


def _fmu_type(fmu: Path, files: dict[str, Path], versions: dict[str, str], where: str,
              component: str) -> str:
    """The FMU's modelName (made unique if two different files share one); its fmiVersion put
    into `versions`."""
    md = model_description(fmu, f"{where}: component {component}")
    name = md.modelName
    kind, k = name, 1
    while kind in files and files[kind] != fmu:
        k += 1
        kind = f"{name}#{k}"
    files[kind] = fmu
    versions[kind] = str(md.fmiVersion)
    return kind


def _parameters(comp: ET.Element, base: Path, where: str) -> dict:
    values = {}
    for binding in comp.iterfind(f"{_q(SSD, 'ParameterBindings')}/{_q(SSD, 'ParameterBinding')}"):
        prefix = binding.get("prefix", "")
        if binding.get("source"):
            file = _inside(base, binding.get("source"))
            if file is None:
                raise ScenarioError(f"{where}: parameter values {binding.get('source')!r} are "
                                    f"not a file inside the system's archive or folder")
            pset = _xml(file, Path(where.split(":")[0]))
            if pset.tag != _q(SSV, "ParameterSet"):
                raise ScenarioError(f"{where}: {binding.get('source')} is not an "
                                    f"ssv:ParameterSet")
        else:
            pset = binding.find(f"{_q(SSD, 'ParameterValues')}/{_q(SSV, 'ParameterSet')}")
            if pset is None:
                continue
        for p in pset.iterfind(f"{_q(SSV, 'Parameters')}/{_q(SSV, 'Parameter')}"):
            name = p.get("name", "")
            if prefix and name.startswith(prefix):
                name = name[len(prefix):]
            values[name] = _value(p, f"{where}: parameter {name}")
    return values


def _value(p: ET.Element, where: str):
    for kind, convert in (("Real", float), ("Integer", int), ("Boolean", _boolean)):
        element = p.find(_q(SSV, kind))
        if element is not None:
            try:
                return convert(element.get("value"))
            except (TypeError, ValueError):
                raise ScenarioError(f"{where}: {element.get('value')!r} is not a valid "
                                    f"{kind}") from None
    raise ScenarioError(f"{where}: only Real, Integer and Boolean parameters are supported")


def _boolean(text: str) -> int:
    if text not in ("true", "false", "1", "0"):
        raise ValueError(text)
    return int(text in ("true", "1"))


def _connection(c: ET.Element, instances: dict, where: str) -> Connection:
    ends = (c.get("startElement"), c.get("startConnector"), c.get("endElement"),
            c.get("endConnector"))
    text = f"{ends[0]}.{ends[1]} -> {ends[2]}.{ends[3]}"
    if not ends[0] or not ends[2]:
        raise ScenarioError(f"{where}: connection {text}: connections to the system's own "
                            f"connectors are not supported (connect components directly)")
    for element in (ends[0], ends[2]):
        if element not in instances:
            raise ScenarioError(f"{where}: connection {text}: no component {element!r}")
    return Connection(*ends)


def _stop_time(root: ET.Element, where: str) -> float:
    experiment = root.find(_q(SSD, "DefaultExperiment"))
    if experiment is None or experiment.get("stopTime") is None:
        raise ScenarioError(f"{where}: no DefaultExperiment stopTime: the run needs an end")
    try:
        start, stop = float(experiment.get("startTime", "0")), float(experiment.get("stopTime"))
    except ValueError:
        raise ScenarioError(f"{where}: DefaultExperiment times must be numbers") from None
    if start != 0.0:
        raise ScenarioError(f"{where}: DefaultExperiment startTime {start:g}: runs start at 0")
    if not 0.0 < stop < float("inf"):
        raise ScenarioError(f"{where}: DefaultExperiment stopTime must be positive, got {stop:g}")
    return stop


def _annotation(root: ET.Element, where: str) -> tuple[dict[str, str], list[str] | None]:
    """sewfmu's annotation of the DefaultExperiment, as ssp_export.py writes it: the experiment
    keys it carries ({key: text}: scenarios/format/experiment.py's in_ssp keys) and a narrowed
    record (None: every output). Another tool's annotations, anywhere, are not read."""
    experiment = root.find(_q(SSD, "DefaultExperiment"))
    notes = [] if experiment is None else [
        note for note in experiment.iterfind(f"{_q(SSD, 'Annotations')}/{_q(SSC, 'Annotation')}")
        if note.get("type") == ANNOTATION]
    if not notes:
        return {}, None
    carried = [element for note in notes for element in note.iterfind(_q(SEWFMU, "Experiment"))]
    if len(notes) > 1 or len(carried) > 1:
        raise ScenarioError(f"{where}: sewfmu's annotation ({ANNOTATION}) appears more than "
                            f"once in the DefaultExperiment")
    if not carried:
        return {}, None
    known = [name for name, key in EXPERIMENT_KEYS.items() if key.in_ssp]
    for name in carried[0].attrib:
        if name not in known:       # a setting the file states would otherwise not be used
            raise ScenarioError(f"{where}: sewfmu's annotation: unknown key {name!r}"
                                f"{did_you_mean(name, known)} (known: {', '.join(known)})")
    settings = {name: carried[0].get(name) for name in known if carried[0].get(name) is not None}
    columns = [element.get("column") for element in carried[0].iterfind(_q(SEWFMU, "Record"))]
    if not all(columns):
        raise ScenarioError(f"{where}: sewfmu's annotation: a Record without its column")
    return settings, columns or None


def _analysis_of(fmu_of: dict[str, str]) -> tuple[str | None, dict[str, str]]:
    """The analysis whose roles the components' FMU types fill, if one does."""

    for analysis, found in mechanisms().items():
        try:
            return analysis, found.bind(fmu_of, {})
        except RoleError:
            continue
    return None, {}
