"""An FMU file that cannot run here is refused in one line naming why, at every door that reads
one (a scenario's instance, `sewfmu references --fmu`, an SSP archive, the run's loading): a
modelDescription.xml that is not XML, or is `<html/>`, or is missing, a zip that is no FMU, a
file that is no zip; an FMU without a binary for this platform (FMI 2.0 linux64, FMI 3.0
x86_64-linux), naming the platforms it has; one whose binary folder lacks its modelIdentifier's
library. Each is made from a built FMU by rewriting its zip. Before, fmpy's AttributeError,
KeyError or BadZipFile came out raw, or "instantiate returned FATAL"."""
import zipfile
from pathlib import Path

import fmpy
import pytest

import sewfmu
from sewfmu.cli import main
from sewfmu.scenarios.cosim.instances import extracted_fmu


def _rewrite(src: Path, dst: Path, change) -> Path:
    """A copy of the FMU with each member passed through change(name, data) -> (name, data) or
    None (left out)."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
        for name in zin.namelist():
            out = change(name, zin.read(name))
            if out is not None:
                zout.writestr(*out)
    return dst


def _md(text: bytes):
    return lambda name, data: (name, text if name == "modelDescription.xml" else data)


BROKEN = {   # kind -> (how the FMU is changed, what the one line says)
    "not XML": (_md(b"this is not XML <<"), "its modelDescription.xml is not XML"),
    "html": (_md(b"<html/>"), "root element is <html>, not <fmiModelDescription>"),
    "no modelDescription": (lambda n, d: None if n == "modelDescription.xml" else (n, d),
                            "is not an FMU: it has no modelDescription.xml"),
}


def _broken(tmp_path, fmu_paths, kind) -> Path:
    path = tmp_path / "Shaft.fmu"
    if kind == "not a zip":
        path.write_bytes(b"PK? no, plain text")
    elif kind == "a zip, no FMU":
        with zipfile.ZipFile(path, "w") as archive:
            archive.writestr("readme.txt", "hello")
    else:
        _rewrite(fmu_paths["MainShaft"], path, BROKEN[kind][0])
    return path


KINDS = {**{k: v[1] for k, v in BROKEN.items()}, "not a zip": "is not an FMU: not a zip archive",
         "a zip, no FMU": r"is not an FMU: it has no modelDescription.xml \(it holds: readme.txt"}


def _scenario(tmp_path, fmu: Path) -> Path:
    path = tmp_path / "mine.toml"
    path.write_text(f'[experiment]\nstop_time = 0.01\nstep = 0.001\n'
                    f'[instances.shaft]\nfmu = "{fmu.name}"\n')
    return path


def _one_line(err) -> str:
    message = str(err.value)
    assert "\n" not in message and "bug in sewfmu" not in message
    return message


@pytest.mark.parametrize("kind", KINDS)
def test_a_scenario_with_a_broken_fmu_is_refused_in_one_line(tmp_path, fmu_paths, kind):
    path = _scenario(tmp_path, _broken(tmp_path, fmu_paths, kind))
    with pytest.raises(sewfmu.ScenarioError, match=KINDS[kind]) as err:
        sewfmu.load(path)
    assert "instances.shaft: Shaft.fmu" in _one_line(err)


@pytest.mark.parametrize("kind", KINDS)
def test_references_of_a_broken_fmu_is_one_line(tmp_path, fmu_paths, kind, capsys):
    fmu = _broken(tmp_path, fmu_paths, kind)
    assert main(["references", "--fmu", str(fmu)]) != 0
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Shaft.fmu" in err, err
    assert __import__("re").search(KINDS[kind], err), err


@pytest.mark.parametrize("kind", ["html", "no modelDescription"])
def test_an_ssp_archive_holding_a_broken_fmu_is_one_line(tmp_path, fmu_paths, kind):
    fmu = _broken(tmp_path, fmu_paths, kind)
    ssd = ('<?xml version="1.0"?><ssd:SystemStructureDescription version="1.0" name="s" '
           'xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription">'
           '<ssd:System name="s"><ssd:Elements><ssd:Component name="c" '
           'source="resources/Shaft.fmu"/></ssd:Elements></ssd:System>'
           '</ssd:SystemStructureDescription>')
    ssp = tmp_path / "s.ssp"
    with zipfile.ZipFile(ssp, "w") as archive:
        archive.writestr("SystemStructure.ssd", ssd)
        archive.write(fmu, "resources/Shaft.fmu")
    with pytest.raises(sewfmu.ScenarioError, match=KINDS[kind]) as err:
        sewfmu.load(ssp)
    assert "component c: Shaft.fmu" in _one_line(err)


def _platforms(path: Path) -> list[str]:
    with zipfile.ZipFile(path) as archive:
        return sorted({n.split("/")[1] for n in archive.namelist()
                       if n.startswith("binaries/") and n.count("/") >= 2})


@pytest.mark.parametrize("fmi", [2, 3])
def test_an_fmu_without_a_binary_for_this_platform_names_the_ones_it_has(tmp_path, fmu_paths,
                                                                         fmu3_paths, fmi):
    source = (fmu_paths if fmi == 2 else fmu3_paths)["MainShaft"]
    here = fmpy.platform if fmi == 2 else fmpy.platform_tuple       # linux64, x86_64-linux
    assert here in _platforms(source)
    fmu = _rewrite(source, tmp_path / "ft.fmu",
                   lambda n, d: None if n.startswith(f"binaries/{here}/") else (n, d))
    others = _platforms(fmu)                     # what pythonfmu builds besides: win64
    assert others and here not in others
    with pytest.raises(sewfmu.ScenarioError) as err:
        extracted_fmu(fmu)
    assert f"ft.fmu has no binary for {here}" in _one_line(err)
    assert f"(it has: {', '.join(others)})" in str(err.value)
    # and a run of it says so before any FMU is loaded, not "instantiate returned FATAL"
    with pytest.raises(sewfmu.Error, match=f"ft.fmu has no binary for {here}"):
        sewfmu.run(_scenario(tmp_path, fmu))


def test_an_fmu_whose_binary_folder_lacks_its_library_names_it(tmp_path, fmu_paths):
    fmu = _rewrite(fmu_paths["MainShaft"], tmp_path / "ft.fmu", lambda n, d: (
        n.replace("linux64/MainShaft.so", "linux64/Other.so"), d))
    with pytest.raises(sewfmu.ScenarioError) as err:
        sewfmu.run(_scenario(tmp_path, fmu))
    assert ("ft.fmu has binaries/linux64/ but not MainShaft.so, the library of its "
            "modelIdentifier 'MainShaft' (it has: Other.so)") in _one_line(err)


def test_the_fmu_they_were_made_from_runs_through_the_same_checks(tmp_path, fmu_paths):
    """The check refuses only what cannot run: the FMU it was made from runs."""
    path = tmp_path / "ok.fmu"
    path.write_bytes(fmu_paths["MainShaft"].read_bytes())
    run = sewfmu.run(_scenario(tmp_path, path))
    assert run.series["time"][-1] == pytest.approx(0.01)
