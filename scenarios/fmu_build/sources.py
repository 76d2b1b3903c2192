"""What an FMU is made from and which version it carries, without the builder: the folders of
the model code and of the build, their content hash, sewfmu's version, and the version an FMU
file says it is (up_to_date.py compares them; build.py writes them)."""
from __future__ import annotations

import os
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import sewfmu.components
from sewfmu._version import __version__
from sewfmu.scenarios.files.code_hash import hash_of

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


# an FMU file's (path, inode, size, mtime) -> the version read from it, for this process's
# lifetime: a run (and every sweep point in a worker) checks the FMUs by a stat of each file
_SEEN: dict[tuple, str | None] = {}


def _signature(path: Path) -> tuple:
    st = path.stat()
    return str(path), st.st_ino, st.st_size, st.st_mtime_ns


def model_code_hash(source: Path = MODEL_CODE_DIR) -> str:
    """Hash of the model code every FMU carries: the name and bytes of each .py file in
    components/ (the FMI 2.0 and 3.0 layers both; nothing outside that folder). It names the
    package inside the FMU: same code, same name."""
    return hash_of(source)


def fmu_content_hash(source: Path = MODEL_CODE_DIR) -> str:
    """Hash of everything an FMU is made from: the model code (components/) and this build
    (fmu_build/: the entry script, the carried reference, the documentation page). It is the
    FMU's version: an edit of either rebuilds the FMUs."""
    return hash_of(source, BUILD_DIR)


def fmu_version(fmu_path: Path) -> str | None:
    """The version attribute of an FMU's modelDescription, or None if unreadable."""
    try:
        key = ("version", *_signature(Path(fmu_path)))
        if key not in _SEEN:
            with zipfile.ZipFile(fmu_path) as zf:
                root = ElementTree.fromstring(zf.read("modelDescription.xml"))
            _SEEN[key] = root.get("version")
    except (OSError, KeyError, zipfile.BadZipFile, ElementTree.ParseError):
        return None
    return _SEEN[key]


def current_version() -> str:
    return f"{VERSION}+{fmu_content_hash()}"
