"""Which FMU files a run uses, and whether they are up to date, without the builder: an FMU is
current when the version in its modelDescription is sewfmu's version and the content hash of
the code it is made from (components/ and fmu_build/: sources.py), so a run checks its FMUs by
a stat of some fifty source files and of each FMU file (each read and hashed once per process
while unchanged), and imports the builders (build.py: pythonfmu's and pythonfmu3's,
xml.dom.minidom) only when an FMU is missing or stale. experiment.fmus = "native" takes the
native FMUs of the same names instead (fmus/native/: native_current.py says when they are
current; the builder, native.py, is imported only to build one)."""
from __future__ import annotations

import os
import sys
from pathlib import Path

from sewfmu.components.registry import FMUS
from sewfmu.errors import Error
from sewfmu.scenarios.fmu_build.native_current import (
    missing_targets,
    native_fmu_dir,
    native_version,
)
from sewfmu.scenarios.fmu_build.sources import current_version, default_fmu_dir, fmu_version
from sewfmu.scenarios.format.fmu_file import (
    fmu_path,
    is_fmu_file,
    read_fmu,
)
from sewfmu.scenarios.format.values import ScenarioError


def ensure_built(names, dest: Path | None = None, fmi: int = 2, kind: str = "python",
                 python_dir: Path | None = None) -> dict[str, Path]:
    """Paths of the named FMUs, (re)building any that is missing or carries other code; `kind`
    "native": the native FMUs (dest default fmus/native/, fmus/native/fmi3/), each made from
    the Python FMU of its name in `python_dir` (default fmus/, fmus/fmi3/)."""
    native = kind == "native"
    dest = Path(dest or (native_fmu_dir(fmi) if native else default_fmu_dir(fmi)))
    version = native_version() if native else current_version()
    paths = {}
    left_out: set = set()       # targets no compiler was found for: one line for the run
    try:
        for name in names:
            path = dest / f"{name}.fmu"
            current = fmu_version(path) == version
            if current and native and _completable(path, dest):
                path = _complete_native(name, dest, fmi, python_dir, left_out, path)
            elif not current:
                if native:
                    path = _build_native(name, dest, fmi, python_dir, left_out=left_out)
                else:
                    from sewfmu.scenarios.fmu_build.build import build_fmu  # only to build
                    build_fmu(name, dest, fmi=fmi)
            paths[name] = path
    finally:
        if left_out:
            # the compilers' module: only where a native FMU was built
            from sewfmu.scenarios.fmu_build.native_compile import left_out_line
            print(f"sewfmu: {left_out_line(left_out)}", file=sys.stderr)
    return paths


def _completable(path: Path, dest: Path) -> bool:
    """A current native FMU without the binary of a target a compiler is found for now (built
    before mingw-w64 or zig was installed), in a folder it can be rebuilt in: out of date. The
    zip is read only for a current native FMU, once per process while unchanged; the compilers
    looked for only where a binary is missing."""
    missing = missing_targets(path)
    if not missing or not os.access(dest, os.W_OK):
        return False
    # the compilers' module: only where a current FMU lacks a binary
    from sewfmu.scenarios.fmu_build.native_compile import TARGETS, NoCompiler, compiler_for
    for target in TARGETS:
        if target.name in missing:
            try:
                compiler_for(target)
            except NoCompiler:
                continue
            return True
    return False


def _complete_native(name: str, dest: Path, fmi: int, python_dir: Path | None,
                     left_out: set, current: Path) -> Path:
    """The native FMU rebuilt with the binaries it lacked; where that fails (a compiler that
    cannot compile), the current one, said in one line: a run here needs no other binary."""
    try:
        return _build_native(name, dest, fmi, python_dir, left_out=left_out)
    except Error as err:
        print(f"sewfmu: {name}: kept without the binaries it lacks: {err}", file=sys.stderr)
        return current


def _build_native(name: str, dest: Path, fmi: int, python_dir: Path | None,
                  left_out: set | None = None) -> Path:
    """native.build_native_fmu (a C compiler's builder: imported only to build), the targets
    it leaves out for want of a compiler into `left_out`; a native FMU that cannot be made here
    (no builder, a model without its C twin yet, a broken compiler) is one line."""
    try:
        # the native builder (C compilers, the FMUs' C sources): only to build one
        from sewfmu.scenarios.fmu_build.native import build_native_fmu
    except ImportError as err:
        raise ScenarioError(f"experiment.fmus = \"native\": this sewfmu cannot build native "
                            f"FMUs ({err}); run with experiment.fmus = \"python\"") from None
    try:
        return Path(build_native_fmu(name, dest, fmi=fmi, python_dir=python_dir,
                                     left_out=left_out))
    except Error:                       # no compiler, a broken one: its one line says why
        raise
    except (FileNotFoundError, KeyError, RuntimeError) as err:
        # a compiler's refusal is many lines: the first error here, all of them from the build
        lines = str(err).strip().splitlines() or [type(err).__name__]
        first = next((line for line in lines[1:] if "error" in line.lower()), "")
        why = " ".join(f"{lines[0]} {first}".split())
        raise ScenarioError(f"experiment.fmus = \"native\": the native {name} cannot be built "
                            f"({why[:300]}); `sewfmu build --native` shows why in full, and "
                            f"experiment.fmus = \"python\" runs the Python FMUs") from None


def fmus_for_names(names: list[str], fmu_dir: Path | None = None, fmi: int = 2,
                   kind: str = "python") -> dict[str, Path]:
    """sewfmu's FMUs of these names for FMI `fmi`, built where missing or stale, in fmu_dir
    (default: fmus/; FMI 3.0: its folder fmi3/); `kind` "native": in its folder native/
    (native/fmi3/), made from the Python FMUs of fmu_dir."""
    python_dir = default_fmu_dir(fmi, fmu_dir)
    if kind != "native":
        return ensure_built(sorted(names), python_dir, fmi=fmi)
    return ensure_built(sorted(names), native_fmu_dir(fmi, fmu_dir), fmi=fmi, kind=kind,
                        python_dir=python_dir)


def fmus_for(scenario, fmu_dir: Path | None = None) -> dict[str, Path]:
    """The FMU file of each FMU type a scenario uses: the files it names (an SSP system's own,
    a scenario file's `fmu = "path/Motor.fmu"`), and sewfmu's built where missing or stale, of
    the build experiment.fmus names (python, native) and the FMI version experiment.fmi does."""

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
    return {**found, **(fmus_for_names(own, fmu_dir, scenario.fmi, scenario.fmus) if own
                        else {})}
