"""An FMU file named in a scenario (`fmu = "path/Motor.fmu"`), whoever made it: found, read and
checked against its modelDescription before anything runs.

- The path is taken relative to the scenario file (a Scenario built in Python: relative to the
  folder the process runs in), so a scenario and its FMUs move together.
- FMI 2.0 and 3.0 co-simulation FMUs; a model-exchange-only FMU or another FMI version is
  refused in one line (the master steps FMUs with doStep).
- Parameters the scenario gives are checked by name, causality, type and declared range here,
  so that a wrong name fails where it is written; the connections (variables, causality, types,
  units) are checked when the system is connected (scenarios/cosim/system.py).
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
import zipfile
import zlib
from pathlib import Path

from sewfmu.components.parameters import did_you_mean
from sewfmu.scenarios.format.declared_range import apart
from sewfmu.scenarios.format.values import ScenarioError

SUFFIX = ".fmu"
MAX_XML_BYTES = 64 << 20        # a modelDescription.xml sewfmu reads (the largest seen: ~20 MiB)
MAX_HEAD_BYTES = 1 << 20        # read for the root element's start tag
_INTEGERS = {"Integer", "Enumeration", "Boolean",
             *(f"{sign}Int{bits}" for sign in ("", "U") for bits in (8, 16, 32, 64))}


def is_fmu_file(text: object) -> bool:
    """Whether an instance's `fmu` names a file rather than one of sewfmu's FMUs."""
    return isinstance(text, str) and text.lower().endswith(SUFFIX)


def fmu_path(text: str, base: Path, where: str) -> Path:
    """The FMU file `text` names, relative to `base` (the scenario file's folder)."""
    path = (Path(base) / Path(text).expanduser()).resolve()
    if not path.is_file():
        raise ScenarioError(f"{where}: FMU file {text!r} not found (looked for {path}; a "
                            f"relative path is taken from the scenario file's folder)")
    return path


def model_description(path: Path, where: str, validate: bool = True):
    """fmpy's modelDescription of an FMU file, or one ScenarioError naming what is wrong: not a
    zip archive, no modelDescription.xml in it, one that is not XML, or not an FMI model
    description. Every reader of an FMU file's modelDescription calls this one."""
    from fmpy import read_model_description  # fmpy: only when an FMU file is read

    path = Path(path)
    name = f"{where}: {path.name}" if where else path.name
    try:
        with zipfile.ZipFile(path) as archive:
            listed = archive.namelist()
            if "modelDescription.xml" not in listed:
                shown = ", ".join(listed[:3]) + (", ..." if len(listed) > 3 else "")
                raise ScenarioError(f"{name} is not an FMU: it has no modelDescription.xml (it "
                                    f"holds: {shown or 'nothing'})")
            size = archive.getinfo("modelDescription.xml").file_size
            if size > MAX_XML_BYTES:     # parsed whole by fmpy: bounded before any parser
                raise ScenarioError(f"{name}: its modelDescription.xml is {size / 2**20:,.0f} "
                                    f"MiB, more than the {MAX_XML_BYTES >> 20} MiB sewfmu reads")
            root, version, why = _root_tag(archive, name)
    except (zipfile.BadZipFile, EOFError):
        raise ScenarioError(f"{name} is not an FMU: not a zip archive") from None
    except OSError as err:
        raise ScenarioError(f"{name}: cannot read: {err.strerror or err}") from None
    if root is None:
        raise ScenarioError(f"{name}: its modelDescription.xml is not XML ({why})")
    if root != "fmiModelDescription":
        raise ScenarioError(f"{name}: its modelDescription.xml is no FMI model description (its "
                            f"root element is <{root[:40]}>, not <fmiModelDescription>)")
    if not isinstance(version, str) or not version.startswith(("2.", "3.")):
        said = ("FMI 1.0" if version in ("1.0", "1") else
                f"its fmiVersion {version[:20]!r}" if isinstance(version, str) else
                "a modelDescription without fmiVersion")
        raise ScenarioError(f"{name}: {said} is not supported (FMI 2.0 and 3.0 are)")
    try:
        return read_model_description(str(path), validate=validate)
    except Exception as err:            # noqa: BLE001 - any unreadable FMU is one message
        said = " ".join(str(err).split())
        raise ScenarioError(f"{name} is not a readable FMU ({type(err).__name__}: "
                            f"{said[:300]}{'...' if len(said) > 300 else ''})") from None


def _root_tag(archive: zipfile.ZipFile, name: str) -> tuple[str | None, str | None, str]:
    """The name of modelDescription.xml's root element (no namespace) and its fmiVersion, or
    None and why it is no XML; only the bytes up to the root element are read, at most
    MAX_HEAD_BYTES of them (expat 2.5 takes quadratic time over one long start tag fed in
    pieces: a root with a 60 MiB attribute was minutes)."""
    parser = ET.XMLPullParser(events=("start",))
    try:
        with archive.open("modelDescription.xml") as xml:
            read = 0
            while read < MAX_HEAD_BYTES:
                chunk = xml.read(1 << 16)
                if not chunk:
                    parser.close()
                    break
                read += len(chunk)
                parser.feed(chunk)
                for _, element in parser.read_events():
                    return element.tag.rpartition("}")[2], element.get("fmiVersion"), ""
            else:
                raise ScenarioError(f"{name}: the root element of its "
                                    f"modelDescription.xml does not end within its first "
                                    f"{MAX_HEAD_BYTES >> 20} MiB (an attribute of megabytes): "
                                    f"no FMI model description")
    except ET.ParseError as err:
        return None, None, " ".join(str(err).split())
    except ScenarioError:               # a ValueError too: not a damaged member
        raise
    except (zipfile.BadZipFile, EOFError, RuntimeError, zlib.error, NotImplementedError,
            UnicodeError, ValueError) as err:
        return None, None, f"a damaged member: {' '.join(str(err).split())[:200]}"
    return None, None, "no element"


def read_fmu(path: Path, where: str):
    """The modelDescription of a co-simulation FMU of FMI 2.0 or 3.0, or one ScenarioError."""
    md = model_description(path, where)
    if not str(md.fmiVersion).startswith(("2.", "3.")):
        raise ScenarioError(f"{where}: {path.name} is an FMI {md.fmiVersion} FMU; sewfmu runs "
                            f"FMI 2.0 and 3.0 co-simulation FMUs")
    if md.coSimulation is None:
        raise ScenarioError(f"{where}: {path.name} ({md.modelName}) has no co-simulation "
                            f"interface (model exchange only); sewfmu's master steps FMUs "
                            f"with doStep")
    return md


def unit_of(variable) -> str:
    """A variable's unit, its own or its declared type's (FMI 2.0 lets either carry it)."""
    declared = getattr(variable, "declaredType", None)
    return variable.unit or (getattr(declared, "unit", None) if declared else None) or ""


def check_parameter(md, key: str, value, where: str) -> None:
    """A value the scenario gives to `key`: a parameter or an input of the FMU, of a number type,
    within the range it declares (the variable's own, or its declared type's)."""
    variables = {v.name: v for v in md.modelVariables}
    v = variables.get(key)
    if v is None or v.causality not in ("parameter", "input"):
        names = sorted(n for n, x in variables.items() if x.causality in ("parameter", "input"))
        raise ScenarioError(f"{where}: {md.modelName} has no parameter or input {key!r}"
                            f"{did_you_mean(key, names)} (has: {', '.join(names) or 'none'})")
    if v.type == "String" or v.type == "Binary":
        raise ScenarioError(f"{where}: {key} is a {v.type}; a scenario gives numbers")
    if v.type in _INTEGERS and float(value) != math.floor(float(value)):
        raise ScenarioError(f"{where}: {key} is a {v.type}: a whole number, got {value!r}")
    for bound, number, limit in zip(("min", "max"), declared_bounds(v),
                                    (lambda x, b: x < b, lambda x, b: x > b)):
        if number is not None and limit(float(value), number):
            shown, limit_text = apart(float(value), number)
            raise ScenarioError(f"{where}: {key} = {shown} {unit_of(v)} is outside the range "
                                f"{md.modelName} declares ({bound} {limit_text})")


def declared_bounds(variable) -> tuple[float | None, float | None]:
    """A variable's declared (min, max), its own or its declared type's; None where it
    declares none (or a bound that is no number, which says nothing)."""
    declared = getattr(variable, "declaredType", None)
    out = []
    for bound in ("min", "max"):
        text = getattr(variable, bound, None) or \
            (getattr(declared, bound, None) if declared else None)
        try:
            out.append(float(text) if text is not None else None)
        except (TypeError, ValueError):
            out.append(None)
    return out[0], out[1]


def check_binary(path: Path, md, where: str = "") -> None:
    """An FMU runs here only with the library of its modelIdentifier for this platform
    (binaries/linux64/X.so in FMI 2.0, binaries/x86_64-linux/X.so in 3.0): refused before it is
    loaded, naming the platforms it has, instead of fmpy's "instantiate returned FATAL"."""
    import fmpy  # fmpy: only when an FMU file is run

    path = Path(path)
    name = f"{where}: {path.name}" if where else path.name
    fmi3 = str(md.fmiVersion).startswith("3")
    here = fmpy.platform_tuple if fmi3 else fmpy.platform
    identifier = md.coSimulation.modelIdentifier if md.coSimulation is not None else md.modelName
    library = f"{identifier}{fmpy.sharedLibraryExtension}"
    try:
        with zipfile.ZipFile(path) as archive:
            listed = archive.namelist()
    except (zipfile.BadZipFile, EOFError, OSError) as err:
        raise ScenarioError(f"{name}: cannot read the archive ({err})") from None
    platforms = sorted({n.split("/")[1] for n in listed
                        if n.startswith("binaries/") and n.count("/") >= 2 and n.split("/")[2]})
    if here not in platforms:
        has = ", ".join(platforms) or ("none: source code only" if any(
            n.startswith("sources/") for n in listed) else "none")
        raise ScenarioError(f"{name} has no binary for {here}, the platform sewfmu runs on (it "
                            f"has: {has}); run it where one of those is, or export it from its "
                            f"tool with a {here} binary")
    if f"binaries/{here}/{library}" not in listed:
        files = sorted(n.rpartition("/")[2] for n in listed if n.startswith(f"binaries/{here}/")
                       and not n.endswith("/"))
        raise ScenarioError(f"{name} has binaries/{here}/ but not {library}, the library of its "
                            f"modelIdentifier {identifier!r} (it has: {', '.join(files[:6])}"
                            f"{', ...' if len(files) > 6 else ''}); the FMU is incomplete")
