"""Regression references for FMUs sewfmu did not make, and for sewfmu's own: recorded, carried
inside the FMU (fmi-ls-ref), checked from the command line and from pytest, and a changed build
caught with the variable, the time and both values.

The third-party FMU is a plain pythonfmu FMU made here: a mass on a spring, x'' = -k·x, stepped
by semi-implicit Euler. Its outputs have a closed form (the recurrence, computed here with
numpy), against which the reported first deviation is checked.
"""
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from sewfmu.scenarios.fmu_build.build import MODEL_CODE_DIR, build_fmu
from sewfmu.scenarios.fmu_build.carried_reference import LS_REF, MANIFEST
from sewfmu.scenarios.format.values import ScenarioError
from sewfmu.scenarios.references import reference_check

pytestmark = pytest.mark.slow

_SPRING = '''
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real
from pythonfmu.default_experiment import DefaultExperiment


class Spring(Fmi2Slave):
    """A mass on a spring (semi-implicit Euler)."""

    author = "someone else"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.k, self.x, self.v = {k}, 1.0, 0.0
        self.default_experiment = DefaultExperiment(start_time=0.0, stop_time=2.0,
                                                    step_size=0.01)
        self.register_variable(Real("k", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.fixed))
        self.register_variable(Real("x", causality=Fmi2Causality.output))
        self.register_variable(Real("v", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.v -= self.k * self.x * step_size
        self.x += self.v * step_size
        return True
'''


def _spring(folder: Path, k: float, tag: str) -> Path:
    """A Spring FMU whose stiffness is k. Each build's script has its own module name: a host
    imports FMU scripts by name, and two builds of one name would share the first's code."""
    from pythonfmu.builder import FmuBuilder

    folder.mkdir(parents=True, exist_ok=True)
    script = folder / f"spring_{tag}.py"
    script.write_text(_SPRING.format(k=k))
    FmuBuilder.build_FMU(script, dest=folder / tag)
    return folder / tag / "Spring.fmu"


def _recurrence(k: float, h: float = 0.01, steps: int = 200) -> tuple[np.ndarray, np.ndarray]:
    x, v, xs = 1.0, 0.0, [1.0]
    for _ in range(steps):
        v -= k * x * h
        x += v * h
        xs.append(x)
    return np.arange(steps + 1) * h, np.array(xs)


def _sewfmu(*args, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sewfmu", "references", *map(str, args)],
                          capture_output=True, text=True, timeout=300, cwd=cwd)


def test_a_third_party_fmu_is_recorded_and_a_changed_build_is_caught(tmp_path):
    original, changed = _spring(tmp_path, 40.0, "v1"), _spring(tmp_path, 40.4, "v2")
    refs = tmp_path / "refs"
    made = _sewfmu("--fmu", original, "--refs", refs, "--regenerate", cwd=tmp_path)
    assert made.returncode == 0, made.stderr
    assert sorted(p.name for p in (refs / "Spring").iterdir()) == ["Spring_ref.csv",
                                                                   "Spring_ref.opt"]
    recorded = np.genfromtxt(refs / "Spring" / "Spring_ref.csv", delimiter=",", names=True)
    t, x = _recurrence(40.0)
    assert np.allclose(recorded["time"], t) and np.allclose(recorded["x"], x, atol=1e-12)

    same = _sewfmu("--fmu", original, "--refs", refs, cwd=tmp_path)
    assert same.returncode == 0 and "Spring.fmu: matches" in same.stdout, same.stdout + same.stderr

    caught = _sewfmu("--fmu", changed, "--refs", refs, "--plot", tmp_path / "plots",
                     cwd=tmp_path)
    assert caught.returncode == 1
    assert caught.stderr.strip() == "sewfmu: error: 2 variables deviate from their references"
    line = next(s for s in caught.stdout.splitlines() if s.startswith("Spring: x "))
    # the first time the 1 % stiffer spring leaves the tolerance, from the recurrences
    allowed = 1e-12 + 1e-6 * np.max(np.abs(x))
    first = int(np.argmax(np.abs(_recurrence(40.4)[1] - x) > allowed))
    assert line.startswith(f"Spring: x leaves the tolerance at t = {t[first]:g} s: "), line
    assert f"the reference {x[first]:.10g}" in line
    assert (tmp_path / "plots" / "Spring_differences.png").stat().st_size > 1000
    # a looser tolerance lets the change pass, as the user asked
    assert _sewfmu("--fmu", changed, "--refs", refs, "--rtol", "0.2", cwd=tmp_path).returncode == 0


def test_the_pytest_fixture_gives_the_same_check(tmp_path):
    original, changed = _spring(tmp_path, 40.0, "v1"), _spring(tmp_path, 40.4, "v2")
    refs = tmp_path / "refs"
    assert _sewfmu("--fmu", original, "--refs", refs, "--regenerate", cwd=tmp_path).returncode == 0
    (tmp_path / "test_springs.py").write_text(
        f"def test_original(fmu_reference):\n"
        f"    fmu_reference({str(original)!r}, {str(refs)!r})\n\n"
        f"def test_changed(fmu_reference):\n"
        f"    fmu_reference({str(changed)!r}, {str(refs)!r})\n")
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           str(tmp_path / "test_springs.py")], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path)
    assert "1 failed, 1 passed" in proc.stdout, proc.stdout[-3000:]
    assert "2 variables deviate from their references:" in proc.stdout
    assert "Spring: x leaves the tolerance at t = " in proc.stdout


def _carry(fmu: Path, model: str, t: np.ndarray, x: np.ndarray) -> None:
    """Put a reference into an FMU as the Modelica Reference-FMUs do (fmi-ls-ref)."""
    rows = "\n".join(f"{float(a)!r},{float(b)!r}" for a, b in zip(t, x))
    manifest = (f'<?xml version="1.0" encoding="UTF-8"?>\n<fmiReferences '
                f'xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest" '
                f'fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-ref" '
                f'fmi-ls:fmi-ls-version="1.0.0-alpha.1">\n  <Related type="text/csv" '
                f'source="{model}_out.csv" role="result" description="Output of the default '
                f'experiment"/>\n</fmiReferences>\n')
    with zipfile.ZipFile(fmu, "a") as archive:
        archive.writestr(MANIFEST, manifest)
        archive.writestr(f"{LS_REF}/{model}_out.csv", f"time,x\n{rows}\n")


def test_an_fmu_is_checked_against_the_reference_it_carries(tmp_path):
    t, x = _recurrence(40.0)
    original, changed = _spring(tmp_path, 40.0, "v1"), _spring(tmp_path, 40.4, "v2")
    for fmu in (original, changed):
        _carry(fmu, "Spring", t, x)
    good = _sewfmu("--fmu", original, cwd=tmp_path)
    assert good.returncode == 0 and "(Spring_out.csv, fmi-ls-ref)" in good.stdout, good.stderr
    bad = _sewfmu("--fmu", changed, cwd=tmp_path)
    assert bad.returncode == 1 and "Spring: x leaves the tolerance" in bad.stdout
    bare = _spring(tmp_path, 40.0, "v3")
    none = _sewfmu("--fmu", bare, cwd=tmp_path)
    assert none.returncode == 1 and "carries no reference (fmi-ls-ref)" in none.stderr
    assert len(none.stderr.strip().splitlines()) == 1


def test_sewfmus_fmus_carry_their_reference_and_a_changed_model_is_caught(fmus, tmp_path):
    for name, path in fmus.items():
        with zipfile.ZipFile(path) as archive:
            assert {MANIFEST, f"{LS_REF}/{name}_out.csv"} <= set(archive.namelist()), name
        outcomes = reference_check.check(path)
        assert [o.deviations for o in outcomes] == [[], []], name     # shipped and carried
    # gravity switched off in a copy of the model code: the FMU's own (carried) reference,
    # made from that code, agrees with it; sewfmu's shipped reference catches the change
    source = tmp_path / "components"
    shutil.copytree(MODEL_CODE_DIR, source, ignore=shutil.ignore_patterns("__pycache__"))
    code = (source / "punch_contact.py").read_text()
    (source / "punch_contact.py").write_text(code.replace("GRAVITY = 9.81", "GRAVITY = 0.0"))
    fmi = 3 if "fmi3" in next(iter(fmus.values())).parts else 2
    changed = build_fmu("PunchContact", tmp_path / "fmus", source=source, fmi=fmi)
    shipped, carried = reference_check.check(changed)
    assert carried.deviations == []
    assert shipped.deviations and shipped.deviations[0].variable == "y"


@pytest.mark.skipif(not os.environ.get("SEWFMU_REFERENCE_FMUS"),
                    reason="SEWFMU_REFERENCE_FMUS names no folder of built Modelica "
                           "Reference-FMUs (docs/regression.md says how to build them)")
def test_the_modelica_reference_fmus_pass_against_what_they_carry():
    folder = Path(os.environ["SEWFMU_REFERENCE_FMUS"])
    checked = []
    for fmu in sorted(folder.glob("*.fmu")):
        try:
            reference_check.describe(fmu)
        except ScenarioError:                       # Clocks: no co-simulation interface
            continue
        try:
            if reference_check.fmu_reference.read_carried(fmu) is None:
                continue
        except ScenarioError as err:
            # StateSpace's output is an array (cells of several numbers): nothing sewfmu can
            # compare, refused rather than passed (docs/regression.md)
            assert "no column of numbers beside time" in str(err), str(err)
            continue
        outcomes = reference_check.check(fmu, rtol=1e-6)
        assert all(not o.deviations for o in outcomes), [str(d) for o in outcomes
                                                         for d in o.deviations]
        checked.append(fmu.name)
    assert checked
