"""Build the native FMUs (`sewfmu build --native [--fmi 3]`): each mechanism as C that needs no
Python, into fmus/native/ (FMI 2.0) and fmus/native/fmi3/ (FMI 3.0).

A native FMU is made from the Python FMU of the same name and FMI version (built, or reused
when current): its modelDescription with a token of its own and the C runtime's capabilities
(native_description.py), the regression reference and the documentation it carries, and the
C sources: the runtime (native/runtime/), the FMI glue of its version with the FMI headers, the
model's twin files (MODEL_FILES) and description.c. They go into the FMU's sources/, flat, and
are compiled from there (native_compile.py), so that the sources shipped are those compiled.
"""
from __future__ import annotations

import hashlib
import importlib
import re
import sys
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from xml.etree import ElementTree

from sewfmu.components.registry import FMI_VERSIONS, FMUS
from sewfmu.scenarios.fmu_build.install import install, scratch_folder, writable
from sewfmu.scenarios.fmu_build.native_compile import (
    TARGETS,
    NoCompiler,
    compile_binary,
    left_out_line,
)
from sewfmu.scenarios.fmu_build.native_current import (
    NATIVE_SOURCE_DIR,
    native_fmu_dir,
    native_version,
)
from sewfmu.scenarios.fmu_build.native_description import (
    TOKEN_PLACEHOLDER,
    build_description_xml,
    description_c,
    native_model_description,
    token_of,
)
from sewfmu.scenarios.fmu_build.sources import current_version, default_fmu_dir, fmu_version

NATIVE = NATIVE_SOURCE_DIR                     # runtime/ and models/
RUNTIME = NATIVE / "runtime"
MODELS = NATIVE / "models"

# the model files each FMU compiles (native/models/), with the headers they include
MODEL_FILES: dict[str, tuple[str, ...]] = {
    "MainShaft": ("parameters.c", "shaft.c"),
    "PunchLinkage": ("parameters.c", "kinematics.c", "punch_linkage.c"),
    "PunchContact": ("parameters.c", "oscillator.c", "punch_contact.c"),
    "PunchBody": ("parameters.c", "oscillator.c", "punch_contact.c"),
    "Fabric": ("parameters.c", "fabric.c"),
    "TakeupLinkage": ("parameters.c", "kinematics.c", "takeup.c"),
    "FeedLinkage": ("parameters.c", "kinematics.c", "feed.c"),
    "CarriageDrive": ("parameters.c", "oscillator.c", "carriage.c"),
    "CarriageModal": ("parameters.c", "oscillator.c", "carriage.c"),
}
RUNTIME_FILES = ("sew_model.h", "sew_slave.h", "sew_slave.c", "sew_state.c")
FMI_FILES = {
    2: ("fmi2_glue.c", "fmi2/fmi2Functions.h", "fmi2/fmi2FunctionTypes.h",
        "fmi2/fmi2TypesPlatform.h"),
    3: ("fmi3_glue.c", "fmi3_glue.h", "fmi3_unsupported.c", "fmi3/fmi3Functions.h",
        "fmi3/fmi3FunctionTypes.h", "fmi3/fmi3PlatformTypes.h"),
}
REBUILD = "sewfmu build --native"        # said where the FMU folder cannot take the build
_INCLUDE = re.compile(rb'^\s*#\s*include\s+"([^"]+)"', re.MULTILINE)

HOST_NEEDS = (
    "This FMU is native code (C99, built by <code>sewfmu build --native</code>): it needs no "
    "Python, no library but the C library, and no environment. Binaries: x86-64 Linux and "
    "x86-64 Windows (linked statically: no runtime DLL beside it). Its C sources are in "
    "sources/ for any other platform; compile them with floating-point contraction off "
    "(<code>-ffp-contract=off</code>) for the numbers of the reference it carries. It refuses "
    "misuse with an error status and says why through the logger: an unknown value reference, "
    "a value outside its declared range, NaN, a write to an output, a parameter set after "
    "initialization, a garbled FMU state.")


def default_native_dir(fmi: int = 2, root: Path | None = None) -> Path:
    """fmus/native/ (FMI 2.0) or fmus/native/fmi3/ (FMI 3.0), beside the Python FMUs' fmus/
    and fmus/fmi3/; `root` (or SEWFMU_FMU_DIR) replaces fmus/ as for the Python FMUs (the
    folder a run reads: native_current.native_fmu_dir)."""
    return native_fmu_dir(fmi, root)


def _read(folder: Path, name: str) -> bytes:
    path = folder / name
    if not path.is_file():
        raise FileNotFoundError(f"native source {path} is missing (not yet written, or sewfmu "
                                f"installed without its native/ folder)")
    return path.read_bytes()


def native_sources(name: str, fmi: int) -> dict[str, bytes]:
    """Every C source and header the FMU compiles but description.c, by its name in the FMU's
    flat sources/ folder."""
    files = {Path(f).name: _read(RUNTIME, f) for f in (*RUNTIME_FILES, *FMI_FILES[fmi])}
    pending = list(MODEL_FILES[name])
    while pending:
        file = pending.pop()
        if file in files:
            continue
        files[file] = _read(MODELS, file)
        # the model headers it includes (the runtime's and the C library's are there already),
        # and the source beside each (parameters.h: parameters.c)
        for inc in (i.decode() for i in _INCLUDE.findall(files[file])):
            companion = inc[:-2] + ".c" if inc.endswith(".h") else ""
            pending += [f for f in (inc, companion)
                        if f and f not in files and (MODELS / f).is_file()]
    return dict(sorted(files.items()))


def _slave_class(name: str):
    module, slave = FMUS[name]
    return getattr(importlib.import_module(f"sewfmu.components.{module}"), slave)


def _documentation(page: bytes) -> bytes:
    """The Python FMU's page, with what a host needs said of the native FMU."""
    text = page.decode("utf-8")
    text = re.sub(r"(<h2>What a host needs</h2>\n<p>).*?(</p>)",
                  lambda m: m.group(1) + HOST_NEEDS + m.group(2), text, count=1, flags=re.S)
    return text.encode("utf-8")


def _compile(target, sources: Path, out: Path) -> NoCompiler | None:
    """Compile one binary; the NoCompiler of a missing compiler, or None."""
    out.parent.mkdir(parents=True, exist_ok=True)
    try:
        compile_binary(target, sources, out)
    except NoCompiler as err:
        return err
    return None


def build_native_fmu(name: str, dest: Path | None = None, fmi: int = 2,
                     python_dir: Path | None = None, left_out: set | None = None) -> Path:
    """Build the native FMU `name` for FMI `fmi` (2 or 3) into dest (default
    default_native_dir(fmi)); return its path. The Python FMU it is made from is taken from
    python_dir (default fmus/, fmus/fmi3/), built there if missing or stale. The targets left
    out for want of a compiler go into `left_out` (build_native_fmus says them once for all
    its FMUs); without it, one line on stderr says them."""
    if isinstance(fmi, bool) or fmi not in FMI_VERSIONS:
        raise ValueError(f"FMI version must be 2 or 3, got {fmi!r}")
    if name not in MODEL_FILES:
        raise KeyError(f"unknown FMU {name!r} (known: {', '.join(MODEL_FILES)})")
    dest = Path(dest or default_native_dir(fmi))
    python_fmu = _python_fmu(name, Path(python_dir or default_fmu_dir(fmi)), fmi)
    with zipfile.ZipFile(python_fmu) as archive:
        python_xml = archive.read("modelDescription.xml")
        carried = {n: archive.read(n) for n in archive.namelist()
                   if n.startswith(("extra/", "documentation/")) and not n.endswith("/")}
    root = ElementTree.fromstring(python_xml)
    sources = native_sources(name, fmi)
    description = description_c(root, fmi, _slave_class(name), f"SEW_MODEL_{name}")
    digest = hashlib.sha256(f"{name}\0{fmi}\0".encode())
    for file, data in (*sources.items(), ("description.c", description.encode())):
        digest.update(file.encode() + b"\0" + data + b"\0")
    token = token_of(digest.digest(), fmi)
    sources["description.c"] = description.replace(TOKEN_PLACEHOLDER, token).encode()
    sources = dict(sorted(sources.items()))
    xml = native_model_description(python_xml, fmi, token, native_version(),
                                   list(sources))
    writable(dest, REBUILD)
    missing = []
    with scratch_folder("native") as tmp:
        tmp = Path(tmp)
        source_dir = tmp / "sources"
        source_dir.mkdir()
        for file, data in sources.items():
            (source_dir / file).write_bytes(data)
        # the targets' compilers run side by side (each is one process)
        outs = [(t, tmp / "bin" / t.folders[fmi] / f"{name}{t.suffix}") for t in TARGETS]
        with ThreadPoolExecutor(len(outs)) as pool:
            done = [pool.submit(_compile, t, source_dir, out) for t, out in outs]
        binaries = {}
        for (target, out), result in zip(outs, done):
            why = result.result()
            if why:
                missing.append(why)
            else:
                binaries[f"binaries/{target.folders[fmi]}/{out.name}"] = out.read_bytes()
        if not binaries:
            raise NoCompiler("; ".join(str(m) for m in missing))
        if left_out is None and missing:
            print(f"sewfmu: {name}: {left_out_line(m.target for m in missing)}",
                  file=sys.stderr)
        elif missing:
            left_out.update(m.target for m in missing)
        built = tmp / f"{name}.fmu"
        with zipfile.ZipFile(built, "w", compression=zipfile.ZIP_DEFLATED) as fmu:
            fmu.writestr("modelDescription.xml", xml)
            for path, data in binaries.items():
                fmu.writestr(path, data)
            for file, data in sources.items():
                fmu.writestr(f"sources/{file}", data)
            if fmi == 3:
                fmu.writestr("sources/buildDescription.xml",
                             build_description_xml(name, list(sources)))
            for path, data in carried.items():
                if path == "documentation/index.html":
                    data = _documentation(data)
                fmu.writestr(path, data)
        return install(built, dest, name, REBUILD)


def build_native_fmus(names, dest: Path | None = None, fmi: int = 2,
                      python_dir: Path | None = None) -> list[Path]:
    """build_native_fmu of each name; the targets left out for want of a compiler are said in
    one line on stderr for all of them (after those built: a build stopped by an error says
    them too)."""
    left_out: set = set()
    try:
        return [build_native_fmu(name, dest, fmi=fmi, python_dir=python_dir, left_out=left_out)
                for name in names]
    finally:
        if left_out:
            print(f"sewfmu: {left_out_line(left_out)}", file=sys.stderr)


def build_all_native(dest: Path | None = None, fmi: int = 2,
                     names: list[str] | None = None) -> list[Path]:
    return build_native_fmus(names or list(MODEL_FILES), dest, fmi=fmi)


def _python_fmu(name: str, folder: Path, fmi: int) -> Path:
    """The Python FMU a native one mirrors, built where missing or carrying other code (not
    through up_to_date.ensure_built, which imports this builder to build native FMUs)."""
    path = folder / f"{name}.fmu"
    if fmu_version(path) != current_version():
        from sewfmu.scenarios.fmu_build.build import build_fmu  # pythonfmu's builders: only to build
        build_fmu(name, folder, fmi=fmi)
    return path
