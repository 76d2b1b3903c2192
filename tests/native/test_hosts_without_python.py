"""Every native FMU (FMI 2.0 and 3.0) in hosts that hold no Python, in an environment with nothing
of Python in it (PATH=/usr/bin:/bin only):

- the C host of c_host/, built by gcc, runs the DefaultExperiment with the numbers fmpy's
  simulate_fmu gets from the Python FMU (every output, every row, ≤ 1e-9 relative);
- the same host built by mingw-w64 runs the FMU's Windows binary under Wine with the numbers of
  the Linux binary;
- each refusal (an unknown value reference, a value outside its range, NaN or infinity, a write
  to an output, a garbled serialized state) is fmi2Error / fmi3Error in both, and the FMU state
  goes round (get, set, serialize, deserialize) to the bit;
- fmuCheck and fmusim (where given) run each one with 0 errors.

The native FMUs are built once per session (sewfmu.scenarios.fmu_build.native); a model the builder
cannot build yet is skipped with its reason, as are the Windows checks where mingw-w64 or Wine is
missing (.ci/run installs them)."""
import os
import shutil
import subprocess
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from sewfmu.components.registry import FMUS
from tests.native.no_python_hosts import (
    ERROR,
    MINGW,
    NO_PYTHON,
    Wine,
    compile_host,
    differing,
    find_wine,
    read_rows,
    run_linux,
    windows_path,
)

pytestmark = [pytest.mark.slow, pytest.mark.interop]

CASES = [(name, fmi) for fmi in (2, 3) for name in FMUS]
IDS = [f"{name}-fmi{fmi}" for name, fmi in CASES]
# under Wine the refusals and the state are the runtime's, the same for every model: a stateless
# FMU and two with state, each version (Wine's runs cost a second each)
WINE_CASES = [(name, fmi) for fmi in (2, 3) for name in ("MainShaft", "PunchContact",
                                                         "CarriageModal")]
WINE_IDS = [f"{name}-fmi{fmi}" for name, fmi in WINE_CASES]
KIND = {"Real": "r", "Float64": "r", "Integer": "i", "Int32": "i", "Boolean": "b"}
GARBLINGS = ("all", "header", "middle", "last", "truncated")


class NativeFmus:
    """The native FMUs, each built on first use into one folder of the session, and unzipped."""

    def __init__(self, folder, python_dir):
        self.folder = folder
        self.python_dir = python_dir      # fmi -> the session's Python FMUs, which it copies
        self.built: dict[tuple[str, int], object] = {}

    def get(self, name: str, fmi: int):
        """(the .fmu, its unzipped folder, its model description), or a skip with the reason."""
        key = (name, fmi)
        if key not in self.built:
            self.built[key] = self._build(name, fmi)
        if isinstance(self.built[key], str):
            pytest.skip(self.built[key])
        return self.built[key]

    def _build(self, name, fmi):
        try:
            # the builder is written alongside these tests: while it is missing, they skip
            from sewfmu.scenarios.fmu_build.native import build_native_fmu
        except ImportError as err:
            return f"no native FMU builder yet (sewfmu.scenarios.fmu_build.native): {err}"
        try:
            fmu = build_native_fmu(name, dest=self.folder / f"fmi{fmi}", fmi=fmi,
                                   python_dir=self.python_dir(fmi))
        except Exception as err:  # noqa: BLE001 - any failure of the builder: skip, say why
            return f"build_native_fmu({name!r}, fmi={fmi}) fails: {type(err).__name__}: {err}"
        unzipped = self.folder / "unzipped" / f"fmi{fmi}" / name
        with zipfile.ZipFile(fmu) as z:
            z.extractall(unzipped)
        return fmu, unzipped, read_model_description(str(fmu))


@pytest.fixture(scope="session")
def native_fmus(request, tmp_path_factory):
    return NativeFmus(tmp_path_factory.mktemp("native_fmus"),
                      lambda fmi: request.getfixturevalue("fmu_dir" if fmi == 2 else "fmu3_dir"))


@pytest.fixture(scope="session")
def linux_host(tmp_path_factory):
    if not shutil.which("gcc"):
        pytest.skip("no gcc: the C host cannot be built for Linux")
    return compile_host("gcc", tmp_path_factory.mktemp("c_host") / "host")


@pytest.fixture(scope="session")
def windows_host(tmp_path_factory):
    if not shutil.which(MINGW):
        pytest.skip(f"no {MINGW} (Debian: apt-get install mingw-w64): the C host cannot be "
                    "built for Windows")
    return compile_host(MINGW, tmp_path_factory.mktemp("c_host_win") / "host.exe")


@pytest.fixture(scope="session")
def wine(tmp_path_factory):
    loader = find_wine()
    if not loader:
        pytest.skip("no Wine (Debian: apt-get install wine64): the Windows binaries are not run")
    wine = Wine(loader, tmp_path_factory.mktemp("wine"))
    yield wine
    wine.close()


def _outputs(md):
    return [v for v in md.modelVariables if v.causality == "output"]


def _spec(v, value=None) -> str:
    """A variable as the C host takes it: "vr:k" or "vr:k=value"."""
    spec = f"{v.valueReference}:{KIND[v.type]}"
    return spec if value is None else f"{spec}={value!r}"


def _out_option(md) -> list[str]:
    return ["--out", ",".join(_spec(v) for v in _outputs(md))]


@pytest.fixture(scope="session")
def linux_runs(native_fmus, linux_host):
    """(name, fmi) -> the Linux C host's DefaultExperiment: (columns, rows)."""
    runs = {}

    def run(name, fmi):
        if (name, fmi) not in runs:
            _, unzipped, md = native_fmus.get(name, fmi)
            proc = run_linux(linux_host[0], str(unzipped), *_out_option(md))
            assert proc.returncode == 0, proc.stderr[-3000:]
            runs[name, fmi] = read_rows(proc.stdout)
        return runs[name, fmi]
    return run


def test_the_c_host_builds_for_linux_without_a_warning(linux_host):
    assert linux_host[1] == "", linux_host[1]


def test_the_c_host_builds_for_windows_without_a_warning(windows_host):
    assert windows_host[1] == "", windows_host[1]


def test_the_environment_holds_no_python():
    assert set(NO_PYTHON) == {"PATH"} and "python" not in NO_PYTHON["PATH"].lower()
    proc = subprocess.run(["env"], env=NO_PYTHON, capture_output=True, text=True, timeout=60)
    assert "PYTHON" not in proc.stdout and "LD_PRELOAD" not in proc.stdout, proc.stdout


@pytest.mark.parametrize("name,fmi", CASES, ids=IDS)
def test_linux_c_host_gives_the_python_fmus_numbers(request, native_fmus, linux_runs, name, fmi):
    _, _, md = native_fmus.get(name, fmi)
    python_fmu = request.getfixturevalue("fmu_paths" if fmi == 2 else "fmu3_paths")[name]
    python_md = read_model_description(str(python_fmu))
    names = [v.name for v in _outputs(md)]
    assert names == [v.name for v in _outputs(python_md)]
    # at the DefaultExperiment's own step, as the C host runs it (fmpy would widen its output
    # interval to keep to 1000 points)
    step = float(md.defaultExperiment.stepSize)
    want = simulate_fmu(str(python_fmu), output=names, output_interval=step)
    columns, rows = linux_runs(name, fmi)
    assert columns == ["time"] + [str(v.valueReference) for v in _outputs(md)]
    assert rows.shape == (len(want), len(columns)), (rows.shape, len(want))
    assert not differing(rows[:, 0], want["time"], 1e-12).any()
    for i, column in enumerate(names, start=1):
        bad = differing(rows[:, i], want[column].astype(float))
        assert not bad.any(), (f"{column}: {bad.sum()} rows differ, first at t="
                               f"{rows[bad, 0][0]!r}: {rows[bad, i][0]!r} native, "
                               f"{want[column][bad][0]!r} Python")


@pytest.mark.parametrize("name,fmi", CASES, ids=IDS)
def test_the_windows_binary_under_wine_gives_the_linux_numbers(request, native_fmus, linux_runs,
                                                               windows_host, name, fmi):
    _, unzipped, md = native_fmus.get(name, fmi)
    wine = request.getfixturevalue("wine")      # (after the build: a skip starts no Wine)
    proc = wine.run(windows_host[0], windows_path(unzipped), *_out_option(md))
    assert proc.returncode == 0, proc.stderr[-3000:]
    columns, rows = read_rows(proc.stdout)
    linux_columns, linux_rows = linux_runs(name, fmi)
    assert columns == linux_columns and rows.shape == linux_rows.shape
    bad = differing(rows, linux_rows)
    assert not bad.any(), (f"{bad.sum()} values differ, first in column "
                           f"{columns[np.argwhere(bad)[0][1]]}")


def _refusals(md) -> list[tuple[str, str | None, str]]:
    """(probe, its argument, the phase it runs in) for every refusal this FMU must make."""
    variables = [v for v in md.modelVariables if v.type in KIND]
    known = [v.valueReference for v in md.modelVariables]
    cases = [("unknown-vr", f"{max(known) + 1000}:r", "stepping")]
    for causality, phase in (("parameter", "instantiated"), ("input", "stepping")):
        ranged = [v for v in variables if v.causality == causality and v.type != "Boolean"
                  and (v.min is not None or v.max is not None)]
        if ranged:
            v = ranged[0]
            beyond = (float(v.max) + abs(float(v.max)) + 1.0 if v.max is not None
                      else float(v.min) - abs(float(v.min)) - 1.0)
            cases.append(("out-of-range", _spec(v, int(beyond) if KIND[v.type] == "i"
                                                else beyond), phase))
    # NaN and infinity: on an input while stepping, else on a parameter before initialization
    reals = [v for v in variables if KIND[v.type] == "r"]
    target = ([(v, "stepping") for v in reals if v.causality == "input"]
              + [(v, "instantiated") for v in reals if v.causality == "parameter"])
    if target:
        v, phase = target[0]
        cases += [("nan", _spec(v), phase), ("inf", _spec(v), phase)]
    cases.append(("set-output", _spec(_outputs(md)[0]), "stepping"))
    cases += [("garbled-state", how, "stepping") for how in GARBLINGS]
    return cases


def _statuses(run, unzipped, md) -> list[str]:
    """Every refusal's calls whose status is not Error, as lines saying what each got."""
    wrong = []
    for probe, arg, phase in _refusals(md):
        proc = run(unzipped, "--probe", probe, *([arg] if arg else []), "--phase", phase)
        lines = proc.stdout.splitlines()
        if proc.returncode != 0 or not lines:
            wrong.append(f"{probe} {arg}: exit {proc.returncode}: {proc.stderr[-500:]}")
            continue
        for line in lines:
            if int(line.split()[-1]) != ERROR:
                wrong.append(f"{line}  (probe {probe} {arg} in {phase})")
        # the reason goes through the logger callback, at Error
        if "[Error]" not in proc.stderr:
            wrong.append(f"{probe} {arg}: no Error line through the logger: {proc.stderr!r}")
    return wrong


@pytest.mark.parametrize("name,fmi", CASES, ids=IDS)
def test_each_refusal_is_an_error_on_linux(native_fmus, linux_host, name, fmi):
    _, unzipped, md = native_fmus.get(name, fmi)
    wrong = _statuses(lambda folder, *args: run_linux(linux_host[0], str(folder), *args),
                      unzipped, md)
    assert not wrong, "\n".join(wrong)


@pytest.mark.parametrize("name,fmi", WINE_CASES, ids=WINE_IDS)
def test_each_refusal_is_an_error_under_wine(request, native_fmus, windows_host, name, fmi):
    _, unzipped, md = native_fmus.get(name, fmi)
    wine = request.getfixturevalue("wine")
    wrong = _statuses(lambda folder, *args: wine.run(windows_host[0], windows_path(folder),
                                                     *args), unzipped, md)
    assert not wrong, "\n".join(wrong)


def _assert_round_trip(proc, linux_runs, name, fmi, exact: bool):
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "equal to the bit, twice" in proc.stderr, proc.stderr[-3000:]
    columns, rows = read_rows(proc.stdout)
    linux_columns, linux_rows = linux_runs(name, fmi)
    assert columns == linux_columns and rows.shape == linux_rows.shape
    # the run the state was taken from is the plain run (the same binary: the same bits)
    assert np.array_equal(rows, linux_rows, equal_nan=True) if exact \
        else not differing(rows, linux_rows).any()


@pytest.mark.parametrize("name,fmi", CASES, ids=IDS)
def test_the_state_goes_round_on_linux(native_fmus, linux_host, linux_runs, name, fmi):
    _, unzipped, md = native_fmus.get(name, fmi)
    proc = run_linux(linux_host[0], str(unzipped), *_out_option(md), "--probe", "state-roundtrip")
    _assert_round_trip(proc, linux_runs, name, fmi, exact=True)


@pytest.mark.parametrize("name,fmi", WINE_CASES, ids=WINE_IDS)
def test_the_state_goes_round_under_wine(request, native_fmus, windows_host, linux_runs, name,
                                         fmi):
    _, unzipped, md = native_fmus.get(name, fmi)
    wine = request.getfixturevalue("wine")
    proc = wine.run(windows_host[0], windows_path(unzipped), *_out_option(md), "--probe",
                    "state-roundtrip")
    _assert_round_trip(proc, linux_runs, name, fmi, exact=False)


FMUCHECK = os.environ.get("SEWFMU_FMUCHECK", "")
FMUSIM = os.environ.get("SEWFMU_FMUSIM") or shutil.which("fmusim") or ""


@pytest.mark.skipif(not (FMUCHECK and os.access(FMUCHECK, os.X_OK)),
                    reason="SEWFMU_FMUCHECK does not name an executable fmuCheck (the Modelica "
                           "FMU Compliance Checker; .ci/run sets it)")
@pytest.mark.parametrize("name,fmi", CASES, ids=IDS)
def test_fmucheck_finds_no_error(native_fmus, tmp_path, name, fmi):
    if fmi == 3:
        # (worded without the checker's name: conftest's summary reads that as "not installed")
        pytest.skip("the Compliance Checker (FMI Library 2.4.1) reads FMI 1.0 and 2.0 only")
    fmu, _, _ = native_fmus.get(name, fmi)
    out = tmp_path / f"{name}.csv"
    proc = subprocess.run([FMUCHECK, "-l", "3", "-o", str(out), str(fmu)], env=NO_PYTHON,
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    text = proc.stdout + proc.stderr
    assert proc.returncode == 0 and "0 Error(s)" in text, text[-3000:]
    data = np.genfromtxt(out, delimiter=",", names=True)
    assert len(data) > 10 and all(np.isfinite(data[c]).all() for c in data.dtype.names)


@pytest.mark.skipif(not os.access(FMUSIM, os.X_OK),
                    reason="no fmusim (Reference-FMUs' simulator): set SEWFMU_FMUSIM or put it "
                           "on PATH (docs/fmi.md: how to build it)")
@pytest.mark.parametrize("name,fmi", CASES, ids=IDS)
def test_fmusim_runs_it_with_the_c_hosts_numbers(native_fmus, linux_runs, tmp_path, name, fmi):
    fmu, _, md = native_fmus.get(name, fmi)
    out = tmp_path / f"{name}.csv"
    proc = subprocess.run([FMUSIM, "--interface-type", "cs", "--output-interval",
                           repr(float(md.defaultExperiment.stepSize)), "--output-file", str(out),
                           str(fmu)], env=NO_PYTHON, cwd=tmp_path, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-3000:]
    # fmusim quotes its column names
    data = np.genfromtxt(out, delimiter=",", names=True, deletechars='"')
    got = {column.strip('"'): data[column].astype(float) for column in data.dtype.names}
    _, rows = linux_runs(name, fmi)
    # where the stop time is not a whole number of steps, fmusim ends at the last whole one
    n = len(got["time"])
    assert n in (len(rows), len(rows) - 1)
    assert not differing(got["time"], rows[:n, 0], 1e-12).any()
    for i, v in enumerate(_outputs(md), start=1):
        assert not differing(got[v.name], rows[:n, i]).any(), v.name
