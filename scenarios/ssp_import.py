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
import shutil
import tempfile
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

from .format import Connection, Instance, Scenario, ScenarioError, check_one_source

SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
ANNOTATION = "org.sewfmu.experiment"
SSD_NAME = "SystemStructure.ssd"


def _q(ns: str, tag: str) -> str:
    return f"{{{ns}}}{tag}"


def load_ssp(path: Path) -> Scenario:
    """The system of an .ssp or .ssd file as a scenario (its FMUs in scenario.fmu_files)."""
    path = Path(path)
    if not path.is_file():
        raise ScenarioError(f"SSP file {path} does not exist")
    raw = path.read_bytes()
    if path.suffix.lower() == ".ssp":
        base = _unpacked(path, raw)
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
    instances, files = {}, {}
    for comp in system.iterfind(f"{_q(SSD, 'Elements')}/{_q(SSD, 'Component')}"):
        name, source = comp.get("name"), comp.get("source")
        if not name or not source:
            raise ScenarioError(f"{where}: a component without name or source")
        if name in instances:
            raise ScenarioError(f"{where}: component {name!r} appears twice")
        if "." in name:
            raise ScenarioError(f"{where}: component {name!r}: a name with '.' cannot be "
                                f"addressed as component.variable")
        fmu = (base / source).resolve()
        if not str(fmu).startswith(str(base.resolve())) or not fmu.is_file():
            raise ScenarioError(f"{where}: component {name}: its FMU {source} is not in the "
                                f"{'archive' if path.suffix.lower() == '.ssp' else 'folder'}")
        kind = _fmu_type(fmu, files, where, name)
        instances[name] = Instance(name, kind, _parameters(comp, base, f"{where}: component "
                                                                       f"{name}"))
    if not instances:
        raise ScenarioError(f"{where}: the system has no components")
    connections = [_connection(c, instances, where)
                   for c in system.iterfind(f"{_q(SSD, 'Connections')}/{_q(SSD, 'Connection')}")]
    analysis, roles = _analysis_of({n: i.fmu for n, i in instances.items()})
    experiment = _experiment(root)
    scenario = Scenario(
        name=path.stem, source=str(path), description=system.get("description", ""),
        analysis=analysis, instances=instances, connections=connections, record=None,
        step=experiment["step"], master=experiment["master"],
        stop_time=_stop_time(root, where), revolutions=None, shaft=None, compare=None,
        roles=roles, tolerance=experiment["tolerance"], acceleration=experiment["acceleration"],
        tolerance_master=experiment["master"])
    scenario.fmu_files = files
    scenario.digest = hashlib.sha256(raw).hexdigest()
    check_one_source(connections, where)
    return scenario


# --- reading ---------------------------------------------------------------------------------
_UNPACKED: dict[str, Path] = {}


def _unpacked(path: Path, raw: bytes) -> Path:
    """The archive unpacked once per process (the FMUs stay there for the run's workers)."""
    key = hashlib.sha256(raw).hexdigest()
    if key not in _UNPACKED:
        folder = Path(tempfile.mkdtemp(prefix="sewfmu-ssp-"))
        atexit.register(shutil.rmtree, folder, True)
        try:
            with zipfile.ZipFile(path) as archive:
                for member in archive.namelist():        # nothing may land outside the folder
                    target = (folder / member).resolve()
                    if not str(target).startswith(str(folder.resolve())):
                        raise ScenarioError(f"{path}: archive member {member!r} points outside "
                                            f"the archive")
                archive.extractall(folder)
        except zipfile.BadZipFile:
            raise ScenarioError(f"{path}: not an SSP archive (not a zip file)") from None
        _UNPACKED[key] = folder
    return _UNPACKED[key]


def _xml(file: Path, where: Path) -> ET.Element:
    try:
        return ET.fromstring(file.read_bytes())
    except ET.ParseError as err:
        raise ScenarioError(f"{where}: {file.name} is not well-formed XML: {err}") from None


def _fmu_type(fmu: Path, files: dict[str, Path], where: str, component: str) -> str:
    """The FMU's modelName (made unique if two different files share one)."""
    from fmpy import read_model_description

    try:
        name = read_model_description(str(fmu)).modelName
    except Exception as err:            # noqa: BLE001 - any unreadable FMU is one message
        raise ScenarioError(f"{where}: component {component}: {fmu.name} is not a readable FMU "
                            f"({' '.join(str(err).split())})") from None
    kind, k = name, 1
    while kind in files and files[kind] != fmu:
        k += 1
        kind = f"{name}#{k}"
    files[kind] = fmu
    return kind


def _parameters(comp: ET.Element, base: Path, where: str) -> dict:
    values = {}
    for binding in comp.iterfind(f"{_q(SSD, 'ParameterBindings')}/{_q(SSD, 'ParameterBinding')}"):
        prefix = binding.get("prefix", "")
        if binding.get("source"):
            pset = _xml(base / binding.get("source"), Path(where.split(":")[0]))
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


def _experiment(root: ET.Element) -> dict:
    """The communication step, master, tolerance and acceleration from sewfmu's annotation;
    where the file gives no step, 0 (the run then asks for --set experiment.step)."""
    from .format import ACCELERATIONS, MASTERS

    found = {"step": 0.0, "master": "jacobi", "tolerance": None, "acceleration": "aitken"}
    for note in root.iter(_q(SSC, "Annotation")):
        if note.get("type") == ANNOTATION:
            for element in note.iter():
                for key in ("step", "tolerance"):
                    try:
                        found[key] = float(element.get(key, found[key]))
                    except (TypeError, ValueError):
                        pass
                if element.get("master") in MASTERS:
                    found["master"] = element.get("master")
                if element.get("acceleration") in ACCELERATIONS:
                    found["acceleration"] = element.get("acceleration")
    return found


def _analysis_of(fmu_of: dict[str, str]) -> tuple[str | None, dict[str, str]]:
    """The analysis whose roles the components' FMU types fill, if one does."""
    from .analyses import ROLES, RoleError, bind

    for analysis in ROLES:
        try:
            return analysis, bind(analysis, fmu_of, {})
        except RoleError:
            continue
    return None, {}
