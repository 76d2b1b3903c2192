"""Which FMU files a run uses, and whether they are up to date, without the builder: an FMU is
current when the version in its modelDescription is sewfmu's version and the content hash of
the code it is made from (components/ and fmu_build/), so a run checks its FMUs by reading one
small file from each and hashing some fifty source files, and imports the builders
(scenarios/fmu_build/build.py: pythonfmu's and pythonfmu3's, xml.dom.minidom) only when an FMU
is missing or stale."""
from __future__ import annotations

import hashlib
import os
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import sewfmu.components
from sewfmu._version import __version__
from sewfmu.components.registry import FMUS
from sewfmu.scenarios.format.values import ScenarioError

# the model code every FMU carries: all of components/, nothing else
MODEL_CODE_DIR = Path(sewfmu.components.__file__).resolve().parent
BUILD_DIR = Path(__file__).resolve().parent
VERSION = __version__     # sewfmu's one version (sewfmu/_version.py)


def default_fmu_dir(fmi: int = 2, base: Path | None = None) -> Path:
    """fmus/ beside the project's pyproject.toml, or ./fmus for an installed copy;
    SEWFMU_FMU_DIR overrides both, `base` all three. The FMI 3.0 FMUs go into its folder
    fmi3/."""
    if base:
        base = Path(base)
    elif os.environ.get("SEWFMU_FMU_DIR"):
        base = Path(os.environ["SEWFMU_FMU_DIR"])
    elif (MODEL_CODE_DIR.parent / "pyproject.toml").exists():
        base = MODEL_CODE_DIR.parent / "fmus"
    else:
        base = Path.cwd() / "fmus"
    return base / "fmi3" if fmi == 3 else base


def _hash_of(*folders: Path) -> str:
    digest = hashlib.sha256()
    for folder in folders:
        for path in sorted(Path(folder).glob("*.py")):
            digest.update(path.name.encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()[:12]


def model_code_hash(source: Path = MODEL_CODE_DIR) -> str:
    """Hash of the model code every FMU carries: the name and bytes of each .py file in
    components/ (the FMI 2.0 and 3.0 layers both; nothing outside that folder). It names the
    package inside the FMU: same code, same name."""
    return _hash_of(source)


def fmu_content_hash(source: Path = MODEL_CODE_DIR) -> str:
    """Hash of everything an FMU is made from: the model code (components/) and this build
    (fmu_build/: the entry script, the carried reference, the documentation page). It is the
    FMU's version: an edit of either rebuilds the FMUs."""
    return _hash_of(source, BUILD_DIR)


def fmu_version(fmu_path: Path) -> str | None:
    """The version attribute of an FMU's modelDescription, or None if unreadable."""
    try:
        with zipfile.ZipFile(fmu_path) as zf:
            root = ElementTree.fromstring(zf.read("modelDescription.xml"))
    except (OSError, KeyError, zipfile.BadZipFile, ElementTree.ParseError):
        return None
    return root.get("version")


def current_version() -> str:
    return f"{VERSION}+{fmu_content_hash()}"


def ensure_built(names, dest: Path | None = None, fmi: int = 2) -> dict[str, Path]:
    """Paths of the named FMUs, (re)building any that is missing or carries other code."""
    dest = Path(dest or default_fmu_dir(fmi))
    version = current_version()
    paths = {}
    for name in names:
        path = dest / f"{name}.fmu"
        if fmu_version(path) != version:
            from sewfmu.scenarios.fmu_build.build import build_fmu  # the builders: only to build
            build_fmu(name, dest, fmi=fmi)
        paths[name] = path
    return paths


def fmus_for_names(names: list[str], fmu_dir: Path | None = None,
                   fmi: int = 2) -> dict[str, Path]:
    """sewfmu's FMUs of these names for FMI `fmi`, built where missing or stale, in fmu_dir
    (default: fmus/; FMI 3.0: its folder fmi3/)."""
    return ensure_built(sorted(names), default_fmu_dir(fmi, fmu_dir), fmi=fmi)


def fmus_for(scenario, fmu_dir: Path | None = None) -> dict[str, Path]:
    """The FMU file of each FMU type a scenario uses: the files it names (an SSP system's own,
    a scenario file's `fmu = "path/Motor.fmu"`), and sewfmu's built where missing or stale."""
    from sewfmu.scenarios.format.fmu_file import (  # loaded on first use (start-up time)
        fmu_path,
        is_fmu_file,
        read_fmu,
    )

    names = sorted({inst.fmu for inst in scenario.instances.values()})
    found = {name: scenario.fmu_files[name] for name in names if name in scenario.fmu_files}
    for name in names:
        if name not in found and is_fmu_file(name):
            # an instance added in Python names the file itself (a scenario file's are in
            # fmu_files): from the folder the process runs in, as Python's open() takes it
            where = f"{scenario.source}: fmu {name!r}"
            found[name] = fmu_path(name, Path.cwd(), where)
            read_fmu(found[name], where)
    unknown = [n for n in names if n not in found and n not in FMUS]
    if unknown:
        raise ScenarioError(f"{scenario.source}: unknown FMU {unknown[0]!r} "
                            f"(known: {', '.join(FMUS)}; or the path of an .fmu file)")
    own = [n for n in names if n not in found]
    return {**found, **(fmus_for_names(own, fmu_dir, scenario.fmi) if own else {})}
