"""A native FMU built where no Windows compiler was (linux64 only) is out of date once a compiler
for Windows is found: the next run or export rebuilds it with the DLL (attack46b, failure 1). The
zip is read only for a current native FMU, once per process while the file is unchanged; the
compilers are looked for only where a binary is missing. An export whose native FMUs still lack
the Windows binary says so in one line."""
from __future__ import annotations

import os
import shutil
import zipfile

import pytest

from sewfmu.scenarios.fmu_build import native_compile, native_current, up_to_date
from sewfmu.scenarios.fmu_build.native_compile import NoCompiler
from sewfmu.scenarios.fmu_build.native_current import missing_targets, without_windows_line


def _fmu(path, folders, version=None):
    """A stand-in native FMU: a modelDescription with `version`, a binary in each folder."""
    version = version or native_current.native_version()
    with zipfile.ZipFile(path, "w") as fmu:
        fmu.writestr("modelDescription.xml",
                     f'<fmiModelDescription fmiVersion="2.0" version="{version}"/>')
        for folder in folders:
            fmu.writestr(f"binaries/{folder}/M.bin", b"\0")
        fmu.writestr("sources/m.c", "int m;\n")
    return path


def test_the_targets_a_native_fmu_lacks(tmp_path):
    assert missing_targets(_fmu(tmp_path / "a.fmu", ["linux64"])) == ["windows"]
    assert missing_targets(_fmu(tmp_path / "b.fmu", ["x86_64-windows"])) == ["linux"]
    assert missing_targets(_fmu(tmp_path / "c.fmu", ["linux64", "win64"])) == []
    assert missing_targets(_fmu(tmp_path / "d.fmu", [])) == ["linux", "windows"]
    assert missing_targets(tmp_path / "none.fmu") == []


def test_the_zip_is_read_once_while_the_file_is_unchanged(tmp_path, monkeypatch):
    path = _fmu(tmp_path / "a.fmu", ["linux64"])
    opened = []
    real = zipfile.ZipFile
    monkeypatch.setattr(native_current.zipfile, "ZipFile",
                        lambda *a, **k: (len(a) == 1 and opened.append(a)) or real(*a, **k))
    for _ in range(3):
        assert missing_targets(path) == ["windows"]
    assert len(opened) == 1
    _fmu(path, ["linux64", "win64"])
    os.utime(path, ns=(1, 1))                     # another stat, whatever the clock's grain
    assert missing_targets(path) == []
    assert len(opened) == 2


@pytest.fixture
def rebuilt(monkeypatch):
    """The native builds ensure_built asks for (none is made)."""
    asked = []

    def build(name, dest, fmi, python_dir, left_out=None):
        asked.append(name)
        _fmu(dest / f"{name}.fmu", ["linux64", "win64"])
        return dest / f"{name}.fmu"
    monkeypatch.setattr(up_to_date, "_build_native", build)
    return asked


def _compilers(monkeypatch, windows: bool):
    looked = []

    def compiler_for(target):
        looked.append(target.name)
        if target.name == "windows" and not windows:
            raise NoCompiler("no compiler for windows", "windows")
        return ["cc"], []
    monkeypatch.setattr(native_compile, "compiler_for", compiler_for)
    return looked


def test_a_linux_only_fmu_is_rebuilt_once_a_windows_compiler_is_found(tmp_path, monkeypatch,
                                                                       rebuilt):
    _fmu(tmp_path / "MainShaft.fmu", ["linux64"])
    _compilers(monkeypatch, windows=True)
    up_to_date.ensure_built(["MainShaft"], tmp_path, kind="native")
    assert rebuilt == ["MainShaft"]
    assert missing_targets(tmp_path / "MainShaft.fmu") == []
    up_to_date.ensure_built(["MainShaft"], tmp_path, kind="native")     # now complete
    assert rebuilt == ["MainShaft"]


def test_a_linux_only_fmu_stays_without_a_windows_compiler(tmp_path, monkeypatch, rebuilt):
    _fmu(tmp_path / "MainShaft.fmu", ["linux64"])
    _compilers(monkeypatch, windows=False)
    paths = up_to_date.ensure_built(["MainShaft"], tmp_path, kind="native")
    assert rebuilt == [] and paths["MainShaft"] == tmp_path / "MainShaft.fmu"


def test_a_complete_fmu_looks_for_no_compiler(tmp_path, monkeypatch, rebuilt):
    _fmu(tmp_path / "MainShaft.fmu", ["linux64", "win64"])
    looked = _compilers(monkeypatch, windows=True)
    up_to_date.ensure_built(["MainShaft"], tmp_path, kind="native")
    assert rebuilt == [] and looked == []


def test_a_folder_that_cannot_be_written_keeps_its_fmus(tmp_path, monkeypatch, rebuilt):
    _fmu(tmp_path / "MainShaft.fmu", ["linux64"])
    _compilers(monkeypatch, windows=True)
    monkeypatch.setattr(up_to_date.os, "access", lambda path, mode: False)
    up_to_date.ensure_built(["MainShaft"], tmp_path, kind="native")
    assert rebuilt == []


def test_an_export_without_windows_binaries_says_so_in_one_line(tmp_path):
    paths = {"MainShaft": _fmu(tmp_path / "MainShaft.fmu", ["linux64"]),
             "PunchBody": _fmu(tmp_path / "PunchBody.fmu", ["x86_64-linux"]),
             "Fabric": _fmu(tmp_path / "Fabric.fmu", ["linux64", "win64"])}
    line = without_windows_line(paths, "export-ssp")
    assert line.startswith("export-ssp: the native FMUs MainShaft, PunchBody inside have no "
                           "Windows binary")
    assert "cannot run on Windows" in line and "\n" not in line
    assert without_windows_line({"Fabric": paths["Fabric"]}, "export-ssp") is None


@pytest.mark.slow
@pytest.mark.skipif(not shutil.which("x86_64-w64-mingw32-gcc"), reason="needs mingw-w64")
def test_fmus_built_before_mingw_get_their_dlls_and_the_export_says_so_until_then(
        native_fmu, tmp_path, monkeypatch, capsys):
    from sewfmu.cli import main  # the command line, as the attack used it

    names = ["MainShaft", "PunchLinkage", "PunchContact"]
    for name in names:
        native_fmu(name, 2)             # their Python FMUs, built once for the session
    shutil.copytree(native_fmu(names[0], 2).parent.parent / "python2", tmp_path / "fmus")
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(tmp_path / "fmus"))
    native = tmp_path / "fmus" / "native"
    args = ["punch_drive", "--set", "experiment.fmus=native", "--set", "experiment.revolutions=2"]
    with monkeypatch.context() as no_mingw:
        real = shutil.which
        no_mingw.setattr(native_compile.shutil, "which",
                         lambda name: None if "mingw" in name else real(name))
        no_mingw.setattr(native_compile, "_zig", lambda: None)
        capsys.readouterr()
        assert main(["export-ssp", *args[:1], "-o", str(tmp_path / "a.ssp"), *args[1:]]) == 0
        err = capsys.readouterr().err
        assert [n for n in names if missing_targets(native / f"{n}.fmu") != ["windows"]] == []
        assert "export-ssp: the native FMUs MainShaft, PunchContact, PunchLinkage inside have " \
               "no Windows binary" in err
    capsys.readouterr()
    assert main(["export-ssp", *args[:1], "-o", str(tmp_path / "b.ssp"), *args[1:]]) == 0
    assert "Windows" not in capsys.readouterr().err
    with zipfile.ZipFile(tmp_path / "b.ssp") as ssp:
        for name in names:
            ssp.extract(f"resources/{name}.fmu", tmp_path / "b")
    for name in names:
        with zipfile.ZipFile(tmp_path / "b" / "resources" / f"{name}.fmu") as fmu:
            assert f"binaries/win64/{name}.dll" in fmu.namelist()
