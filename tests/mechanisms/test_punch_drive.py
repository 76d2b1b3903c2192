"""The punch_drive scenario: co-simulation against the monolithic solution (scipy DOP853 with
event location), convergence with the communication step, and the command line."""
import hashlib
import json
import math

import numpy as np
import pytest

from sewfmu.cli import main
from sewfmu.components.parameters import parameter_info
from sewfmu.components.punch_contact import PunchContactParams
from sewfmu.scenarios.cosim.master import run
from sewfmu.scenarios.fmu_build.build import current_version
from sewfmu.scenarios.format.loader import load, resolve
from sewfmu.scenarios.mechanisms import punch as punch_drive
from sewfmu.scenarios.runs.compare import monolithic_summary
from sewfmu.scenarios.runs.results import run_scenario
from sewfmu.scenarios.runs.runner import summarize


@pytest.fixture(scope="module")
def monolithic():
    return monolithic_summary(load("punch_drive"))[0]


@pytest.mark.parametrize("master", ["jacobi", "gauss-seidel"])
def test_summary_figures_match_the_monolithic_solution(fmu_paths, monolithic, master):
    sc = load("punch_drive")
    sc.master = master
    figures = summarize(run(sc, fmu_paths))
    assert figures["n_contacts"] == monolithic["n_contacts"] == 1
    # just above what the code gives (both masters alike): onset +0.044°, loss +0.005°, duration
    # -0.039°, F2_peak -0.0003 N, F2_weld_mean -0.0012 N (docs/punch_drive.md: within 0.04° and
    # 0.002 N)
    for key, within in (("contact_onset_deg", 0.05), ("contact_loss_deg", 0.01),
                        ("contact_duration_deg", 0.05), ("F2_peak", 0.001),
                        ("F2_weld_mean", 0.002)):
        assert abs(figures[key] - monolithic[key]) < within, (key, figures[key] - monolithic[key])
    # the paper: at ω = 100 s⁻¹ the pressing force during welding is practically constant, ≈ 22 N
    assert 20.0 < figures["F2_weld_mean"] < 25.0


def _trajectory_error(fmu_paths, master, h, revolutions=3):
    sc = load("punch_drive")
    sc.master, sc.step, sc.revolutions = master, h, revolutions
    result = run(sc, fmu_paths)
    t_end = result.time[-1]
    h = sc.even_steps()[1]                # the run's whole, even steps
    mono = punch_drive.solve({"omega0": 100.0}, {}, {}, t_end, sample_step=h,
                                sample_switches=False)
    n = len(result.time) - 1              # the last step may be shorter: compare the grid
    assert np.allclose(mono.time[:n], result.time[:n], rtol=0, atol=1e-12)
    return np.max(np.abs(result["punch.y"][:n] - mono.y[:n]))


@pytest.mark.slow
@pytest.mark.parametrize("master", ["jacobi", "gauss-seidel"])
def test_error_shrinks_with_the_step_at_the_observed_order(fmu_paths, master):
    steps = [1e-3, 5e-4, 2.5e-4]
    errors = [_trajectory_error(fmu_paths, master, h) for h in steps]
    orders = [math.log2(a / b) for a, b in zip(errors, errors[1:])]
    # the body is integrated exactly; the error comes from the Taylor extrapolation of ξ within a
    # step: observed order ≈ 2.6 (see README)
    assert all(o > 2.0 for o in orders), (errors, orders)
    assert errors[-1] < 2e-8                  # 0.02 µm of punch height at 2.5e-4 s


@pytest.mark.slow
def test_punch_held_on_a_preloaded_stop_matches_the_monolithic_solution(fmu_paths):
    """Compression-only spring 11 with a 30 N preload: the punch rides on the stop for most of the
    revolution (the monolithic solution says how long), lands, leaves the stop and is picked up again. The
    co-simulation's punch height and spring-11 force follow the monolithic solution."""
    h = 2.5e-4
    punch = {"compression_only": 1, "F30": 30.0}
    sc = load("punch_drive")
    sc.step, sc.revolutions = h, 3
    for name, value in punch.items():
        sc.set_value(f"punch.{name}", value)
    result = run(sc, fmu_paths)
    step = sc.even_steps()[1]           # the run's own step: whole, even steps to its end
    mono = punch_drive.solve({"omega0": 100.0}, {}, punch, result.time[-1], sample_step=step,
                                sample_switches=False)
    n = len(result.time) - 1
    assert 0.5 < np.mean(mono.held[:n]) < 0.9
    assert np.max(np.abs(result["punch.y"][:n] - mono.y[:n])) < 5e-8
    assert np.max(np.abs(result["punch.F3"][:n] - mono.F3[:n])) < 0.05


def test_cli_run_writes_results_summary_and_plot(tmp_path, fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))
    out = tmp_path / "out"
    assert main(["run", "punch_drive", "--set", "shaft.omega0=200", "--set",
                 "experiment.revolutions=4", "--out", str(out), "--plot"]) == 0
    header = [name.split(" [")[0]         # "punch.F2 [N]": each column names its unit
              for name in (out / "results.csv").read_text().splitlines()[0].split(",")]
    assert header[0] == "time" and {"shaft.phi", "linkage.xi", "punch.y", "punch.F2",
                                    "punch.contact"} <= set(header)
    data = np.loadtxt(out / "results.csv", delimiter=",", skiprows=1)
    assert data[-1, header.index("shaft.phi")] == pytest.approx(8 * math.pi, rel=1e-12)
    summary = json.loads((out / "summary.json").read_text())
    for key in ("contact_onset_deg", "contact_loss_deg", "contact_duration_deg", "n_contacts",
                "F2_peak", "F2_weld_mean"):
        assert key in summary
    assert (out / "punch_drive.png").stat().st_size > 10_000


@pytest.mark.parametrize("args, message", [
    (["run", "no_such_scenario"], "unknown scenario"),
    (["run", "punch_drive", "--set", "punch.mass=1"], "has no parameter 'mass'"),
    (["run", "punch_drive", "--set", "press.c3=1"], "unknown instance 'press'"),
    (["run", "punch_drive", "--set", "punch.c3=stiff"], "must be a number"),
    (["run", "punch_drive", "--set", "experiment.step=0"], "positive"),
    (["run", "punch_drive", "--set", "punch.m=-1"], "parameter m"),
    (["run", "punch_drive", "--set", "linkage.L_AB=0.029"], "crank angle"),
])
def test_cli_errors_are_one_clear_line(args, message, capsys, tmp_path, fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))
    assert main(args + ["--out", str(tmp_path)]) != 0
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err
    assert not (tmp_path / "results.csv").exists()


@pytest.mark.slow
def test_summary_records_what_produced_it(fmu_dir, tmp_path, monkeypatch):
    """Two runs that differ in c3 have summaries that tell them apart: every parameter value used
    (defaults included, the scenario's own marked), the scenario file's hash, master, step,
    sewfmu's version and each FMU's code."""
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))
    summaries = []
    for c3 in (1e5, 2e5):
        sc = load("punch_drive")
        sc.set_value("punch.c3", c3)
        run_scenario(sc, tmp_path / str(c3))
        summaries.append(json.loads((tmp_path / str(c3) / "summary.json").read_text()))
    made = [s["provenance"] for s in summaries]
    punch = [m["instances"]["punch"]["parameters"] for m in made]
    assert punch[0]["c3"] == {"value": 1e5, "unit": "N/m", "set": True}
    assert punch[1]["c3"]["value"] == 2e5
    assert punch[0]["m"] == {"value": PunchContactParams().m, "unit": "kg", "set": False}
    assert set(punch[0]) == {info.name for info in parameter_info(PunchContactParams)}
    assert made[0]["scenario"]["sha256"] == hashlib.sha256(
        resolve("punch_drive").read_bytes()).hexdigest()
    assert made[0]["master"] == "jacobi" and made[0]["step"] == 2.5e-4
    assert set(made[0]["fmus"]) == {"MainShaft", "PunchLinkage", "PunchContact"}
    assert all(v == current_version() for v in made[0]["fmus"].values())


def test_the_monolithic_figures_of_a_run_cut_between_revolutions_are_its_last_whole_ones():
    """A stop time between two revolutions (0.17 s at 100 rad/s: 2.7 turns) is read, as the
    co-simulation reads it, over the last whole revolution, the second: the same figures as
    the monolithic solution of exactly two revolutions (the window once began inside it)."""
    cut, whole = load("punch_drive"), load("punch_drive")
    cut.set_value("experiment.stop_time", 0.17)
    whole.set_value("experiment.revolutions", 2)
    a, b = monolithic_summary(cut)[0], monolithic_summary(whole)[0]
    for figure in ("contact_onset_deg", "contact_loss_deg", "F2_weld_mean", "n_contacts"):
        assert a[figure] == pytest.approx(b[figure], rel=1e-6, abs=1e-6), figure
