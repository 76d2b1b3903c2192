"""The fixed-step Jacobi loop, compiled (jacobi_loop.c), for runs whose every instance is a native
sewfmu FMU: there the master's Python was ~all of a step's time (3 doSteps and 9 batched calls
through ctypes and the Python around them, ~19 µs; the FMUs' own work well under 1 µs).

`compiled_loop(master)` says whether a run may take it, once at its opening: the Jacobi master as
it is (no feedback loop, so no divergence watch and no settling), the recorder's whole-row mode,
no experiment.step_timeout (the watchdog names a stuck call from the Python stack), and only
native sewfmu FMUs called through the instances' own bound calls. Python FMUs never: their code
needs the interpreter, and the watchdog and guardian answer a Python FMU that hangs from the
Python loop's bookkeeping. Otherwise, or where no C compiler is found, the Python loop runs as
before (a debug line says why); SEWFMU_STEP_LOOP=python makes every run take it (to compare).

The library is compiled once, on first use, with a C compiler of this machine (found as the
native FMUs' builder finds its own) into the folder FOLDER of sewfmu's cache
(files/cache_root.py), or a temporary folder where the cache is off or cannot be written,
removed once the library is loaded (_drop_scratch).
"""
from __future__ import annotations

import atexit
import contextlib
import ctypes
import functools
import hashlib
import importlib.util
import logging
import os
import shutil
import sys
import tempfile
from pathlib import Path

import filelock
import numpy as np

from sewfmu.scenarios.cosim.algorithms.fixed_step import Jacobi
from sewfmu.scenarios.cosim.fmi_calls import FmiCallError
from sewfmu.scenarios.cosim.guardian import BEAT, CODE, WHERE, T
from sewfmu.scenarios.cosim.instances import Fmi2Instance, Fmi3Instance, Instance
from sewfmu.scenarios.cosim.recorder import Recorder
from sewfmu.scenarios.files.cache_root import SUBFOLDER, configured_root

log = logging.getLogger(__name__)

SOURCE = Path(__file__).with_name("jacobi_loop.c")
FOLDER = "stepper"              # in the cache's SUBFOLDER
NATIVE_TOOL = "sewfmu build --native"       # a native sewfmu FMU's generationTool begins so
# steps per call of the C loop: between two, Ctrl-C, close() and the clock are looked at (at
# ~1 µs a step, well under a millisecond)
CHUNK = 512
# False: every run takes the Python loop (the tests compare the two)
enabled = os.environ.get("SEWFMU_STEP_LOOP") != "python"

# why a chunk ended (jacobi_loop.c)
STEPS_DONE, CALL_FAILED, NOT_FINITE, ROW_NEEDS_PYTHON = range(4)
CALLS = {CODE["doStep"]: "doStep", CODE["set inputs"]: "set inputs",
         CODE["get outputs"]: "get outputs", CODE["get Boolean outputs"]: "get Boolean outputs"}

# the Python loop's pieces as this module found them: a run where one was replaced (a test's
# stand-in) keeps to the Python loop
_TWINS = (Jacobi.advance, Jacobi.exchange, Instance.exchange, Recorder._record_at_once,
          Fmi2Instance._do_step, Fmi3Instance._do_step)

_p, _d, _q = ctypes.c_void_p, ctypes.c_double, ctypes.c_int64


class SewInstance(ctypes.Structure):
    _fields_ = [("fmi", _q), ("no_set_prior", _q), ("where", _q), ("component", _p),
                ("do_step", _p), ("set_real", _p), ("get_real", _p), ("get_boolean", _p),
                ("event", _p), ("terminate", _p), ("early", _p), ("last_time", _p),
                ("n_in", _q), ("in_vr", _p), ("in_buf", _p), ("in_src", _p), ("in_a", _p),
                ("in_b", _p), ("n_out", _q), ("out_vr", _p), ("out_buf", _p), ("n_bool", _q),
                ("bool_vr", _p), ("bool_buf", _p)]


class SewRun(ctypes.Structure):
    _fields_ = [("n_inst", _q), ("inst", _p), ("h", _d), ("stop", _d), ("n", _q),
                ("every", _q), ("dense_k", _q), ("beat", _p), ("now", _p), ("where", _p),
                ("times", _p), ("reals", _p), ("outputs", _p), ("n_reals", _q),
                ("rows_cap", _q), ("n_flags", _q), ("flag_rows", _p), ("flag_now", _p),
                ("flag_bytes", _p), ("k", _q), ("length", _q), ("failed_inst", _q),
                ("failed_call", _q), ("failed_status", _q)]


def compiled_loop(master) -> "CompiledLoop | None":
    """The compiled loop for the run `master` has just opened, or None: the Python loop."""
    why = _refused(master)
    if why is None and library() is None:
        why = "no compiled loop (see the line above)"
    if why is not None:
        log.debug("the Python step loop: %s", why)
        return None
    return CompiledLoop(library(), master)


def _refused(master) -> str | None:
    """Why the run keeps to the Python loop, or None."""
    algorithm, system, recorder = master.algorithm, master.system, master.recorder
    if not enabled:
        return "stepper.enabled is off"
    if type(algorithm) is not Jacobi or algorithm.variable_step or \
            getattr(algorithm.advance, "__func__", None) is not _TWINS[0] or \
            algorithm.exchange is not _TWINS[1]:
        return "another master than Jacobi"
    if system.in_loops or master.watch is not None:
        return "a feedback loop (settled and watched by Python)"
    if master.scenario.step_timeout is not None:
        return "experiment.step_timeout (the watchdog reads the call from the Python stack)"
    if not recorder.at_once or getattr(recorder.record, "__func__", None) is not _TWINS[3]:
        return "records of some outputs only"
    if len({id(inst.board) for inst in system.instances}) > 1:
        return "instances on different boards"
    for inst in system.instances:
        if type(inst) not in (Fmi2Instance, Fmi3Instance) or inst.carried or \
                not str(getattr(inst.md, "generationTool", "")).startswith(NATIVE_TOOL):
            return f"{inst.name} is not a native sewfmu FMU"
        if type(inst).exchange is not _TWINS[2] or \
                type(inst)._do_step is not _TWINS[4 + (type(inst) is Fmi3Instance)] or \
                "_do_step" in vars(inst) or not all(
                    isinstance(call, functools.partial) for call in
                    (inst._set_reals, inst._get_reals, inst._get_booleans)):
            return f"{inst.name}'s calls are not its library's"
    return None


class CompiledLoop:
    """One open run's tables for jacobi_loop.c (pointers into the instances' buffers, which
    stay where they are for the run's life), and its chunks."""

    def __init__(self, lib, master):
        self.lib, self.master = lib, master
        system, recorder = master.system, master.recorder
        self.instances = instances = system.instances
        self._keep = []             # every ctypes array the tables point into
        self.table = (SewInstance * len(instances))(*[self._instance(inst, system.outputs)
                                                      for inst in instances])
        self.run = SewRun(n_inst=len(instances), inst=ctypes.addressof(self.table),
                          h=master.h, stop=master.stop, n=master.n_steps, every=master.every,
                          dense_k=master.dense_k, n_reals=len(system.outputs))
        self.run.outputs = system.outputs.ctypes.data
        self.run.n_flags = n_flags = len(recorder.flags)
        self._flag_rows = (_p * max(1, n_flags))()
        self._flag_now = (_p * max(1, n_flags))(*[now.ctypes.data
                                                  for now in recorder._flags_now])
        self._flag_bytes = (_q * max(1, n_flags))(*[now.nbytes for now in recorder._flags_now])
        self.run.flag_rows, self.run.flag_now, self.run.flag_bytes = (
            ctypes.addressof(a) for a in (self._flag_rows, self._flag_now, self._flag_bytes))
        self._board = None     # (the board's q, the instances' board): what the addresses are of

    def _instance(self, inst, outputs: np.ndarray) -> SewInstance:
        fmi3 = isinstance(inst, Fmi3Instance)

        def function(call):
            return ctypes.cast(inst._function(call), _p).value

        at = outputs.ctypes.data
        sources = (_p * max(1, inst.n_in))(
            *[at + 8 * (src.out_at + idx) for src, idx in inst.in_sources])
        scales = [(_d * max(1, inst.n_in))(*column) for column in zip(*inst.in_scales)] \
            if inst.in_scales is not None else []
        self._keep += [sources, *scales]
        results = [ctypes.addressof(x) for x in inst._step_results] if fmi3 else [None] * 4
        return SewInstance(
            fmi=3 if fmi3 else 2, no_set_prior=int(not inst.may_roll_back), where=inst.at,
            component=inst.component, do_step=function("do_step"),
            set_real=function("set_real"), get_real=function("get_real"),
            get_boolean=function("get_boolean"), event=results[0], terminate=results[1],
            early=results[2], last_time=results[3],
            n_in=inst.n_in, in_vr=ctypes.addressof(inst.in_vr),
            in_buf=ctypes.addressof(inst.in_buf), in_src=ctypes.addressof(sources),
            in_a=ctypes.addressof(scales[0]) if scales else None,
            in_b=ctypes.addressof(scales[1]) if scales else None,
            n_out=inst.n_out, out_vr=ctypes.addressof(inst.out_vr),
            out_buf=ctypes.addressof(inst.out_buf), n_bool=inst.n_bool,
            bool_vr=ctypes.addressof(inst.bool_vr), bool_buf=ctypes.addressof(inst.bool_buf))

    def _note_boards(self, paper) -> None:
        """The addresses of the board's beat and time (the run's now) and of the instances'
        WHERE (the board they were given at the opening)."""
        where = self.instances[0].board if self.instances else paper.q
        if self._board is None or self._board[0] is not paper.q or self._board[1] is not where:
            self.run.beat = ctypes.addressof(_q.from_buffer(paper.q)) + 8 * BEAT
            self.run.now = ctypes.addressof(_d.from_buffer(paper.d)) + 8 * T
            self.run.where = ctypes.addressof(_q.from_buffer(where)) + 8 * WHERE
            self._board = (paper.q, where)

    def steps(self, k: int, end: int, paper) -> tuple[int, FmiCallError | None]:
        """Steps from k up to `end`, recorded: (the steps done, the failure of the step k
        they stopped at, or None)."""
        run, recorder = self.run, self.master.recorder
        self._note_boards(paper)
        run.k = k
        while True:
            run.times, run.reals = recorder.times.ctypes.data, recorder.reals.ctypes.data
            for f, rows in enumerate(recorder.flags):
                self._flag_rows[f] = rows.ctypes.data
            run.rows_cap, run.length = len(recorder.times), recorder.length
            why = self.lib.sew_jacobi_steps(ctypes.byref(run), end)
            recorder.length = run.length
            if why != ROW_NEEDS_PYTHON:
                break
            m = self.master            # a row the recorder has no room for: its own words
            recorder.record(m.stop if run.k == m.n_steps else run.k * m.h)
        if why == STEPS_DONE:
            return run.k, None
        inst = self.instances[run.failed_inst]
        try:          # the error the Python loop raises, by the same code
            if why == NOT_FINITE:
                inst._refuse_non_finite_outputs()
            inst.check(CALLS[run.failed_call], run.failed_status)
        except FmiCallError as err:
            return run.k, err
        raise AssertionError(f"jacobi_loop.c stopped ({why}) where Python goes on")


# --- the library ---------------------------------------------------------------------------------
_loaded: list = []          # [the library, or None where it cannot be had]: once per process


def library():
    """jacobi_loop.c compiled and loaded (its function typed), or None (a debug line says why)."""
    if not _loaded:
        try:
            path, scratch = _compiled()
            try:
                lib = ctypes.CDLL(str(path))
            finally:
                if scratch is not None:
                    _drop_scratch(scratch)
            lib.sew_jacobi_steps.argtypes = [ctypes.POINTER(SewRun), _q]
            lib.sew_jacobi_steps.restype = ctypes.c_int
        except Exception as err:         # no compiler, a failed compile: the Python loop
            log.debug("jacobi_loop.c not compiled: %s", " ".join(str(err).split()))
            lib = None
        _loaded.append(lib)
    return _loaded[0]


def _host_compiler() -> tuple[list[str], list[str]]:
    """(command, flags) of a C compiler for this machine, found as fmu_build/native_compile.py
    finds the native FMUs' (which the run's wing may not import: tests/test_layout.py): the
    machine's gcc or cc (mingw-w64's on Windows), else zig's from the package index."""
    names = ("x86_64-w64-mingw32-gcc", "gcc", "cc") if sys.platform == "win32" else \
        ("gcc", "cc", "clang")
    cc = next((found for name in names if (found := shutil.which(name))), None)
    if cc is not None:
        command = [cc]
    elif importlib.util.find_spec("ziglang") is not None:
        command = [sys.executable, "-m", "ziglang", "cc"]
    else:
        raise FileNotFoundError("no C compiler (gcc, cc, or the ziglang package)")
    # the builder's flags: no fused multiply-add, so that the numbers are the Python loop's
    flags = ["-std=c99", "-O2", "-ffp-contract=off", "-Wall", "-Wextra", "-shared"]
    return command, flags + ([] if sys.platform == "win32" else ["-fPIC"])


def _drop_scratch(folder: Path) -> None:
    """Remove the temporary folder a library was compiled into (the cache off or unwritable):
    on Linux and macOS at once, the loaded library stays mapped; on Windows, where a loaded DLL
    cannot be removed, at exit (what is loaded then stays: best effort)."""
    if sys.platform == "win32":
        atexit.register(shutil.rmtree, folder, ignore_errors=True)
    else:
        shutil.rmtree(folder, ignore_errors=True)


def _compiled() -> tuple[Path, Path | None]:
    """The library's file: from the cache, or compiled now (into it where it can be written);
    and the temporary folder it was compiled into where the cache is off or unwritable (the
    caller removes it once the library is loaded), else None."""
    import subprocess  # only to compile, once per cache

    command, flags = _host_compiler()
    source = SOURCE.read_bytes()
    key = hashlib.sha256(b"\0".join([source, *(a.encode() for a in (*command, *flags)),
                                     sys.platform.encode()])).hexdigest()[:16]
    name = f"jacobi_loop-{key}{'.dll' if sys.platform == 'win32' else '.so'}"
    root = configured_root()
    folder = root / SUBFOLDER / FOLDER if root is not None else None
    try:
        folder.mkdir(parents=True, exist_ok=True)
        lock = filelock.FileLock(str(folder / f".{name}.lock"))
        lock.acquire(timeout=60)
    except (AttributeError, OSError, filelock.Timeout):
        folder, lock = Path(tempfile.mkdtemp(prefix="sewfmu-stepper-")), None
    scratch_folder = folder if lock is None else None
    try:
        out = folder / name
        if not out.is_file():
            scratch = folder / f".{name}.{os.getpid()}"
            done = subprocess.run([*command, *flags, str(SOURCE), "-o", str(scratch), "-lm"],
                                  capture_output=True, text=True)
            if done.returncode != 0 or not scratch.is_file():
                raise RuntimeError(f"{' '.join(command)} failed: {done.stderr.strip()}")
            os.replace(scratch, out)
            # the libraries of earlier sources go (one a process has loaded stays loaded)
            for stale in folder.glob(f"jacobi_loop-*{out.suffix}"):
                if stale != out:
                    for path in (stale, folder / f".{stale.name}.lock"):
                        with contextlib.suppress(OSError):
                            path.unlink()
        return out, scratch_folder
    except BaseException:
        if scratch_folder is not None:
            shutil.rmtree(scratch_folder, ignore_errors=True)
        raise
    finally:
        if lock is not None:
            lock.release()
