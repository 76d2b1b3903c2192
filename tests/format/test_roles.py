"""Analyses bind roles, not names: a catalogue scenario with every instance renamed (non-ASCII
names too) gives the same figures; roles bound to the wrong FMU type, ambiguous roles, unknown
analyses and a shaft that is not a MainShaft are errors naming what is wrong."""
import pytest

from sewfmu.cli import main
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.format.values import ScenarioError
from sewfmu.scenarios.runs.results import run_scenario
from tests.cosim.test_reliability import PUNCH  # the catalogue's punch_drive.toml, as text

RENAMED = {"shaft": "вал", "linkage": "рычаг", "punch": "ram"}


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


def _renamed(text: str, names: dict[str, str]) -> str:
    for old, new in names.items():
        text = text.replace(f'"{old}.', f'"{new}.').replace(f" {old}.", f" {new}.")
        text = text.replace(f"[instances.{old}]", f'[instances."{new}"]')
        text = text.replace(f'shaft = "{old}"', f'shaft = "{new}"')
    return text


@pytest.mark.slow
def test_a_catalogue_scenario_with_every_instance_renamed_gives_the_same_figures(tmp_path):
    path = tmp_path / "renamed.toml"
    path.write_text(_renamed(PUNCH, RENAMED), encoding="utf-8")
    scenario = load(str(path))
    assert set(scenario.instances) == set(RENAMED.values())
    assert scenario.roles == RENAMED
    renamed = run_scenario(scenario, tmp_path / "renamed", plot=True)
    original = run_scenario(load("punch_drive"), tmp_path / "original")
    for key in ("contact_onset_deg", "contact_loss_deg", "F2_peak", "F2_weld_mean", "n_contacts"):
        assert renamed[key] == original[key], key
    header = (tmp_path / "renamed" / "results.csv").read_text(encoding="utf-8").splitlines()[0]
    assert "вал.phi" in header and "ram.F2" in header
    assert (tmp_path / "renamed" / "renamed.png").exists()


def test_the_revolutions_are_counted_on_the_analysis_shaft_without_experiment_shaft(tmp_path):
    path = tmp_path / "noshaft.toml"
    path.write_text(_renamed(PUNCH, RENAMED).replace('shaft = "вал"\n', ""), encoding="utf-8")
    scenario = load(str(path))
    assert scenario.shaft == "вал"
    assert scenario.end_time() == pytest.approx(10 * 2 * 3.141592653589793 / 100.0)


@pytest.mark.parametrize("edit, words", [
    (lambda t: t.replace('analysis = "punch"', 'analysis = "punch"\nroles = { punch = "linkage" }'),
     ["roles.punch", "'linkage' is an instance of PunchLinkage", "punch of the punch analysis is "
                                                                  "a PunchContact"]),
    (lambda t: t.replace('analysis = "punch"', 'analysis = "punch"\nroles = { ram = "punch" }'),
     ["roles.ram", "no role 'ram'", "shaft, linkage, punch"]),
    (lambda t: t.replace('analysis = "punch"', 'analysis = "pnuch"'),
     ["unknown analysis 'pnuch'", "punch"]),
    (lambda t: t + '\n[instances.punch2]\nfmu = "PunchContact"\n',
     ["needs its punch (PunchContact)", "'punch', 'punch2'", "roles table"]),
    (lambda t: t.replace('shaft = "shaft"', 'shaft = "punch"'),
     ["experiment.shaft", "'punch', an instance of PunchContact", "MainShaft"]),
])
def test_bad_role_bindings_are_named(tmp_path, capsys, edit, words):
    path = tmp_path / "roles.toml"
    path.write_text(edit(PUNCH), encoding="utf-8")
    with pytest.raises(ScenarioError) as err:
        load(str(path))
    for word in words:
        assert word in str(err.value), str(err.value)
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 1
    assert "roles.toml" in capsys.readouterr().err


def test_the_bound_instance_is_the_one_analysed(tmp_path):
    """Two punches on one linkage; the roles table picks the stiffer one: its figures are those of
    punch_drive with that stiffness."""
    text = PUNCH + '\n[instances.punch2]\nfmu = "PunchContact"\nparameters = { c3 = 2e5 }\n'
    for var in ("xi", "xi_dot", "xi_ddot"):
        text = text.replace(f'"linkage.{var} -> punch.{var}",',
                            f'"linkage.{var} -> punch.{var}",\n  "linkage.{var} -> punch2.{var}",')
    text = text.replace('analysis = "punch"', 'analysis = "punch"\nroles = { punch = "punch2" }')
    path = tmp_path / "two.toml"
    path.write_text(text, encoding="utf-8")
    two = run_scenario(load(str(path)), tmp_path / "two")
    stiff = load("punch_drive")
    stiff.set_value("punch.c3", 2e5)
    alone = run_scenario(stiff, tmp_path / "alone")
    for key in ("contact_onset_deg", "contact_loss_deg", "F2_peak", "F2_weld_mean"):
        assert two[key] == alone[key], key
    assert two["contact_loss_deg"] != run_scenario(load("punch_drive"),
                                                   tmp_path / "soft")["contact_loss_deg"]


def test_every_mechanism_is_declared_once_in_its_module():
    """The mechanisms' modules are the one list of mechanisms: each names known FMUs for its
    roles, units for its figures, a drawing where it draws itself and studies of their own; and
    no module outside scenarios/mechanisms lists the analyses by name."""
    import re
    from pathlib import Path

    from sewfmu.components.registry import FMUS
    from sewfmu.scenarios import mechanisms as registry
    from sewfmu.scenarios.mechanisms import SHARED, mechanisms

    found = mechanisms()
    folder = Path(registry.__file__).parent
    assert set(found) == {p.stem for p in folder.glob("*.py")
                          if p.stem != "__init__" and p.stem not in SHARED}
    for name, m in found.items():
        assert m.name == name
        assert m.roles and set(m.roles.values()) <= set(FMUS), name
        assert m.figures and all(isinstance(u, str) and u for u in m.figures.values()), name
        assert m.Scene is None or all(callable(getattr(m.Scene, f)) for f in ("points", "draw"))
        for study in m.studies.values():
            assert callable(study.compute) and callable(study.plot) and study.units
    scenarios = folder.parent
    for path in [*scenarios.rglob("*.py")]:
        if path.parent == folder:
            continue
        text = path.read_text(encoding="utf-8")
        listed = re.findall(r"[\[{(]\s*\"punch\",\s*\"punch_split\"", text)
        assert not listed, path
