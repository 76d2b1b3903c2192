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

FLAGS = ["-std=c99", "-O2", "-ffp-contract=off", "-Wall", "-Wextra"]
# the one line said where a target's compiler is missing
INSTALL_HINT = {
    "linux": "a C compiler for x86-64 Linux (gcc or cc): apt install gcc, or pip install "
             "'sewfmu[native]' (ziglang)",
    "windows": "a C compiler for x86-64 Windows (x86_64-w64-mingw32-gcc): apt install mingw-w64, "
               "or pip install 'sewfmu[native]' (ziglang)",
}


class NoCompiler(Error, RuntimeError):
    """No compiler for a target: the message is the one line that says what to install."""


@dataclass(frozen=True)
class Target:
    name: str            # "linux" or "windows"
    suffix: str          # of the binary
    folders: dict        # FMI version -> the folder under binaries/


TARGETS = (
    Target("linux", ".so", {2: "linux64", 3: "x86_64-linux"}),
    Target("windows", ".dll", {2: "win64", 3: "x86_64-windows"}),
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
                     f"{INSTALL_HINT[target.name]}")


def compile_binary(target: Target, sources: Path, out: Path) -> None:
    """Compile every .c in the folder `sources` (the FMU's own sources/, so that what is shipped
    is what was compiled) into the shared library `out`."""
    command, extra = compiler_for(target)
    files = sorted(str(p) for p in sources.glob("*.c"))
    args = [*command, *FLAGS, *extra, "-shared", f"-I{sources}", *files, "-o", str(out), "-lm"]
    done = subprocess.run(args, capture_output=True, text=True)
    if done.returncode != 0 or not out.exists():
        raise RuntimeError(f"compiling {out.name} for {target.name} failed:\n"
                           f"{' '.join(args)}\n{done.stderr.strip()}")
    if done.stderr.strip():
        # warnings are shown, not fatal: tests/native holds the sources warning-free
        print(f"{out.name} ({target.name}): {done.stderr.strip()}", file=sys.stderr)
