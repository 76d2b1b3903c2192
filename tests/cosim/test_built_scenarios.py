"""A Scenario built or changed in Python, from the attack: its name became a path (sc.name =
"../../precious" replaced victim/precious.png beside the out= folder), and what a scenario file
cannot hold (an Instance whose fmu is None, a string among the connections, a step of None, an
instance named "/tmp/x") ran into Python's AttributeError, KeyError or TypeError. Now each is one
ScenarioError line before anything runs or is written."""
import dataclasses

import pytest

import sewfmu
from sewfmu.scenarios.format.scenario import Connection, Instance, Scenario


@pytest.mark.parametrize("name", ["../../precious", "/abs/dir/abs", "a/b", "a\\b", "..", ".",
                                  "", "a\x00b", "line\nbreak", "x" * 201, None, 7])
def test_a_scenario_name_that_is_no_file_name_is_refused_where_it_is_set(name):
    sc = sewfmu.load("punch_drive")
    with pytest.raises(sewfmu.ScenarioError, match="scenario's name") as bad:
        sc.name = name
    assert "\n" not in str(bad.value)
    assert sc.name == "punch_drive"
    fields = {f.name: getattr(sc, f.name) for f in dataclasses.fields(sc) if f.init}
    with pytest.raises(sewfmu.ScenarioError, match="scenario's name"):
        Scenario(**{**fields, "name": name})


@pytest.mark.slow
def test_a_name_forced_past_the_check_writes_nothing_outside_out(tmp_path):
    victim = tmp_path / "victim"
    (victim / "sub").mkdir(parents=True)
    (victim / "precious.png").write_bytes(b"mine")
    sc = sewfmu.load("punch_drive", set={"experiment.revolutions": 1})
    object.__setattr__(sc, "name", "../precious")        # around the assignment's check
    with pytest.raises(sewfmu.ScenarioError, match="scenario's name"):
        sewfmu.run(sc, out=victim / "sub", plot=True)
    assert (victim / "precious.png").read_bytes() == b"mine"
    assert list((victim / "sub").iterdir()) == []
    from sewfmu.scenarios.runs.results import write_outputs  # the guard at the write itself
    from sewfmu.scenarios.runs.studies import run_study  # likewise for a study

    with pytest.raises(sewfmu.ScenarioError, match="scenario's name"):
        write_outputs(sc, [], victim / "sub", plot=True)
    study = sewfmu.load("carriage_resonance")
    object.__setattr__(study, "name", "/abs/dir/abs")
    with pytest.raises(sewfmu.ScenarioError, match="scenario's name"):
        run_study(study, victim / "sub", plot=True)
    assert list((victim / "sub").iterdir()) == []


def _changed(change):
    sc = sewfmu.load("punch_drive")
    change(sc)
    return sc


def _renamed(sc, name):
    inst = sc.instances.pop("punch")
    inst.name = name
    sc.instances[name] = inst


@pytest.mark.parametrize("change, says", [
    (lambda sc: sc.instances.__setitem__("shaft", Instance("shaft", "MainShaft", None)),
     "instance shaft: parameters must be a dict"),
    (lambda sc: sc.instances.__setitem__("shaft", Instance("shaft", None)),
     "instance shaft: fmu must name one of sewfmu's FMUs"),
    (lambda sc: sc.instances.__setitem__("shaft", "MainShaft"), "expected an Instance"),
    (lambda sc: sc.instances.__setitem__("shaft", Instance("other", "MainShaft")),
     "the Instance is named 'other'"),
    (lambda sc: sc.connections.append(Connection("../a", "x", "punch", "y")),
     "'../a' is no instance of the scenario"),
    (lambda sc: sc.connections.append("shaft.phi -> linkage.phi"),
     "expected Connection(src, src_var, dst, dst_var) objects"),
    (lambda sc: sc.connections.append(Connection("shaft", None, "punch", "y")),
     "None is no variable name"),
    (lambda sc: setattr(sc, "step", None), "Scenario.step: must be a number"),
    (lambda sc: setattr(sc, "step", "fast"), "Scenario.step"),
    (lambda sc: setattr(sc, "stop_time", 1.0), "exactly one of stop_time and revolutions"),
    (lambda sc: setattr(sc, "master", "nope"), "Scenario.master: one of"),
    (lambda sc: setattr(sc, "record", "punch.F2"), "record must be a list"),
    (lambda sc: setattr(sc, "record_every", 0), "record_every: a whole number >= 1"),
    (lambda sc: setattr(sc, "shaft", "punch"), "Scenario.shaft: the MainShaft instance"),
    (lambda sc: setattr(sc, "instances", []), "Scenario.instances: expected a dict"),
    (lambda sc: sc.instances["shaft"].parameters.__setitem__("omega0", object()),
     "shaft.omega0: a value is a number"),
    (lambda sc: _renamed(sc, "/tmp/x"), "an instance name starts with a letter"),
    (lambda sc: _renamed(sc, "a\x00b"), "an instance name starts with a letter"),
    (lambda sc: _renamed(sc, "experiment"), "not 'experiment'"),
    (lambda sc: _renamed(sc, "p" * 65), "at most 64"),
])
def test_a_scenario_built_in_python_is_checked_before_it_runs(change, says):
    sc = _changed(change)
    for call in (sewfmu.check, sewfmu.run):
        with pytest.raises(sewfmu.ScenarioError) as bad:
            call(sc)
        assert says in str(bad.value) and "\n" not in str(bad.value), str(bad.value)


def test_a_time_with_its_unit_is_taken_as_a_file_takes_it():
    sc = _changed(lambda sc: setattr(sc, "step", "0.25 ms"))
    checked = sewfmu.check(sc)
    assert checked.step == pytest.approx(2.5e-4, rel=1e-15) and sc.step == "0.25 ms"
