"""The FMUs' declared units kept in the cache (scenarios/format/declared_units.py): what a later
process reads is what the slave classes declare, a table that does not say what it must is not
used, and a process that finds the table checks a scenario without importing the slave classes."""
import json
import subprocess
import sys

import pytest

from sewfmu.components.registry import FMUS
from sewfmu.components.registry import parameter_units as from_classes
from sewfmu.scenarios.files.cache_root import SUBFOLDER
from sewfmu.scenarios.fmu_build.sources import model_code_hash
from sewfmu.scenarios.format import declared_units


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("SEWFMU_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(declared_units, "_KNOWN", {})
    return tmp_path / SUBFOLDER / declared_units.FOLDER / f"{model_code_hash()}.json"


def test_the_table_written_and_read_again_is_what_the_classes_declare(cache):
    first = {fmu: declared_units.parameter_units(fmu) for fmu in FMUS}
    assert cache.is_file()
    declared_units._KNOWN.clear()           # as a new process: from the file
    again = {fmu: declared_units.parameter_units(fmu) for fmu in FMUS}
    assert first == again == {fmu: from_classes(fmu) for fmu in FMUS}
    assert again["MainShaft"]["omega0"] == "rad/s"


@pytest.mark.parametrize("damage", ["another code version", "an FMU missing", "not JSON",
                                    "a unit changed"])
def test_a_table_that_does_not_say_what_it_must_is_not_used(cache, damage):
    declared_units.parameter_units("MainShaft")
    data = json.loads(cache.read_text())
    data["units"]["MainShaft"]["omega0"] = "rpm"            # a wrong unit, and a wrong table:
    if damage == "another code version":
        data["model_code"] = "0" * 12
    elif damage == "an FMU missing":
        del data["units"]["Fabric"]
    # "a unit changed": only that, the hash and every FMU as written (a hand edit, a damaged
    # disk): the digest written with the units no longer matches them
    cache.write_text("{" if damage == "not JSON" else json.dumps(data))
    declared_units._KNOWN.clear()
    assert declared_units.parameter_units("MainShaft")["omega0"] == "rad/s"
    assert json.loads(cache.read_text())["units"]["MainShaft"]["omega0"] == "rad/s"  # written anew


def test_without_a_cache_the_classes_are_read(tmp_path, monkeypatch):
    monkeypatch.setenv("SEWFMU_CACHE_DIR", "")
    monkeypatch.setattr(declared_units, "_KNOWN", {})
    assert declared_units.parameter_units("PunchContact") == from_classes("PunchContact")
    assert not any(tmp_path.iterdir())


@pytest.mark.slow
def test_with_the_table_a_scenario_is_checked_without_the_slave_classes(cache, monkeypatch):
    declared_units.parameter_units("MainShaft")              # the table is there
    probe = ("import sys\nfrom sewfmu.scenarios.format.loader import load\n"
             "sc = load('punch_drive')\nsc.set_value('shaft.omega0', '955 rpm')\n"
             "print(sc.instances['shaft'].parameters['omega0'])\n"
             "print(sorted(m for m in sys.modules if m.endswith(('_fmu', '.slave'))))")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr[-1500:]
    value, loaded = done.stdout.splitlines()
    assert float(value) == pytest.approx(955 * 2 * 3.141592653589793 / 60, rel=1e-12)
    assert loaded == "[]"


@pytest.mark.slow
def test_a_changed_unit_in_the_table_gives_no_wrong_run(cache, tmp_path):
    """From the attack: omega0's unit changed to rev/s in the table by hand; "955 rpm" must still
    reach the FMU as 100.007 rad/s (a run in a new process, reading the table)."""
    declared_units.parameter_units("MainShaft")
    data = json.loads(cache.read_text())
    data["units"]["MainShaft"]["omega0"] = "rev/s"
    cache.write_text(json.dumps(data))
    probe = ("from sewfmu.scenarios.format.loader import load\n"
             "sc = load('punch_drive')\nsc.set_value('shaft.omega0', '955 rpm')\n"
             "print(repr(sc.instances['shaft'].parameters['omega0']))\n")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         timeout=120, check=True).stdout
    assert float(out) == pytest.approx(955 * 2 * 3.141592653589793 / 60, rel=1e-12)
