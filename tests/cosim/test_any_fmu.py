"""A designer's own FMU in a scenario (`fmu = "Motor.fmu"`, relative to the scenario file), beside
sewfmu's: checked against its modelDescription when the file is read, its connections converted
through the FMI unit definitions or refused, and its results the ones fmpy's own simulate_fmu
and a hand computation give. The FMUs are made here, not by sewfmu (tests/foreign_fmus.py)."""
import shutil

import numpy as np
import pytest
from fmpy import simulate_fmu

import sewfmu
from sewfmu.scenarios.format.scenario import Connection, Instance
from tests.foreign_fmus import build_gain, build_gain3, build_motor, rewritten

STEP, STOP = 1e-4, 0.08

MOTOR_SCENARIO = f"""
description = "a designer's first-order motor drives sewfmu's punch"
connections = [
  "motor.phi -> linkage.phi", "motor.omega -> linkage.omega",
  "motor.epsilon -> linkage.epsilon",
  "linkage.xi -> punch.xi", "linkage.xi_dot -> punch.xi_dot",
  "linkage.xi_ddot -> punch.xi_ddot",
]
record = ["motor.phi", "motor.omega", "punch.y", "punch.F2"]

[experiment]
stop_time = {STOP}
step = {STEP}

[instances.motor]
fmu = "fmus/Motor.fmu"
parameters = {{ omega_ref = 150.0, T = 0.02 }}  # it declares no units: numbers

[instances.linkage]
fmu = "PunchLinkage"

[instances.punch]
fmu = "PunchContact"
"""

# the punch drive with the C gain between the linkage and the punch: xi in m -> u in mm, and
# y in mm -> xi in m; with k = 1 the punch must move exactly as without the gain
GAIN_SCENARIO = """
connections = [
  "shaft.phi -> linkage.phi", "shaft.omega -> linkage.omega",
  "shaft.epsilon -> linkage.epsilon",
  {xi}
  "linkage.xi_dot -> punch.xi_dot", "linkage.xi_ddot -> punch.xi_ddot",
]
record = ["linkage.xi", "punch.y", "punch.F2"{record}]

[experiment]
revolutions = 1.5
step = "0.1 ms"

[instances.shaft]
fmu = "MainShaft"

[instances.linkage]
fmu = "PunchLinkage"

[instances.punch]
fmu = "PunchContact"
{gain}
"""
WITH_GAIN = dict(xi='"linkage.xi -> gain.u", "gain.y -> punch.xi",', record=', "gain.y"',
                 gain='[instances.gain]\nfmu = "Gain.fmu"\nparameters = { k = 1.0 }\n')
WITHOUT_GAIN = dict(xi='"linkage.xi -> punch.xi",', record="", gain="")


@pytest.fixture(scope="module")
def motor_fmu(tmp_path_factory):
    return build_motor(tmp_path_factory.mktemp("motor"))


@pytest.fixture(scope="module")
def gain_fmu(tmp_path_factory):
    fmu = build_gain(tmp_path_factory.mktemp("gain"))
    if fmu is None:
        pytest.skip("gcc is not installed: the C FMU cannot be compiled")
    return fmu


def _motor_phi(t, omega0=100.0, omega_ref=150.0, T=0.02):
    return omega_ref * t + (omega0 - omega_ref) * T * (1.0 - np.exp(-t / T))


def test_a_pythonfmu_motor_drives_the_punch(tmp_path, motor_fmu):
    (tmp_path / "fmus").mkdir()
    shutil.copy(motor_fmu, tmp_path / "fmus" / "Motor.fmu")
    (tmp_path / "motor.toml").write_text(MOTOR_SCENARIO)
    r = sewfmu.run(tmp_path / "motor.toml")
    t = r.series["time"]
    # a hand computation: the motor's closed form
    assert np.allclose(r.series["motor.phi"], _motor_phi(t), rtol=1e-12, atol=1e-12)
    # fmpy's own run of the same FMU with the same parameter values
    alone = simulate_fmu(str(motor_fmu), stop_time=STOP, output_interval=STEP,
                         start_values={"omega_ref": 150.0, "T": 0.02})
    assert np.allclose(np.interp(t, alone["time"], alone["phi"]), r.series["motor.phi"],
                       rtol=1e-9, atol=1e-12)
    # sewfmu's punch follows it: it lands and presses with the forces of the mechanism
    assert r.series["punch.F2"].max() > 5.0 and r.series["punch.F2"].max() < 500.0
    assert r.series["punch.y"].min() < 0.0


def test_a_c_gain_converts_m_to_mm_and_back(tmp_path, gain_fmu):
    shutil.copy(gain_fmu, tmp_path / "Gain.fmu")
    (tmp_path / "with.toml").write_text(GAIN_SCENARIO.format(**WITH_GAIN))
    (tmp_path / "without.toml").write_text(GAIN_SCENARIO.format(**WITHOUT_GAIN))
    with_gain, without = sewfmu.run(tmp_path / "with.toml"), sewfmu.run(tmp_path / "without.toml")
    # by hand: y = k·u with u the linkage's xi in mm (FMI unit mm: m, factor 0.001)
    assert np.allclose(with_gain.series["gain.y"], 1000.0 * with_gain.series["linkage.xi"],
                       rtol=1e-12, atol=0.0)
    assert with_gain.units["gain.y"] == "mm"
    # and back in m, the punch moves as without the gain (its output follows its input at once)
    for column in ("punch.y", "punch.F2"):
        assert np.allclose(with_gain.series[column], without.series[column], rtol=1e-9,
                           atol=1e-9 * np.abs(without.series[column]).max())
    assert without.series["punch.F2"].max() > 5.0          # it landed and pressed
    # the tool tells its parameters as it tells sewfmu's, from its modelDescription
    k = next(r for r in sewfmu.parameters(tmp_path / "with.toml") if r["instance"] == "gain")
    assert (k["parameter"], k["default"], k["value"], k["range"]) == ("k", 1.0, 1.0,
                                                                        "[-1000, 1000]")
    # the gain in fmpy's own simulate_fmu: y = k·u
    alone = simulate_fmu(str(gain_fmu), start_values={"k": 3.0, "u": 2.0})
    assert np.all(alone["y"] == 6.0)


def test_an_fmi3_fmu_runs_beside_sewfmus_fmi2_ones(tmp_path):
    build_gain3(tmp_path)
    (tmp_path / "fmi3.toml").write_text(GAIN_SCENARIO.format(
        xi='"linkage.xi -> punch.xi", "punch.F2 -> gain.u",', record=', "gain.y"',
        gain='[instances.gain]\nfmu = "Gain3.fmu"\nparameters = { k = 3.0 }\n'))
    r = sewfmu.run(tmp_path / "fmi3.toml")
    # by hand: its output at each step's end is k times the input set at the step's start
    F2, y = r.series["punch.F2"], r.series["gain.y"]
    assert np.array_equal(y[1:], 3.0 * F2[:-1]) and F2.max() > 5.0


def test_a_scenario_built_in_python_runs_an_fmu_by_its_path(tmp_path, gain_fmu, monkeypatch):
    shutil.copy(gain_fmu, tmp_path / "Gain.fmu")
    sc = sewfmu.load("punch_drive", set={"experiment.revolutions": 1})
    sc.instances["gain"] = Instance("gain", "Gain.fmu", {"k": 1.0})   # from the working folder
    sc.connections = [c for c in sc.connections if c.dst_var != "xi"] + [
        Connection("linkage", "xi", "gain", "u"), Connection("gain", "y", "punch", "xi")]
    sc.record = None                      # every output: the punch analysis reads its own
    monkeypatch.chdir(tmp_path)
    r = sewfmu.run(sc)
    assert np.allclose(r.series["gain.y"], 1000.0 * r.series["linkage.xi"], rtol=1e-12)
    assert r.series["punch.F2"].max() > 5.0


@pytest.mark.parametrize("change, message", [
    ('"shaft.omega -> gain.u",', "incompatible units 'rad/s' -> 'mm'"),
    ("", "has no parameter or input 'kk'; did you mean 'k'"),
    ("", "outside the range Gain declares (max 1000)"),
    ("", "FMU file 'Missing.fmu' not found"),
])
def test_a_foreign_fmu_is_checked_and_refused_in_one_line(tmp_path, gain_fmu, change, message):
    shutil.copy(gain_fmu, tmp_path / "Gain.fmu")
    parts = dict(WITH_GAIN)
    if "incompatible" in message:
        parts["xi"] = '"linkage.xi -> punch.xi", ' + change
        parts["record"] = ""
    elif "'kk'" in message:
        parts["gain"] = parts["gain"].replace("k = 1.0", "kk = 1.0")
    elif "range" in message:
        parts["gain"] = parts["gain"].replace("k = 1.0", "k = 5000.0")
    else:
        parts["gain"] = parts["gain"].replace("Gain.fmu", "Missing.fmu")
    (tmp_path / "bad.toml").write_text(GAIN_SCENARIO.format(**parts))
    with pytest.raises(sewfmu.ScenarioError) as err:
        sewfmu.run(tmp_path / "bad.toml")
    assert message in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("master, capability, said", [
    ("adaptive", "canGetAndSetFMUstate", "cannot save and restore its state"),
    ("adaptive", "canHandleVariableCommunicationStepSize", "takes only steps of one size"),
])
def test_an_fmu_is_not_asked_for_what_it_declares_it_cannot_do(tmp_path, gain_fmu, master,
                                                                capability, said):
    rewritten(gain_fmu, tmp_path, "Gain.fmu", **{capability: "false"})
    (tmp_path / "s.toml").write_text(GAIN_SCENARIO.format(**WITH_GAIN))
    with pytest.raises(sewfmu.CosimError) as err:
        sewfmu.run(tmp_path / "s.toml", set={"experiment.master": master})
    assert said in str(err.value) and "gain (Gain)" in str(err.value)
    assert "jacobi" in str(err.value) and "\n" not in str(err.value)
    # the fixed-step masters never roll back: the same FMU runs with them
    r = sewfmu.run(tmp_path / "s.toml", set={"experiment.master": "jacobi"})
    assert r.series["punch.F2"].max() > 5.0


def test_a_value_given_to_a_connected_input_is_refused_not_ignored(tmp_path):
    with pytest.raises(sewfmu.ScenarioError, match="punch.xi is an input fed by the connection "
                                                   "linkage.xi -> punch.xi"):
        sewfmu.run("punch_drive", set={"punch.xi": 0.01, "experiment.revolutions": 1})


def test_an_instance_built_in_python_takes_values_with_units():
    sc = sewfmu.load("punch_drive", set={"experiment.revolutions": 1})
    sc.instances["shaft"] = sewfmu.Instance("shaft", "MainShaft", {"omega0": "1910 rpm"})
    assert sewfmu.load(sc).instances["shaft"].parameters["omega0"] == pytest.approx(
        1910 * 2 * np.pi / 60, rel=1e-12)
    sc.instances["shaft"] = sewfmu.Instance("shaft", "MainShaft", {"omega0": "3 kg"})
    with pytest.raises(sewfmu.ScenarioError, match="kg is a mass"):
        sewfmu.load(sc)
