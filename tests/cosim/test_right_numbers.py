"""Right numbers or a clear refusal, written as the attack: a host that leaves rate inputs unset,
runs that do not end on a whole revolution, a diverging coupling, an input nobody connects,
values in the wrong unit, names that try to write outside the output folder, SSP archives that
try to exhaust the host, runs too large to record."""
import json
import math
import os
import stat
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description
from scipy.integrate import solve_ivp
from scipy.linalg import eigh

from sewfmu.cli import main
from sewfmu.components.carriage import CarriageModal, CarriageParams
from sewfmu.console import explain
from sewfmu.scenarios.cosim.divergence import Diverged, DivergenceWatch
from sewfmu.scenarios.cosim.master import Master, run
from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.format.values import ScenarioError
from sewfmu.scenarios.mechanisms.base import RunTooShort
from sewfmu.scenarios.runs.compare import monolithic_summary
from sewfmu.scenarios.runs.results import run_scenario
from sewfmu.scenarios.runs.runner import summarize
from tests.fmu_host import Host


def _closed_form_static(a_base: float) -> tuple[float, float]:
    """(U1, U2) under a steady base acceleration, from beam theory alone: the guide is a
    cantilever loaded by its own inertia ρ·a spread along it (ρ = m_n/l) and the carriage's m_k·a
    at the tip (J_c does not enter: nothing turns). Deflection at z of a unit load at s:
    z²(3s − z)/(6EJ) for z ≤ s; by reciprocity the spread load deflects z = s by ρ·a·∫ w_s dz."""
    p = CarriageParams()
    l, a, EJ, rho = p.l, p.a, p.EJ, p.m_n / p.l
    tip = rho * l ** 4 / (8 * EJ) + p.m_k * l ** 3 / (3 * EJ)
    at_a = (rho * (a ** 4 / (8 * EJ) + a * a / (6 * EJ) * (1.5 * (l * l - a * a) - a * (l - a)))
            + p.m_k * a * a * (3 * l - a) / (6 * EJ))
    return -at_a * a_base, -tip * a_base


@pytest.mark.slow
@pytest.mark.parametrize("step", [1e-3, 1e-4])
@pytest.mark.parametrize("every_step", [True, False], ids=["set-every-step", "set-once"])
def test_a_host_that_never_sets_the_rate_gets_the_static_deflection(fmus, step, every_step):
    """a_base = 1 m/s² and a_base_dot never set: the carriage stays in its static deflection
    (−50.27 µm at the tip), whether the host sets the acceleration every step or once."""
    U1, U2 = _closed_form_static(1.0)
    assert U2 == pytest.approx(-50.27e-6, rel=1e-4)          # docs/carriage.md's number
    host = Host(fmus["CarriageModal"])
    host.set(a_base=1.0)
    host.fmu.exitInitializationMode()
    t, worst = 0.0, 0.0
    deflections = [host.vr["U1"], host.vr["U2"]]
    for k in range(int(round(2.0 / step))):
        if every_step:
            host.set(a_base=1.0)
        host.fmu.doStep(t, step)
        t += step
        got = host.fmu.getReal(deflections)
        worst = max(worst, abs(got[0] - U1), abs(got[1] - U2))
    assert worst < 1e-12                      # 2e-8 of U2
    host.close()


def _carriage_from_rest(a_of, knots) -> np.ndarray:
    """(U2, U2_dot) at the knots of the carriage starting at rest under the base acceleration
    a_of(t), smooth between knots: M·Ü + C·U̇ + K·U = −p·a(t) integrated by scipy (DOP853) knot
    to knot, from the model's matrices, C = M·Φ·diag(2ζω)·Φᵀ·M from scipy's modes."""
    model = CarriageModal()
    K, M, p = np.array(model.K), np.array(model.M), np.array(model.load)
    lam, phi = eigh(K, M)                                    # mass-normalized
    C = M @ phi @ np.diag(2 * model.p.zeta * np.sqrt(lam)) @ phi.T @ M
    M_inv = np.linalg.inv(M)

    def rhs(t, s):
        return np.concatenate([s[2:], M_inv @ (-p * a_of(t) - C @ s[2:] - K @ s[:2])])

    state, out = np.zeros(4), []
    for t0, t1 in zip(knots, knots[1:]):
        state = solve_ivp(rhs, (t0, t1), state, method="DOP853", rtol=1e-12,
                          atol=1e-18).y[:, -1]
        out.append((state[1], state[3]))
    return np.array(out)


def test_a_rate_set_with_its_value_is_used_and_a_stale_one_is_not(fmus):
    """Given the rate with the value the FMU extrapolates (a ramp is followed exactly); once the
    host stops giving the rate, the value is held."""
    host = Host(fmus["CarriageModal"])
    host.fmu.exitInitializationMode()
    h = 1e-3
    got = []
    for k in range(10):
        if k < 5:                           # a ramp of the base acceleration: 1000 m/s³
            host.set(a_base=1000.0 * k * h, a_base_dot=1000.0)
        else:                               # then only the value, 5 m/s², where the ramp ended
            host.set(a_base=5.0)
        host.fmu.doStep(k * h, h)
        got.append(host.get("U2", "U2_dot"))
    knots = np.arange(11) * h
    want = _carriage_from_rest(lambda t: 1000.0 * min(t, 5 * h), knots)
    scale = np.max(np.abs(want), axis=0)                     # ≈ 1.1e-4 m, 2.5e-2 m/s
    assert np.all(np.abs(np.array(got) - want) <= 1e-10 * scale)     # measured: 5e-14
    # a held value (the rate ignored: 12 % off) or a stale rate (the ramp going on: 16 %)
    staircase = _carriage_from_rest(lambda t: 1000.0 * min(math.floor(t / h + 1e-9) * h,
                                                           5 * h), knots)
    ramp_on = _carriage_from_rest(lambda t: 1000.0 * t, knots)
    assert np.max(np.abs(staircase - want)[:, 0]) > 0.05 * scale[0]
    assert np.max(np.abs(ramp_on - want)[:, 0]) > 0.05 * scale[0]
    descriptions = {v.name: v.description for v in host.md.modelVariables}
    assert "acts as zero unless set" in descriptions["a_base_dot"]
    host.close()


# --- whole revolutions, whole steps --------------------------------------------------------
def test_a_run_between_revolutions_reads_the_last_whole_one(fmu_paths):
    sc = load("punch_drive")
    sc.set_value("experiment.stop_time", 0.6)        # 9.55 revolutions at 100 s⁻¹
    partial = summarize(run(sc, fmu_paths))
    sc = load("punch_drive")
    sc.set_value("experiment.revolutions", 9)
    whole = summarize(run(sc, fmu_paths))
    for key in ("contact_onset_deg", "contact_loss_deg"):
        assert partial[key] == pytest.approx(whole[key], abs=0.05)
    assert partial["F2_weld_mean"] == pytest.approx(whole["F2_weld_mean"], abs=0.01)
    assert partial["n_contacts"] == 1


def test_a_run_shorter_than_a_revolution_is_refused(fmu_paths, capsys, tmp_path):
    sc = load("punch_drive")
    sc.set_value("experiment.stop_time", 0.05)
    with pytest.raises(RunTooShort, match="0.7958 revolutions"):
        summarize(run(sc, fmu_paths))
    assert main(["run", "punch_drive", "--set", "experiment.stop_time=0.05",
                 "--out", str(tmp_path / "out")]) == 1
    assert "whole revolution" in capsys.readouterr().err


def test_steps_are_whole_and_even_and_end_on_the_revolution(fmu_paths):
    sc = load("punch_drive")                           # 2513.27 steps of 2.5e-4 s
    result = run(sc, fmu_paths)
    steps = np.diff(result.time)
    assert steps.max() - steps.min() < 1e-15
    assert steps.max() <= 2.5e-4
    assert result.time[-1] == sc.end_time()
    assert result["shaft.phi"][-1] == pytest.approx(20 * math.pi, rel=1e-12)


def test_every_default_experiment_is_a_whole_number_of_steps(fmus):
    for name, path in fmus.items():
        experiment = read_model_description(str(path)).defaultExperiment
        n = float(experiment.stopTime) / float(experiment.stepSize)
        assert abs(n - round(n)) < 1e-6, name


# --- divergence ------------------------------------------------------------------------------
@pytest.mark.parametrize("step", [2e-3, 1.6e-3])
def test_a_diverging_jacobi_run_is_stopped_and_named(fmu_paths, step):
    sc = load("punch_split")
    sc.set_value("experiment.master", "jacobi")
    sc.set_value("experiment.step", step)
    with pytest.raises(Diverged) as caught:
        run(sc, fmu_paths)
    text = str(caught.value)
    assert "diverged at t = " in text and "body, fabric" in text
    assert "experiment.step" in text and "iterative" in text


class _FakeInstance:
    """An FMU instance that declares no ranges, as an FMU of another tool may."""

    class _Var:
        min = max = None
        unit = "N"

    def __init__(self, name):
        self.name = name
        self.inputs = [("F", self, "F")]
        self.variables = {"F": self._Var()}
        self.in_buf = [0.0]


def test_growth_without_declared_ranges_is_divergence_too():
    inst = _FakeInstance("spring")
    watch = DivergenceWatch([inst], 1e-3)
    value, t = 1.0, 0.0
    with pytest.raises(Diverged, match="grew"):
        for k in range(10_000):
            value *= -1.2                  # the sign-alternating growth of an unstable coupling
            inst.in_buf[0] = value
            t += 1e-3
            watch.check(t)
    steady = DivergenceWatch([inst], 1e-3)
    for k in range(10_000):                 # a bounded oscillation is physics, not divergence
        inst.in_buf[0] = 25.0 * math.sin(0.3 * k)
        steady.check(k * 1e-3)


@pytest.mark.parametrize("tolerance", [1e300, 1.0, 1e-30])
def test_a_tolerance_the_master_cannot_honour_is_refused(fmu_paths, tolerance):
    sc = load("punch_split")                            # its own master: adaptive
    sc.set_value("experiment.tolerance", tolerance)
    with pytest.raises(ScenarioError, match="honours tolerances"):
        run(sc, fmu_paths)


# --- inputs nobody connects ------------------------------------------------------------------
def _without(connection: str, tmp_path, extra: str = "") -> str:
    text = load("punch_drive").source
    toml = open(text).read().replace(f'"{connection}",', "")
    path = tmp_path / "open_input.toml"
    path.write_text(toml + extra)
    return str(path)


def test_an_input_left_unconnected_is_named(fmu_paths, tmp_path):
    sc = load(_without("linkage.xi -> punch.xi", tmp_path))
    with pytest.raises(ScenarioError, match="input punch.xi is neither connected nor given"):
        run(sc, fmu_paths)


@pytest.mark.slow
def test_an_input_given_a_value_runs_held_there(fmu_paths, tmp_path):
    sc = load(_without("linkage.xi_ddot -> punch.xi_ddot", tmp_path))
    sc.set_value("punch.xi_ddot", 0.0)
    with Master(sc, fmu_paths) as master:
        while not master.finished():
            master.step()
        punch = next(inst for inst in master.instances if inst.name == "punch")
        held = punch.fmu.getReal([punch.variables["xi_ddot"].valueReference])[0]
        figures = summarize(master.result())
    assert held == 0.0                     # as given, to the end (its start value is -44.87)
    # the punch sees ξ extrapolated to first order only; measured against the monolithic
    # solution: onset +0.029°, loss +0.026°, F2_peak +0.016 N, F2_weld_mean +0.0011 N (connected,
    # F2_peak is within 0.0003 N: the larger error says ξ'' really is missing)
    mono = monolithic_summary(load("punch_drive"))[0]
    assert figures["n_contacts"] == mono["n_contacts"] == 1
    for key, within in (("contact_onset_deg", 0.035), ("contact_loss_deg", 0.03),
                        ("F2_peak", 0.02), ("F2_weld_mean", 0.0015)):
        assert abs(figures[key] - mono[key]) < within, key
    assert figures["F2_peak"] - mono["F2_peak"] > 0.01


# --- units and ranges ------------------------------------------------------------------------
def test_values_with_units_convert_by_the_declared_definitions(fmu_paths):
    plain, with_units = load("punch_drive"), load("punch_drive")
    plain.set_value("linkage.angle_BO2C", math.radians(110.0))
    plain.set_value("shaft.omega0", 955 * 2 * math.pi / 60)
    plain.set_value("punch.m", 0.063)
    with_units.set_value("linkage.angle_BO2C", "110 deg")
    with_units.set_value("shaft.omega0", "955 rpm")
    with_units.set_value("punch.m", "63 g")
    assert with_units.instances["linkage"].parameters == plain.instances["linkage"].parameters
    assert with_units.instances["shaft"].parameters["omega0"] == pytest.approx(100.0073661)
    assert with_units.instances["punch"].parameters["m"] == pytest.approx(0.063)
    sc = load("carriage_startstop")
    sc.set_value("drive.stitch_length", "3 mm")
    assert sc.instances["drive"].parameters["stitch_length"] == pytest.approx(3e-3)
    sc.set_value("shaft.omega0", "1600 st/min")
    assert sc.instances["shaft"].parameters["omega0"] == pytest.approx(1600 * math.pi / 30)


@pytest.mark.parametrize("target, value, said", [
    ("linkage.angle_BO2C", 110, '"110 deg"'),          # degrees meant
    ("punch.m", 63, '"63 g"'),                           # grams meant
])
def test_a_value_in_the_wrong_unit_is_refused_with_the_unit_meant(fmu_paths, target, value,
                                                                   said):
    sc = load("punch_drive")
    sc.set_value(target, value)
    with pytest.raises(ScenarioError, match="outside the range") as caught:
        run(sc, fmu_paths)
    assert said in str(caught.value)


def test_a_length_meant_in_mm_is_refused(fmu_paths):
    sc = load("carriage_startstop")
    sc.set_value("drive.stitch_length", 3)
    with pytest.raises(ScenarioError, match="stitch_length"):
        run(sc, fmu_paths)


@pytest.mark.parametrize("text", ["110 kg", "110 furlongs", "deg 110", "1 2 deg"])
def test_a_unit_that_does_not_fit_is_one_line(text):
    sc = load("punch_drive")
    with pytest.raises(ScenarioError) as caught:
        sc.set_value("linkage.angle_BO2C", text)
    assert "\n" not in str(caught.value) and "angle_BO2C" in str(caught.value)


def test_the_fmus_refuse_values_outside_their_declared_ranges(fmus):
    md = read_model_description(str(fmus["PunchLinkage"]))
    angle = next(v for v in md.modelVariables if v.name == "angle_BO2C")
    assert (float(angle.min), float(angle.max)) == (0.0, pytest.approx(2 * math.pi))
    assert angle.displayUnit == "deg"
    units = {u.name: {d.name for d in u.displayUnits} for u in md.unitDefinitions}
    assert {"deg"} <= units["rad"] and {"rpm", "st/min"} <= units["rad/s"]
    host = Host(fmus["PunchLinkage"])
    host.set(angle_BO2C=110.0)
    host.fmu.exitInitializationMode()
    assert "angle_BO2C" in host.log_text() and "110 deg" in host.log_text()
    host.close()
    host = Host(fmus["Fabric"])
    host.fmu.exitInitializationMode()
    host.set(y=-3.0)                                    # three metres into the fabric
    with pytest.raises(Exception):
        host.fmu.doStep(0.0, 1e-4)
    assert "outside its range" in host.log_text()
    host.close()


def test_results_and_summary_say_their_units(fmu_paths, tmp_path):
    run_scenario(load("punch_drive"), tmp_path)
    header = (tmp_path / "results.csv").read_text().splitlines()[0].split(",")
    assert header[0] == "time [s]"
    assert "punch.F2 [N]" in header and "shaft.phi [rad]" in header
    assert "punch.contact" in header                   # a Boolean has no unit
    units = json.loads((tmp_path / "summary.json").read_text())["units"]
    assert units["F2_weld_mean"] == "N" and units["contact_onset_deg"] == "deg"


# --- nothing written outside --out -----------------------------------------------------------
@pytest.mark.parametrize("name", ["/tmp/evil", "../up", "a/b", "x\\y", ".hidden", ""])
def test_an_instance_name_that_is_a_path_is_refused(tmp_path, name):
    quoted = name.replace("\\", "\\\\")                     # as TOML writes it
    text = open(load("punch_drive").source).read().replace("[instances.punch]",
                                                            f'[instances."{quoted}"]')
    path = tmp_path / "named.toml"
    path.write_text(text.replace("-> punch.", f"-> {quoted}.").replace('"punch.',
                                                                       f'"{quoted}.'))
    with pytest.raises(ScenarioError, match="instance name"):
        load(str(path))


@pytest.mark.slow
def test_compare_variants_with_slashes_stay_inside_the_output_folder(fmu_paths, tmp_path):
    sc = load("punch_drive")
    sc.revolutions = 1
    sc.compare = {"parameter": "shaft.omega0", "values": ["100 st/min", "110 st/min"]}
    out = tmp_path / "out"
    run_scenario(sc, out)
    written = [p for p in tmp_path.rglob("*") if p.is_file()]
    assert written and all(out in p.parents for p in written)
    assert len(list(out.glob("*/results.csv"))) == 2


def _ssp_with(tmp_path, members: dict, modes: dict | None = None) -> str:
    path = tmp_path / "attack.ssp"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in members.items():
            info = zipfile.ZipInfo(name)
            info.compress_type = zipfile.ZIP_DEFLATED
            if modes and name in modes:
                info.external_attr = modes[name] << 16
            z.writestr(info, data)
    return str(path)


_SSD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
  xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="x">
 <ssd:System name="x"><ssd:Elements>
  <ssd:Component name="{name}" source="resources/MainShaft.fmu">
   <ssd:ParameterBindings><ssd:ParameterBinding source="{ssv}"/></ssd:ParameterBindings>
  </ssd:Component></ssd:Elements></ssd:System>
 <ssd:DefaultExperiment startTime="0" stopTime="0.1"/>
</ssd:SystemStructureDescription>"""


def test_ssp_references_outside_the_archive_are_refused(fmu_paths, tmp_path):
    fmu = fmu_paths["MainShaft"].read_bytes()
    for ssv in ("/etc/passwd", "/dev/zero", "../../../../etc/hostname"):
        ssp = _ssp_with(tmp_path, {"SystemStructure.ssd": _SSD.format(name="shaft", ssv=ssv),
                                   "resources/MainShaft.fmu": fmu})
        with pytest.raises(ScenarioError, match="not a file inside"):
            load(ssp)


def test_a_fifo_named_by_an_ssd_does_not_hang(fmu_paths, tmp_path):
    folder = tmp_path / "system"
    (folder / "resources").mkdir(parents=True)
    (folder / "resources" / "MainShaft.fmu").write_bytes(fmu_paths["MainShaft"].read_bytes())
    os.mkfifo(folder / "values.ssv")
    (folder / "SystemStructure.ssd").write_text(_SSD.format(name="shaft", ssv="values.ssv"))
    with pytest.raises(ScenarioError, match="not a file inside"):
        load(str(folder / "SystemStructure.ssd"))


def test_an_ssp_component_named_as_a_path_is_refused(fmu_paths, tmp_path):
    ssp = _ssp_with(tmp_path, {
        "SystemStructure.ssd": _SSD.format(name="/tmp/evil", ssv="x.ssv"),
        "resources/MainShaft.fmu": fmu_paths["MainShaft"].read_bytes()})
    with pytest.raises(ScenarioError, match="instance name"):
        load(ssp)


def test_zip_bombs_links_and_member_floods_are_refused(tmp_path, monkeypatch):
    from sewfmu.scenarios.format import ssp_import

    monkeypatch.setattr(ssp_import, "MAX_UNPACKED_BYTES", 1 << 20)
    bomb = _ssp_with(tmp_path, {"SystemStructure.ssd": "<x/>", "zeros": b"\0" * (8 << 20)})
    assert os.path.getsize(bomb) < 100_000
    with pytest.raises(ScenarioError, match="zip bomb"):
        load(bomb)
    link = _ssp_with(tmp_path, {"SystemStructure.ssd": "<x/>", "link": "/etc/passwd"},
                     {"link": stat.S_IFLNK | 0o777})
    with pytest.raises(ScenarioError, match="not a regular file"):
        load(link)
    monkeypatch.setattr(ssp_import, "MAX_MEMBERS", 50)
    flood = _ssp_with(tmp_path, {f"m{k}": "" for k in range(60)})
    with pytest.raises(ScenarioError, match="archive members"):
        load(flood)


# --- size ------------------------------------------------------------------------------------
@pytest.mark.parametrize("step, said", [(4e-8, "GiB"), (1e-12, "FMU steps")])
def test_runs_too_large_to_record_are_refused_up_front(fmu_paths, step, said):
    sc = load("punch_drive")
    sc.set_value("experiment.step", step)
    with pytest.raises(ScenarioError, match=said):
        run(sc, fmu_paths)


@pytest.mark.slow
def test_record_every_does_not_change_the_key_figures(fmu_paths):
    sc = load("punch_drive")
    every = summarize(run(sc, fmu_paths))
    sc.set_value("experiment.record_every", 100)
    thinned = run(sc, fmu_paths)
    assert len(thinned.time) < 0.2 * 2514
    figures = summarize(thinned)
    for key in ("contact_onset_deg", "contact_loss_deg", "F2_peak", "F2_weld_mean"):
        assert figures[key] == every[key], key


# --- sweeps and errors -----------------------------------------------------------------------
@pytest.mark.parametrize("scenario, grid", [("takeup", "shaft.omega0=400,500"),
                                            ("feed", "shaft.omega0=150,170"),
                                            ("carriage_startstop", "shaft.omega0=150,170")])
@pytest.mark.slow
def test_sweep_plots_and_reports_every_analysis(tmp_path, scenario, grid):
    out = tmp_path / "sweep"
    assert main(["sweep", scenario, "--grid", grid, "--workers", "1", "--plot", "--report",
                 "--quiet", "--out", str(out)]) == 0
    assert (out / f"{scenario}_sweep.png").stat().st_size > 1000
    assert (out / "report.html").exists()


def test_a_missing_extra_names_the_command_that_installs_it():
    err = ModuleNotFoundError("No module named 'distributed'", name="distributed")
    text = explain(err, "sweep")
    # from where this sewfmu was installed (here: the checkout, editable)
    assert "bug" not in text and 'pip install -e "' in text and '[dask]"' in text, text
