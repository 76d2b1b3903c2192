"""Asking the tool what can be set: `sewfmu show NAME --parameters` and sewfmu.parameters(NAME),
for one of sewfmu's FMUs by name and for every instance of a scenario; `sewfmu show COMPONENT`
describes the FMU instead of calling it an unknown scenario."""
import subprocess
import sys

import pytest

import sewfmu
from sewfmu.components.parameters import parameter_info
from sewfmu.components.registry import FMUS
from sewfmu.scenarios.format.parameter_table import COLUMNS, slave_class


@pytest.mark.parametrize("name", list(FMUS))
def test_every_fmu_lists_its_declared_parameters(name):
    cls = slave_class(name)
    infos = parameter_info(cls.params_class) if cls.params_class else []
    rows = sewfmu.parameters(name)
    assert [r["parameter"] for r in rows] == [i.name for i in infos]
    for row, info in zip(rows, infos):
        assert set(row) == set(COLUMNS)
        assert row["default"] == row["value"] == info.default and row["unit"] == info.unit
        assert row["meaning"] == info.description and row["range"]


def test_the_punch_contacts_table_reads_as_its_page_says():
    rows = {r["parameter"]: r for r in sewfmu.parameters("PunchContact")}
    assert rows["c2"]["default"] == 50000.0 and rows["c2"]["unit"] == "N/m"
    assert rows["c2"]["range"] == "(0, 1e+09]"            # positive, up to the machine's scale
    assert rows["compression_only"]["range"] == "one of 0, 1"
    assert rows["F30"]["range"] == "[0, 10000]"


def test_a_scenarios_table_has_every_instance_with_its_values():
    rows = sewfmu.parameters("punch_drive", set={"shaft.omega0": "955 rpm"})
    assert {r["instance"] for r in rows} == {"shaft", "linkage", "punch"}
    omega0 = next(r for r in rows if (r["instance"], r["parameter"]) == ("shaft", "omega0"))
    assert omega0["default"] == 100.0 and omega0["value"] == pytest.approx(100.0, rel=1e-3)


def test_an_unknown_name_is_one_line():
    with pytest.raises(sewfmu.ScenarioError) as err:
        sewfmu.parameters("PunchContakt")
    assert "unknown scenario" in str(err.value) and "\n" not in str(err.value)


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "sewfmu", *args], capture_output=True,
                          text=True, timeout=120)


@pytest.mark.slow
def test_the_command_line_shows_a_component_and_tables():
    shown = _cli("show", "PunchContact")
    assert shown.returncode == 0, shown.stderr
    assert "unknown scenario" not in shown.stdout + shown.stderr
    assert "inputs:" in shown.stdout and "xi [m]" in shown.stdout and "c2" in shown.stdout
    table = _cli("show", "PunchContact", "--parameters")
    assert table.returncode == 0 and table.stdout.splitlines()[0].split() == list(COLUMNS)
    assert str(sewfmu.parameters("PunchContact")) == table.stdout
    scenario = _cli("show", "punch_drive", "--parameters")
    assert scenario.returncode == 0 and "linkage   L_O1A" in scenario.stdout
