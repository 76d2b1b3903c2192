"""What a native build says about the machine's compilers, each in one line: the targets left
out for want of a compiler once per build or run (not once per FMU), naming them and how to get
one; a compiler that is there but cannot compile even a one-line C file (gcc without the C
library's headers) as the machine's fault with a hint, not as a bug of sewfmu's."""
from __future__ import annotations

import os
import shutil
import zipfile

import pytest

from sewfmu import api
from sewfmu.errors import Error
from sewfmu.scenarios.fmu_build import native_compile
from sewfmu.scenarios.fmu_build.native_compile import TARGETS, CompilerFailed, left_out_line
from sewfmu.scenarios.fmu_build.up_to_date import ensure_built
from sewfmu.scenarios.format.values import ScenarioError

LINUX = TARGETS[0]
WINDOWS_LEFT_OUT = ("sewfmu: Windows binaries left out: no mingw-w64 or zig; apt install "
                    "mingw-w64, or pip install 'sewfmu[native]'")
NAMES = ["MainShaft", "PunchContact"]


def _fake_gcc(tmp_path, monkeypatch, message: str) -> None:
    """A `gcc` first on PATH that prints `message` and fails, as gcc without libc6-dev does."""
    folder = tmp_path / "fakebin"
    folder.mkdir()
    gcc = folder / "gcc"
    gcc.write_text(f"#!/bin/sh\necho '{message}' >&2\nexit 1\n")
    gcc.chmod(0o755)
    monkeypatch.setenv("PATH", f"{folder}:{os.environ['PATH']}")


def _sources(tmp_path, text: str):
    folder = tmp_path / "sources"
    folder.mkdir()
    (folder / "m.c").write_text(text)
    return folder


def test_the_left_out_line_names_the_target_what_is_missing_and_how_to_get_it():
    assert f"sewfmu: {left_out_line(['windows'])}" == WINDOWS_LEFT_OUT
    both = left_out_line(["windows", "linux", "windows"])
    assert both.count("left out") == 2 and "\n" not in both and "apt install gcc" in both


@pytest.mark.skipif(shutil.which("sh") is None, reason="a shell script as the fake compiler")
def test_a_compiler_without_the_c_headers_is_one_line_with_a_hint(tmp_path, monkeypatch):
    _fake_gcc(tmp_path, monkeypatch, "m.c:1:10: fatal error: stdio.h: No such file or directory")
    out = tmp_path / "out" / "M.so"
    out.parent.mkdir()
    with pytest.raises(CompilerFailed) as caught:
        native_compile.compile_binary(LINUX, _sources(tmp_path, "int f(void) { return 0; }\n"),
                                      out)
    text = str(caught.value)
    assert isinstance(caught.value, ScenarioError) and isinstance(caught.value, Error)
    assert "\n" not in text and len(text) < 400, text
    assert "gcc" in text and "for linux" in text, text
    assert "fatal error: stdio.h: No such file or directory" in text, text
    assert "is libc6-dev installed?" in text and "bug" not in text, text


def test_sources_that_do_not_compile_with_a_working_compiler_stay_sewfmus_bug(tmp_path):
    if not shutil.which("gcc"):
        pytest.skip("no gcc")
    out = tmp_path / "out" / "M.so"
    out.parent.mkdir()
    with pytest.raises(RuntimeError) as caught:
        native_compile.compile_binary(LINUX, _sources(tmp_path, "int f(void) { return }\n"), out)
    assert not isinstance(caught.value, CompilerFailed)


def _no_windows_compiler(monkeypatch):
    real = shutil.which
    monkeypatch.setattr(native_compile.shutil, "which",
                        lambda name: None if "mingw" in name else real(name))
    monkeypatch.setattr(native_compile, "_zig", lambda: None)


def _linux_only(fmu) -> bool:
    with zipfile.ZipFile(fmu) as archive:
        folders = {n.split("/")[1] for n in archive.namelist() if n.startswith("binaries/")}
    return folders == {"linux64"}


@pytest.mark.slow
def test_a_runs_rebuild_without_mingw_says_so_once(native_fmu, tmp_path, monkeypatch, capsys):
    python_dir = native_fmu(NAMES[0], 2).parent.parent / "python2"
    for name in NAMES:
        native_fmu(name, 2)            # their Python FMUs, built once for the session
    capsys.readouterr()
    _no_windows_compiler(monkeypatch)
    # a run's FMUs that are missing or stale: rebuilt as `sewfmu run` does (up_to_date)
    paths = ensure_built(NAMES, tmp_path / "native", kind="native", python_dir=python_dir)
    assert capsys.readouterr().err.strip().splitlines() == [WINDOWS_LEFT_OUT]
    assert all(_linux_only(paths[name]) for name in NAMES)


@pytest.mark.slow
def test_build_native_without_mingw_says_so_once(native_fmu, tmp_path, monkeypatch, capsys):
    for name in NAMES:
        shutil.copy2(native_fmu(name, 2).parent.parent / "python2" / f"{name}.fmu", tmp_path)
    capsys.readouterr()
    _no_windows_compiler(monkeypatch)
    built = api.build(2, tmp_path, names=NAMES, native=True)
    assert capsys.readouterr().err.strip().splitlines() == [WINDOWS_LEFT_OUT]
    assert [p.name for p in built] == [f"{name}.fmu" for name in NAMES]
    assert all(_linux_only(p) for p in built)
