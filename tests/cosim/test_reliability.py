"""Reliability: bad input gets one clear line, a failing FMU stops the run cleanly, states roll
back exactly, instances and builds stay independent, memory stays flat, and random parameter sets
never crash the host (signals and faults: test_faults.py)."""
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from sewfmu.cli import main
from sewfmu.components.punch_contact import GRAVITY, PunchContact, PunchContactParams
from sewfmu.scenarios.cosim.fmi_calls import CosimError
from sewfmu.scenarios.cosim.master import Master
from sewfmu.scenarios.fmu_build.build import MODEL_CODE_DIR, build_fmu
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.format.values import ScenarioError
from tests.fmu_host import Host
from tests.paths import REPO


def _jacobi(sc):
    """The scenario run by the Jacobi master (punch_split's own is the adaptive one)."""
    sc.master = "jacobi"
    return sc




@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


# --- bad input: one line, non-zero exit, no results that look complete ------------------------
PUNCH = (REPO / "scenarios" / "catalogue" / "punch_drive.toml").read_text()


@pytest.mark.parametrize("edit, words", [
    (lambda t: t.replace("[experiment]", "[experiment\n"), ["not valid TOML"]),
    (lambda t: t.replace("revolutions = 10", "revolutions = 10\nspeed = 3"),
     ["unknown key experiment.speed"]),
    (lambda t: t.replace('"shaft.phi -> linkage.phi"', '"shaft.angle -> linkage.phi"'),
     ["connection", "shaft.angle", "has no output 'angle'"]),
    (lambda t: t.replace('"shaft.phi -> linkage.phi"', '"shaft.omega -> linkage.phi"'),
     ["incompatible units", "rad/s", "rad"]),
    (lambda t: t.replace("parameters = { omega0 = 100.0 }", 'parameters = { omega0 = "fast" }'),
     ["instances.shaft.parameters", "must be a number"]),
    (lambda t: t.replace("parameters = { omega0 = 100.0 }", "parameters = { omega_0 = 100.0 }"),
     ["broken.toml", "omega_0", "has no parameter", "did you mean 'omega0'"]),
    (lambda t: t.replace("step = 2.5e-4", "step = 2.0"), ["longer than the run"]),
    (lambda t: t.replace("step = 2.5e-4", "step = -1e-4"), ["experiment.step", "positive"]),
    (lambda t: t.replace('fmu = "PunchContact"', 'fmu = "PunchBdy"'), ["unknown FMU 'PunchBdy'"]),
    (lambda t: t.replace('fmu = "PunchContact"', 'fmu = "PunchContact"\nparameters = { mass = 1.0 }'),
     ["broken.toml", "punch.mass", "has no parameter 'mass'"]),
])
def test_a_broken_scenario_file_is_named_with_its_key(tmp_path, capsys, edit, words):
    path = tmp_path / "broken.toml"
    path.write_text(edit(PUNCH))
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, err
    assert not (out / "results.csv").exists()


@pytest.mark.parametrize("value, words", [("nan", ["parameter omega0", "finite"]),
                                          ("inf", ["parameter omega0", "finite"]),
                                          ("-5", ["parameter omega0", "> 0"])])
def test_nan_infinite_or_negative_values_are_refused(capsys, tmp_path, value, words):
    assert main(["run", "punch_drive", "--set", f"shaft.omega0={value}",
                 "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert all(w in err for w in words), err


def test_debug_shows_the_traceback(tmp_path):
    with pytest.raises(ScenarioError):
        main(["--debug", "run", "no_such_scenario", "--out", str(tmp_path)])


# --- an FMU that fails in mid-run ----------------------------------------------------------------
def test_an_fmu_failing_mid_run_stops_cleanly_with_time_and_log_line(fmu_paths):
    """A shaft run up to 2000 rad/s in 0.2 ms: its angular acceleration (2·ω/t_r at the middle
    of the cycloidal ramp, 2e7 rad/s²) leaves the linkage's declared input range after a few
    steps, and the linkage refuses that step."""
    sc = load("punch_drive")
    sc.set_value("shaft.omega0", 2000.0)
    sc.set_value("shaft.ramp_time", 2e-4)
    sc.set_value("experiment.stop_time", 1e-3)
    sc.set_value("experiment.step", 1e-5)
    master = Master(_jacobi(sc), fmu_paths)
    with pytest.raises(CosimError) as err:
        master.run()
    text = str(err.value)
    assert text.startswith("linkage failed during step from t = "), text
    assert "input epsilon = " in text and "is outside its range" in text, text
    failed_at = float(text.split("from t = ")[1].split(" ")[0])
    assert 0.0 < failed_at < 1e-4              # mid-run: after the first steps, inside the ramp
    # no call ended in fmi2Fatal (a getter of sewfmu's FMUs logs instead of raising): every
    # instance, the one that failed included, is terminated and freed
    assert not any(u.failed for u in master.instances)
    assert not any(u.instantiated for u in master.instances)


# --- state: the master rolls back, every FMU restores (and serializes) exactly ------------------
ON_STOP = {"punch.compression_only": 1, "punch.F30": 30.0}     # the punch held on spring 11's stop


@pytest.mark.parametrize("scenario, overrides", [
    ("punch_drive", {}), ("punch_drive", ON_STOP), ("takeup", {}), ("feed", {}),
    ("carriage_startstop", {})])
def test_master_rolls_back_a_stretch_of_steps_bit_for_bit(fmu_paths, scenario, overrides):
    sc = load(scenario)
    sc.set_value("experiment.revolutions", 2)
    for name, value in overrides.items():
        sc.set_value(name, value)
    with Master(_jacobi(sc), fmu_paths) as master:
        for _ in range(master.n_steps // 8):           # a quarter revolution
            master.step()
        saved = master.save_state()
        if overrides is ON_STOP:                         # saved while riding on the stop
            f3, delta = master.result()["punch.F3"][-1], master.result()["punch.Delta"][-1]
            assert 0.0 < f3 < 30.0 and abs(delta) < 1e-7, (f3, delta)
        for _ in range(master.n_steps // 4):
            master.step()
        first = master.result()
        master.restore_state(saved)
        for _ in range(master.n_steps // 4):
            master.step()
        second = master.result()
    for name in first.columns:
        assert np.array_equal(first[name], second[name]), name


@pytest.mark.slow
def test_every_fmu_state_survives_serialization(fmu_paths):
    """Serialize each FMU's state to bytes, run on, restore from the bytes: the same steps."""
    for scenario, overrides in (("punch_drive", {}), ("punch_drive", ON_STOP),
                                ("carriage_startstop", {}), ("takeup", {}), ("feed", {}),
                                ("punch_split", {})):
        sc = load(scenario)
        sc.set_value("experiment.revolutions", 1)
        for name, value in overrides.items():
            sc.set_value(name, value)
        with Master(_jacobi(sc), fmu_paths) as master:
            for _ in range(master.n_steps // 4):                # on the stop, with ON_STOP
                master.step()
            snapshot = master.save_state()
            blobs = [u.fmu.serializeFMUstate(slot)
                     for u, slot in zip(master.instances, snapshot.states.slots)]
            for _ in range(master.n_steps // 4):
                master.step()
            first = master.result()
            for u, slot in zip(master.instances, snapshot.states.slots):   # forget the states
                u.free_state(slot)
            snapshot.states.slots[:] = [u.fmu.deSerializeFMUstate(b)
                                        for u, b in zip(master.instances, blobs)]
            master.restore_state(snapshot)
            for _ in range(master.n_steps // 4):
                master.step()
            second = master.result()
        for name in first.columns:
            assert np.array_equal(first[name], second[name]), (scenario, name)


# --- many instances, two builds -----------------------------------------------------------------
def test_fifty_punch_instances_in_one_process_are_independent(fmu_paths):
    stiffness = np.linspace(3e4, 3e5, 50)
    hosts = []
    for k, c3 in enumerate(stiffness):
        host = Host(fmu_paths["PunchContact"], f"punch{k}")
        host.set(c3=c3, xi=2e-3, xi_dot=-0.05, xi_ddot=0.0)
        host.fmu.exitInitializationMode()
        hosts.append(host)
    for step in range(40):                                   # interleaved
        for host in hosts:
            host.fmu.doStep(step * 1e-3, 1e-3)
    assert len({host.get("y") for host in hosts}) == 50
    for host, c3 in zip(hosts, stiffness):
        model = PunchContact(PunchContactParams(c3=float(c3)))
        state = model.initial_state(2e-3, -0.05)
        for step in range(40):
            t = step * 1e-3
            state = model.step(state, 2e-3 - 0.05 * t, -0.05, 0.0, 1e-3)
        assert host.get("y") == pytest.approx(state.y, rel=1e-12, abs=1e-18)


def test_two_builds_with_different_code_each_run_their_own(fmu_paths, tmp_path):
    """A copy of the model code with gravity switched off, built into a second PunchContact:
    loaded beside the original in this process, each settles where its own code says."""
    source = tmp_path / "components"
    shutil.copytree(MODEL_CODE_DIR, source, ignore=shutil.ignore_patterns("__pycache__"))
    code = (source / "punch_contact.py").read_text()
    (source / "punch_contact.py").write_text(code.replace("GRAVITY = 9.81", "GRAVITY = 0.0"))
    weightless = build_fmu("PunchContact", tmp_path / "fmus", source=source)
    settled = []
    for path in (fmu_paths["PunchContact"], weightless):
        host = Host(path, "punch")
        host.set(xi=2e-3, xi_ddot=0.0)
        host.fmu.exitInitializationMode()
        for step in range(400):
            host.fmu.doStep(step * 1e-3, 1e-3)
        settled.append(host.get("y"))
    p = PunchContactParams()
    assert settled[1] - settled[0] == pytest.approx(p.m * GRAVITY / (p.c1 + p.c3), rel=1e-9)


# --- memory ---------------------------------------------------------------------------------------
def _rss_mib() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    raise RuntimeError("no VmRSS")


@pytest.mark.slow
def test_memory_stays_flat_over_a_long_run(fmu_paths):
    """5·10⁴ communication steps (bench/long_run.py does 10⁶): the resident size after the
    first 10⁴ steps does not grow."""
    sc = load("punch_drive")
    sc.set_value("experiment.revolutions", 200)
    sc.set_value("experiment.record_every", 1000)
    with Master(_jacobi(sc), fmu_paths) as master:
        samples = []
        for k in range(50_000):
            master.step()
            if k % 10_000 == 9_999:
                samples.append(_rss_mib())
    assert max(samples) - samples[0] < 3.0, samples


# --- property-based: valid parameters never crash, invalid ones always get a clear error --------
POSITIVE = ("m", "c1", "c2", "c3")
NONNEGATIVE = ("F10", "b1", "b2", "b3", "F30")


VALID_PUNCH = st.fixed_dictionaries({
    "m": st.floats(0.005, 1.0), "c1": st.floats(100.0, 1e4), "c2": st.floats(1e3, 5e5),
    "c3": st.floats(1e3, 5e5), "F10": st.floats(0.0, 60.0), "b1": st.floats(0.0, 5.0),
    "b2": st.floats(0.0, 300.0), "b3": st.floats(0.0, 30.0), "F30": st.floats(0.0, 20.0),
    "compression_only": st.sampled_from([0, 1])})


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(values=VALID_PUNCH)
@example(values={"m": 0.0078125, "c1": 5965.0, "c2": 1000.0, "c3": 64466.0, "F10": 0.0,
                 "b1": 0.0, "b2": 0.0, "b3": 19.0, "F30": 12.0, "compression_only": 1})
                 # found by a random run: the punch bouncing on the stop of spring 11
def test_random_valid_parameters_never_crash_the_host(fmu_paths, values):
    host = Host(fmu_paths["PunchContact"], "punch")
    host.set(**values, xi=3e-3, xi_dot=-0.4, xi_ddot=0.0)
    host.fmu.exitInitializationMode()
    for step in range(30):                       # falling onto the fabric and pressing
        host.set(xi=3e-3 - 0.4 * step * 5e-4, xi_dot=-0.4)
        host.fmu.doStep(step * 5e-4, 5e-4)
    outputs = host.get("y", "y_dot", "F1", "F2", "F3")
    assert all(math.isfinite(v) for v in outputs)
    assert outputs[3] >= 0.0


@settings(max_examples=8 * settings().max_examples)
@given(values=VALID_PUNCH, h=st.sampled_from([1e-4, 5e-4, 2e-3]), speed=st.floats(-2.0, 0.5),
       acc=st.floats(-500.0, 500.0))
def test_random_parameters_and_slider_motions_keep_the_punch_model_sound(values, h, speed, acc):
    """The model itself, many more draws than through the FMU: any valid parameter set under a
    slider moving with constant acceleration runs 20 ms without a chatter error, with finite
    outputs, a fabric that only pushes, and a compression-only spring 11 that only pushes."""
    model = PunchContact(PunchContactParams(**values))
    s = model.initial_state(3e-3, speed, acc)
    for k in range(1, int(round(0.02 / h)) + 1):
        t = (k - 1) * h
        s = model.step(s, 3e-3 + t * (speed + 0.5 * acc * t), speed + acc * t, 0.5 * acc, h)
        t += h
        out = model.outputs(s, 3e-3 + t * (speed + 0.5 * acc * t), speed + acc * t, acc)
        assert all(math.isfinite(v) for v in (out.y, out.y_dot, out.y_ddot, out.F3))
        assert out.F2 >= 0.0
        if values["compression_only"]:
            assert out.F3 >= -1e-9 * (1.0 + values["F30"])


@settings(suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=st.sampled_from(POSITIVE + NONNEGATIVE),
       value=st.one_of(st.just(float("nan")), st.just(float("inf")), st.just(-float("inf")),
                       st.floats(-1e6, -1e-9)))
def test_random_invalid_parameters_always_get_a_clear_error(fmu_paths, name, value):
    host = Host(fmu_paths["PunchContact"], "punch")
    host.set(**{name: value})
    host.fmu.exitInitializationMode()
    errors = [line for line in host.log.lines if line.startswith("[ERROR]")]
    assert errors and f"parameter {name}" in errors[0], host.log.lines
    with pytest.raises(FMICallException, match="discard"):
        host.fmu.doStep(0.0, 1e-4)
    assert f"parameter {name}" in host.log.lines[-1]
