"""Values with units as engineers write them: every unit the brief names lands in the declared SI
unit as pint itself converts it, rpm is 2π/60 rad/s exactly, a unit of the wrong dimension is one
line naming both dimensions, and a bare number stays as it is (the declared unit)."""
import math
from pathlib import Path

import pint
import pytest

import sewfmu
from sewfmu.components.units import UnitError
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.format.quantities import in_declared_unit
from sewfmu.scenarios.format.values import ScenarioError

UREG = pint.UnitRegistry()     # pint's own definitions, apart from the module's registry

# (what is written, the declared SI unit, the same value as pint spells it)
WRITTEN = [
    ("3 kN", "N", "3 kilonewton"), ("5 mN", "N", "5 millinewton"),
    ("2 kgf", "N", "2 kilogram_force"), ("3 lbf", "N", "3 pound_force"),
    ("2 mm", "m", "2 millimeter"), ("5 µm", "m", "5 micrometer"), ("5 um", "m", "5 micrometer"),
    ("1.5 in", "m", "1.5 inch"),
    ("955 rpm", "rad/s", "955 revolution/minute"), ("955 rev/min", "rad/s", "955 revolution/minute"),
    ("955 1/min", "rad/s", "955 revolution/minute"), ("16 rev/s", "rad/s", "16 revolution/second"),
    ("720 deg/s", "rad/s", "720 degree/second"),
    ("150 N/mm", "N/m", "150 newton/millimeter"), ("800 lbf/in", "N/m", "800 pound_force/inch"),
    ("63 g", "kg", "63 gram"), ("2 kg", "kg", "2 kilogram"), ("0.5 lb", "kg", "0.5 pound"),
    ("0.25 ms", "s", "0.25 millisecond"), ("2 s", "s", "2 second"), ("1.5 min", "s", "1.5 minute"),
    ("110 deg", "rad", "110 degree"), ("1.2 rad", "rad", "1.2 radian"),
]


@pytest.mark.parametrize("text, unit, pints", WRITTEN, ids=[w[0] for w in WRITTEN])
def test_every_unit_lands_in_the_declared_si_unit_as_pint_converts_it(text, unit, pints):
    expected = UREG.Quantity(pints).to({"N": "newton", "m": "meter", "rad/s": "radian/second",
                                        "N/m": "newton/meter", "kg": "kilogram",
                                        "s": "second", "rad": "radian"}[unit]).magnitude
    assert in_declared_unit(text, unit) == pytest.approx(expected, rel=1e-14)


def test_rpm_is_two_pi_over_sixty_exactly():
    for text in ("955 rpm", "955 rev/min", "955 1/min"):
        assert in_declared_unit(text, "rad/s") == 955 * 2 * math.pi / 60
    assert in_declared_unit("1 rpm", "rad/s") == 2 * math.pi / 60


@pytest.mark.parametrize("value", [300.0, 300, 0.0, -2.5])
def test_a_bare_number_is_in_the_declared_unit(value):
    sc = load("punch_drive")
    sc.set_value("shaft.omega0", value)
    assert sc.instances["shaft"].parameters["omega0"] == value
    assert in_declared_unit(str(value), "rad/s") == float(value)     # a string without a unit


@pytest.mark.parametrize("target, text, said", [
    ("punch.c2", "30 N", "punch.c2 = '30 N': N is a force, punch.c2 wants a stiffness (N/m)"),
    ("shaft.omega0", "3 mm", "mm is a length, shaft.omega0 wants a rotational speed (rad/s)"),
    ("punch.F30", "2 lb", "lb is a mass, punch.F30 wants a force (N)"),
    ("experiment.step", "1 deg", "deg is an angle, experiment.step wants a time (s)"),
])
def test_a_unit_of_the_wrong_dimension_is_refused_in_one_line(target, text, said):
    with pytest.raises(ScenarioError) as err:
        load("punch_drive").set_value(target, text)
    assert said in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("text", ["300 s⁻¹", "300 1/s", "300 s^-1"])
def test_per_second_for_a_rotational_speed_is_ambiguous_and_refused(text):
    # the papers' ω in s⁻¹ is rad/s; pint's turns per second would be 2π times more
    with pytest.raises(ScenarioError, match=r"ambiguous for a rotational speed.*rad/s.*rev/s"):
        load("punch_drive").set_value("shaft.omega0", text)
    assert in_declared_unit("5 Hz", "rad/s") == pytest.approx(10 * 3.141592653589793)


def test_an_unknown_unit_and_a_missing_number_are_refused():
    with pytest.raises(UnitError, match="'furlongs/fortnight' is not a unit|is a velocity"):
        in_declared_unit("3 furlongs/fortnight", "N")
    with pytest.raises(UnitError, match="'foo' is not a unit"):
        in_declared_unit("3 foo", "N")
    with pytest.raises(UnitError, match="must be a number"):
        in_declared_unit("fast", "rad/s")


def test_units_reach_the_scenario_from_every_door(tmp_path):
    """--set and the API's set= (set_value), a scenario file and a sweep grid take the same
    strings and hold the number in the declared unit."""
    from sewfmu.scenarios.runs.sweep import points_of

    sc = load("punch_drive")
    sc.set_value("punch.c2", "150 N/mm")
    sc.set_value("experiment.step", "0.25 ms")
    assert sc.instances["punch"].parameters["c2"] == pytest.approx(150e3)
    assert sc.step == pytest.approx(2.5e-4)
    toml = load("punch_drive").source
    text = Path(toml).read_text().replace("omega0 = 100.0", 'omega0 = "955 rpm"')
    text = text.replace("step = 2.5e-4", 'step = "0.25 ms"')
    (tmp_path / "mine.toml").write_text(text)
    mine = load(str(tmp_path / "mine.toml"))
    assert mine.instances["shaft"].parameters["omega0"] == 955 * 2 * math.pi / 60
    assert mine.step == pytest.approx(2.5e-4)
    points = points_of(load("punch_drive"), {"shaft.omega0": ["955 rpm", "100 rad/s"]})
    assert [dict(p.values)["shaft.omega0"] for p in points] == [955 * 2 * math.pi / 60, 100.0]


def test_revolutions_take_a_value_with_an_angle_unit(tmp_path):
    """experiment.revolutions in turns of the shaft: "720 deg" is 2, as a number or "2 rev";
    a time is refused naming the unit wanted."""
    assert sewfmu.load("punch_drive", set={"experiment.revolutions": "720 deg"}).revolutions \
        == pytest.approx(2.0, rel=1e-15)
    assert sewfmu.load("punch_drive", set={"experiment.revolutions": "3 rev"}).revolutions == 3
    path = tmp_path / "mine.toml"
    path.write_text(sewfmu.show("punch_drive").replace("revolutions = 10",
                                                       'revolutions = "1440 deg"'))
    assert sewfmu.load(path).revolutions == pytest.approx(4.0, rel=1e-15)
    with pytest.raises(sewfmu.ScenarioError, match=r"wants an angle \(rev\)"):
        sewfmu.load("punch_drive", set={"experiment.revolutions": "1 s"})


def test_check_refuses_what_a_run_would_refuse_before_its_first_step():
    """sewfmu.check: the declared range (which load alone does not read), nothing run."""
    sc = sewfmu.check("punch_drive", set={"punch.c2": "6e4 N/m"})
    assert sc.instances["punch"].parameters["c2"] == 6e4
    assert sewfmu.load("punch_drive", set={"punch.c2": -5}).instances["punch"].parameters["c2"] \
        == -5
    with pytest.raises(sewfmu.ScenarioError, match=r"punch.c2: parameter c2 = -5 N/m is outside"):
        sewfmu.check("punch_drive", set={"punch.c2": -5})
    with pytest.raises(sewfmu.ScenarioError, match="fed by the connection"):
        sewfmu.check("punch_drive", set={"linkage.phi": 0.0})


@pytest.mark.parametrize("name, value, says", [
    ("punch.c2", 0, "must be > 0 N/m"),              # inside the declared [0, 1e9], refused
    ("shaft.omega0", 0, "must be > 0 rad/s"),        # by the FMU when it initializes
    ("linkage.L_AB", 0, "must be > 0 m"),
    ("experiment.step", "1e-30 s", "makes more than 1e18 steps"),
])
def test_check_refuses_what_the_fmu_s_initialization_or_the_steps_would(name, value, says):
    with pytest.raises(sewfmu.ScenarioError, match=says):
        sewfmu.check("punch_drive", set={name: value})
    with pytest.raises(sewfmu.Error, match=says):       # and the run does too, as said
        sewfmu.run("punch_drive", set={name: value, "experiment.revolutions": 1})


def test_an_out_of_range_value_is_shown_with_its_digits_and_a_unit_hint_only_where_it_fits():
    with pytest.raises(sewfmu.ScenarioError) as fast:
        sewfmu.check("punch_drive", set={"shaft.omega0": "1e6 rpm"})
    assert "104719.7551 rad/s is outside" in str(fast.value) and "meant in" not in str(fast.value)
    with pytest.raises(sewfmu.ScenarioError) as edge:
        sewfmu.check("punch_drive", set={"shaft.omega0": 2000.0001})
    assert "2000.0001 rad/s is outside the range [0, 2000]" in str(edge.value)
    with pytest.raises(sewfmu.ScenarioError, match=r'meant in rpm\? give the unit: "9550 rpm"'):
        sewfmu.check("punch_drive", set={"shaft.omega0": 9550})


def test_a_huge_typed_value_is_cut_in_the_message_which_ends_with_what_is_wrong():
    with pytest.raises(sewfmu.ScenarioError) as bad:
        sewfmu.check("punch_drive", set={"punch.F30": "x" * 100_000})
    message = str(bad.value)
    assert len(message) < 300 and "(100000 characters)" in message
    assert message.endswith('must be a number, or a number with its unit like "110 deg"')
