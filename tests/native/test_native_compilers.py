"""The native FMUs' C: the runtime and the FMI glue compile without a warning under the
project's C rules for both targets (gcc, mingw-w64); a missing compiler is said in one line
that names it and how to install it, and a build without the Windows one still gives the Linux
binary."""
from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from sewfmu.scenarios.fmu_build import native_compile
from sewfmu.scenarios.fmu_build.native import MODEL_FILES, MODELS, RUNTIME, build_native_fmu

CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-O2", "-ffp-contract=off"]
FILES = [RUNTIME / "sew_slave.c", RUNTIME / "sew_state.c", MODELS / "parameters.c",
         MODELS / "shaft.c"]


@pytest.mark.parametrize("compiler", ["gcc", "x86_64-w64-mingw32-gcc"])
def test_the_runtime_compiles_without_a_warning(compiler, tmp_path):
    if not shutil.which(compiler):
        pytest.skip(f"no {compiler}")
    for glue, headers in ((("fmi2_glue.c",), "fmi2"),
                          (("fmi3_glue.c", "fmi3_unsupported.c"), "fmi3")):
        files = [str(f) for f in (*FILES, *(RUNTIME / g for g in glue))]
        done = subprocess.run([compiler, *CFLAGS, "-c", f"-I{RUNTIME}", f"-I{RUNTIME / headers}",
                               *files], capture_output=True, text=True, cwd=tmp_path)
        assert done.returncode == 0 and not done.stderr, done.stderr


def _no_compilers(monkeypatch, *missing):
    real = shutil.which
    names = {"linux": ("gcc", "cc"), "windows": ("x86_64-w64-mingw32-gcc",)}
    gone = {n for target in missing for n in names[target]}
    monkeypatch.setattr(native_compile.shutil, "which",
                        lambda name: None if name in gone else real(name))
    monkeypatch.setattr(native_compile, "_zig", lambda: None)


@pytest.mark.parametrize("target", native_compile.TARGETS, ids=lambda t: t.name)
def test_a_missing_compiler_is_one_line_naming_it_and_its_installation(monkeypatch, target):
    _no_compilers(monkeypatch, target.name)
    with pytest.raises(native_compile.NoCompiler) as caught:
        native_compile.compiler_for(target)
    text = str(caught.value)
    assert "\n" not in text
    assert "pip install 'sewfmu[native]' (ziglang)" in text
    assert ("apt install mingw-w64" if target.name == "windows" else "gcc") in text


@pytest.mark.slow
def test_a_build_without_the_windows_compiler_gives_the_linux_binary(monkeypatch, tmp_path,
                                                                     capsys):
    _no_compilers(monkeypatch, "windows")
    fmu = build_native_fmu("MainShaft", tmp_path / "native", python_dir=tmp_path / "python")
    with zipfile.ZipFile(fmu) as archive:
        names = archive.namelist()
    assert "binaries/linux64/MainShaft.so" in names
    assert not any(n.startswith("binaries/win64") for n in names)
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "Windows binaries left out: no mingw-w64" in lines[0], lines


@pytest.mark.slow
def test_a_build_without_any_compiler_is_refused_in_lines_naming_them(monkeypatch, tmp_path):
    _no_compilers(monkeypatch, "windows", "linux")
    with pytest.raises(native_compile.NoCompiler, match="apt install mingw-w64"):
        build_native_fmu("MainShaft", tmp_path / "native", python_dir=tmp_path / "python")


@pytest.mark.slow
def test_without_mingw_zig_builds_the_windows_binary(monkeypatch, tmp_path):
    # zig's first run builds its C library for the target (minutes), later ones take seconds
    if native_compile._zig() is None:
        pytest.skip("ziglang is not installed (pip install 'sewfmu[native]')")
    real = shutil.which
    monkeypatch.setattr(native_compile.shutil, "which",
                        lambda name: None if "mingw" in name else real(name))
    fmu = build_native_fmu("MainShaft", tmp_path / "native", python_dir=tmp_path / "python")
    with zipfile.ZipFile(fmu) as archive:
        dll = archive.read("binaries/win64/MainShaft.dll")
    assert dll[:2] == b"MZ"
    (tmp_path / "M.dll").write_bytes(dll)
    objdump = shutil.which("x86_64-w64-mingw32-objdump") or shutil.which("objdump")
    if objdump:
        table = subprocess.run([objdump, "-p", str(tmp_path / "M.dll")], capture_output=True,
                               text=True).stdout.lower()
        assert "python" not in table and "libgcc" not in table and "winpthread" not in table


@pytest.mark.slow
def test_sewfmu_build_native_writes_the_native_folder(tmp_path):
    done = subprocess.run([sys.executable, "-m", "sewfmu", "build", "--native", "--fmi", "3",
                           "--dest", str(tmp_path)], capture_output=True, text=True,
                          timeout=900)
    assert done.returncode == 0, done.stderr
    built = sorted(Path(line).name for line in done.stdout.split())
    assert built == sorted(f"{name}.fmu" for name in MODEL_FILES)
    assert sorted(p.name for p in (tmp_path / "native" / "fmi3").glob("*.fmu")) == built
