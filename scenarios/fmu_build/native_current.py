"""Whether a native FMU (compiled C, fmus/native/ and fmus/native/fmi3/: native.py builds them)
is up to date, without the builder, as sources.py says it for the Python FMUs.

A native FMU mirrors a Python FMU (the same modelDescription) in C (native/). It is out of date
when either changes: its version, the `version` attribute of its modelDescription, is the
Python FMU's (sewfmu's version and the hash of components/ and fmu_build/) joined with the hash
of every C source and header under native/. The builder writes `native_version()` there; a run
compares it with the file's, a stat of each source file and of the FMU file (each read and hashed
once per process while unchanged), and imports the builder only to build.
"""
from __future__ import annotations

import os
import zipfile
from pathlib import Path

from sewfmu.scenarios.files.code_hash import hash_of_files
from sewfmu.scenarios.fmu_build.sources import MODEL_CODE_DIR, current_version, default_fmu_dir

# the C sources of the native FMUs: the models, the FMI layers, the runtime
NATIVE_SOURCE_DIR = MODEL_CODE_DIR.parent / "native"
SOURCE_SUFFIXES = (".c", ".h")
NATIVE_FOLDER = "native"        # fmus/native/, fmus/native/fmi3/
# each target's folder under binaries/, by FMI version (native_compile.TARGETS compiles for them)
TARGET_FOLDERS = {"linux": {2: "linux64", 3: "x86_64-linux"},
                  "windows": {2: "win64", 3: "x86_64-windows"}}
# an FMU file's (path, inode, size, mtime) -> the targets it holds a binary for, for this
# process's lifetime (as sources.fmu_version's versions)
_HELD: dict[tuple, frozenset] = {}


def native_fmu_dir(fmi: int = 2, base: Path | None = None) -> Path:
    """Where the native FMUs are: the folder native/ (FMI 3.0: native/fmi3/) of the Python FMUs'
    folder (sources.default_fmu_dir: fmus/, SEWFMU_FMU_DIR, or `base`). The builder's
    default_native_dir says the same (tests/cosim/test_native_fmus.py holds them together); this
    one a run reads without importing the builder."""
    folder = default_fmu_dir(2, base) / NATIVE_FOLDER
    return folder / "fmi3" if fmi == 3 else folder


def _source_files(folder: Path) -> list[tuple[str, str]]:
    """(path relative to `folder`, path) of every C source and header under it, sorted."""
    found = []
    for top, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        for name in files:
            if name.endswith(SOURCE_SUFFIXES):
                path = os.path.join(top, name)
                found.append((os.path.relpath(path, folder).replace(os.sep, "/"), path))
    return sorted(found)


def native_sources_hash(folder: Path | None = None) -> str:
    """Hash of the name and bytes of every .c and .h file under `folder` (default native/; 12
    hex digits)."""
    return hash_of_files(_source_files(Path(folder or NATIVE_SOURCE_DIR)), separator=b"\0")


def native_version() -> str:
    """The version a native FMU built now carries: the Python FMU's it mirrors (current_version:
    sewfmu's version and its code's hash), then `.native.` and the hash of the C sources."""
    return f"{current_version()}.native.{native_sources_hash()}"


def build_of(path: Path) -> str:
    """"python" for an FMU file that carries Python code (resources/*.py: a Python FMU, whose
    host needs a Python), "native" for one of compiled code only, "unknown" for a file that
    cannot be read."""
    try:
        with zipfile.ZipFile(path) as archive:
            names = archive.namelist()
    except (OSError, zipfile.BadZipFile):
        return "unknown"
    return "python" if any(n.startswith("resources/") and n.endswith(".py") for n in names) \
        else "native"


def missing_targets(path: Path) -> list[str]:
    """The targets (TARGET_FOLDERS) a native FMU holds no binary for (built where a compiler
    was missing), sorted; its zip read once per process while the file is unchanged (stat)."""
    try:
        st = os.stat(path)
        key = (str(path), st.st_ino, st.st_size, st.st_mtime_ns)
        if key not in _HELD:
            with zipfile.ZipFile(path) as archive:
                folders = {n.split("/")[1] for n in archive.namelist()
                           if n.startswith("binaries/") and n.count("/") >= 2}
            _HELD[key] = frozenset(t for t, by_fmi in TARGET_FOLDERS.items()
                                   if folders & set(by_fmi.values()))
    except (OSError, zipfile.BadZipFile):
        return []
    return sorted(set(TARGET_FOLDERS) - _HELD[key])


def without_windows_line(paths: dict[str, Path], what: str) -> str | None:
    """The one line of an export (`what`: "export-fmu") whose native FMUs lack the Windows
    binary (built where no Windows compiler was), or None."""
    lacking = [name for name, path in sorted(paths.items())
               if build_of(Path(path)) == "native" and "windows" in missing_targets(Path(path))]
    if not lacking:
        return None
    return (f"{what}: the native FMUs {', '.join(lacking)} inside have no Windows binary "
            f"(built without a Windows compiler): the export cannot run on Windows; apt install "
            f"mingw-w64, or pip install 'sewfmu[native]', then export again")
