"""The hosts of tests/native/test_hosts_without_python.py, none of which holds a Python: the C host
of c_host/ compiled for Linux (gcc) and for Windows (mingw-w64, run under Wine in a prefix of its
own), in an environment with nothing of Python in it."""
from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from tests.paths import REPO

C_HOST = Path(__file__).resolve().parent / "c_host"
# a machine's plain environment: no PYTHONHOME, PYTHONPATH, LD_PRELOAD, LD_LIBRARY_PATH, no venv
NO_PYTHON = {"PATH": "/usr/bin:/bin"}
# the C rules of the native FMUs (notes: C99, no FMA), warnings as the failure they are
CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-O2", "-ffp-contract=off"]
MINGW = "x86_64-w64-mingw32-gcc"
# fmi2Error, fmi3Error
ERROR = 3


def fmi_headers() -> list[Path]:
    """The folders of the FMI 2.0 and 3.0 headers: the runtime's own copies, else fmpy's."""
    runtime = REPO / "native" / "runtime"
    if (runtime / "fmi2" / "fmi2FunctionTypes.h").exists() \
            and (runtime / "fmi3" / "fmi3FunctionTypes.h").exists():
        return [runtime / "fmi2", runtime / "fmi3"]
    import fmpy  # only where the runtime has no headers yet: fmpy ships both versions'

    return [Path(fmpy.__file__).parent / "c-code"]


def compile_host(compiler: str, out: Path) -> tuple[Path, str]:
    """The C host built by `compiler` into `out`: (its path, the compiler's messages)."""
    sources = sorted(str(p) for p in C_HOST.glob("*.c"))
    libs = [] if "mingw" in compiler else ["-ldl", "-lm"]
    includes = [f"-I{folder}" for folder in fmi_headers()]
    proc = subprocess.run([compiler, *CFLAGS, *includes, "-o", str(out), *sources, *libs],
                          capture_output=True, text=True, timeout=300)
    if proc.returncode != 0:
        raise RuntimeError(f"{compiler} cannot build the C host:\n{proc.stderr[-3000:]}")
    return out, proc.stderr


def find_wine() -> str | None:
    """Debian's 64-bit Wine loader: wine64 on PATH, in /usr/lib/wine (Debian 12 keeps it there),
    else the `wine` wrapper."""
    for candidate in (shutil.which("wine64"), "/usr/lib/wine/wine64", shutil.which("wine")):
        if candidate and os.access(candidate, os.X_OK):
            return candidate
    return None


class Wine:
    """Wine with a prefix of its own in `folder`, made once (`wineboot -i`, then waiting for
    wineserver to finish writing it; `seconds` says how long that took), and one wineserver with
    Wine's services kept running for the session, so that a run starts in a fraction of a second.
    Debian's wineserver otherwise exits with its last program (-p0), and every run would boot
    the services again, about 2.5 s."""

    def __init__(self, loader: str, folder: Path):
        self.loader = loader
        server = Path(loader).with_name("wineserver")
        self.server = str(server) if server.exists() else shutil.which("wineserver") or ""
        self.folder = folder
        folder.mkdir(parents=True, exist_ok=True)
        # no display (no window may open), no debug chatter, no offer to install Mono or Gecko
        self.env = {**NO_PYTHON, "HOME": str(folder), "WINEPREFIX": str(folder / "prefix"),
                    "WINEDEBUG": "-all", "WINEDLLOVERRIDES": "mscoree,mshtml="}
        start = time.monotonic()
        quiet = {"env": self.env, "stdin": subprocess.DEVNULL, "stdout": subprocess.DEVNULL,
                 "stderr": subprocess.DEVNULL}
        booted = subprocess.run([loader, "wineboot", "-i"], timeout=600, **quiet)
        if booted.returncode != 0:
            raise RuntimeError(f"wine64 wineboot -i fails with exit status {booted.returncode}")
        if self.server:
            subprocess.run([self.server, "-w"], timeout=600, **quiet)
        self.seconds = time.monotonic() - start
        # the lasting server and services, started with none of our pipes: a service a run
        # started would hold that run's stdout open for as long as it lives
        if self.server:
            subprocess.run([self.server, "-p"], timeout=60, **quiet)
        subprocess.run([loader, "wineboot"], timeout=600, **quiet)

    def run(self, exe: Path, *args: str, timeout: float = 300) -> subprocess.CompletedProcess:
        """The program's exit status, stdout and stderr: through files, not pipes, so that
        the end of the program is the end of the run whatever Wine starts beside it."""
        with tempfile.TemporaryFile(dir=self.folder) as out, \
                tempfile.TemporaryFile(dir=self.folder) as err:
            proc = subprocess.run([self.loader, str(exe), *args], env=self.env, timeout=timeout,
                                  stdin=subprocess.DEVNULL, stdout=out, stderr=err)
            out.seek(0)
            err.seek(0)
            return subprocess.CompletedProcess(proc.args, proc.returncode,
                                               out.read().decode("utf-8", "replace"),
                                               err.read().decode("utf-8", "replace"))

    def close(self) -> None:
        """Stop the server and its services, and remove the prefix (700 MB)."""
        if self.server:
            subprocess.run([self.server, "-k"], env=self.env, timeout=60,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        shutil.rmtree(self.env["WINEPREFIX"], ignore_errors=True)


def windows_path(path: Path) -> str:
    """A path of this machine as a Windows program under Wine names it (Wine's Z: is /)."""
    return "Z:" + str(Path(path).resolve()).replace("/", "\\")


def run_linux(host: Path, *args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([str(host), *args], env=NO_PYTHON, capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL)


def read_rows(stdout: str) -> tuple[list[str], np.ndarray]:
    """The C host's CSV: (its columns, "time" then value references; its rows)."""
    lines = stdout.splitlines()
    columns = lines[0].split(",")
    rows = np.array([[float(x) for x in line.split(",")] for line in lines[1:] if line],
                    dtype=float).reshape(-1, len(columns))
    return columns, rows


def differing(got: np.ndarray, want: np.ndarray, rtol: float = 1e-9) -> np.ndarray:
    """Where two arrays differ by more than rtol relative (NaN equals NaN)."""
    same = (got == want) | (np.isnan(got) & np.isnan(want))
    close = np.abs(got - want) <= rtol * np.maximum(np.abs(got), np.abs(want))
    return ~(same | close)
