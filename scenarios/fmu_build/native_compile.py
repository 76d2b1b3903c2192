"""The compilers of the native FMUs' binaries, from places a fresh machine reaches: the machine's
C compiler (gcc, cc) for x86-64 Linux; mingw-w64 (Debian's x86_64-w64-mingw32-gcc) for x86-64
Windows; else zig's C compiler from the package index (`pip install 'sewfmu[native]'`: the
ziglang package, `python -m ziglang cc`) for either. Always -ffp-contract=off: no fused
multiply-add, so that the numbers are the Python model's, which does not fuse. A Windows DLL
links libgcc and winpthread statically: it needs no DLL of mingw's beside it."""
from __future__ import annotations

import importlib.util
import platform
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from sewfmu.errors import Error
from sewfmu.scenarios.fmu_build.native_current import TARGET_FOLDERS
from sewfmu.scenarios.format.values import ScenarioError

FLAGS = ["-std=c99", "-O2", "-ffp-contract=off", "-Wall", "-Wextra"]
# the one line said where a target's compiler is missing
INSTALL_HINT = {
    "linux": "a C compiler for x86-64 Linux (gcc or cc): apt install gcc, or pip install "
             "'sewfmu[native]' (ziglang)",
    "windows": "a C compiler for x86-64 Windows (x86_64-w64-mingw32-gcc): apt install mingw-w64, "
               "or pip install 'sewfmu[native]' (ziglang)",
}


# a target whose compiler is missing, as the one line of a build says it: (what is left out,
# what was looked for, how to get one)
LEFT_OUT = {
    "linux": ("Linux binaries", "no gcc, cc or zig",
              "apt install gcc, or pip install 'sewfmu[native]'"),
    "windows": ("Windows binaries", "no mingw-w64 or zig",
                "apt install mingw-w64, or pip install 'sewfmu[native]'"),
}


class NoCompiler(Error, RuntimeError):
    """No compiler for a target: the message is the one line that says what to install;
    `target` names the target."""

    def __init__(self, message: str, target: str = ""):
        super().__init__(message)
        self.target = target


class CompilerFailed(ScenarioError, RuntimeError):
    """A compiler that is there but cannot compile even a one-line C file here (its C library's
    headers missing, a broken install): the machine's to mend, not sewfmu's; one line."""


def left_out_line(targets) -> str:
    """The one line of a build (of any number of FMUs) whose binaries for `targets` were left
    out, e.g. "Windows binaries left out: no mingw-w64 or zig; apt install mingw-w64, or pip
    install 'sewfmu[native]'"."""
    parts = [LEFT_OUT[t] for t in sorted(set(targets))]
    return "; ".join(f"{what} left out: {missing}; {how}" for what, missing, how in parts)


@dataclass(frozen=True)
class Target:
    name: str            # "linux" or "windows"
    suffix: str          # of the binary
    folders: dict        # FMI version -> the folder under binaries/


TARGETS = (
    Target("linux", ".so", TARGET_FOLDERS["linux"]),
    Target("windows", ".dll", TARGET_FOLDERS["windows"]),
)


def _zig() -> list[str] | None:
    if importlib.util.find_spec("ziglang") is None:
        return None
    return [sys.executable, "-m", "ziglang", "cc"]


def compiler_for(target: Target) -> tuple[list[str], list[str]]:
    """(command, extra flags) of a compiler for the target; NoCompiler where none is found."""
    native_linux = sys.platform.startswith("linux") and platform.machine() in ("x86_64", "AMD64")
    if target.name == "linux":
        cc = shutil.which("gcc") or shutil.which("cc")
        if cc and native_linux:
            return [cc], ["-fPIC", "-fvisibility=hidden"]
        zig = _zig()
        if zig:
            return zig, ["-target", "x86_64-linux-gnu", "-fPIC", "-fvisibility=hidden"]
    else:
        cc = shutil.which("x86_64-w64-mingw32-gcc")
        if cc:
            return [cc], ["-static-libgcc", "-static"]
        zig = _zig()
        if zig:
            return zig, ["-target", "x86_64-windows-gnu"]
    raise NoCompiler(f"sewfmu build --native: no compiler for {target.name}: needs "
                     f"{INSTALL_HINT[target.name]}", target.name)


def compile_binary(target: Target, sources: Path, out: Path) -> None:
    """Compile every .c in the folder `sources` (the FMU's own sources/, so that what is shipped
    is what was compiled) into the shared library `out`."""
    command, extra = compiler_for(target)
    files = sorted(str(p) for p in sources.glob("*.c"))
    args = [*command, *FLAGS, *extra, "-shared", f"-I{sources}", *files, "-o", str(out), "-lm"]
    done = subprocess.run(args, capture_output=True, text=True)
    if done.returncode != 0 or not out.exists():
        _check_compiler(target, command, extra, out.parent)
        # the compiler works, sewfmu's sources do not compile with it: sewfmu's bug
        raise RuntimeError(f"compiling {out.name} for {target.name} failed:\n"
                           f"{' '.join(args)}\n{done.stderr.strip()}")
    if done.stderr.strip():
        # warnings are shown, not fatal: tests/native holds the sources warning-free
        print(f"{out.name} ({target.name}): {done.stderr.strip()}", file=sys.stderr)


def _first_error(stderr: str) -> str:
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    return next((line for line in lines if "error" in line.lower()), lines[0] if lines else
                "no message")


def _check_compiler(target: Target, command: list[str], extra: list[str], folder: Path) -> None:
    """CompilerFailed where the compiler cannot build a one-line C file with the headers the
    FMUs include either (the machine's fault); else nothing (the FMU's sources are at fault)."""
    probe = folder / "sewfmu_probe.c"
    probe.write_text("#include <math.h>\n#include <stdio.h>\n#include <stdlib.h>\n"
                     "#include <string.h>\nint sewfmu_probe(double x) { return (int)floor(x); }\n")
    out = folder / f"sewfmu_probe{target.suffix}"
    done = subprocess.run([*command, *FLAGS, *extra, "-shared", str(probe), "-o", str(out),
                           "-lm"], capture_output=True, text=True)
    if done.returncode == 0 and out.exists():
        return
    first = _first_error(done.stderr).replace(str(probe), probe.name)
    if target.name == "windows":
        hint = "is mingw-w64 complete? (apt install mingw-w64)"
    elif "no such file" in first.lower() or ".h" in first:
        hint = "is libc6-dev installed? (apt install libc6-dev)"
    else:
        hint = "check that compiler's installation, or pip install 'sewfmu[native]' (ziglang)"
    raise CompilerFailed(f"sewfmu build --native: the C compiler {' '.join(command)} for "
                         f"{target.name} cannot compile a one-line C file: {first}; {hint}")
