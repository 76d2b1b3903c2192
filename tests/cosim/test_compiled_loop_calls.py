"""jacobi_loop.c makes the Python loop's FMI calls, in its order, with its arguments: fake FMUs
(tests/fake_fmu.py) behind C function pointers (ctypes callbacks into the same Python models)
run by the compiled loop and by the Python loop give the same trace of calls, the same records,
and the same one line where a step fails (a Discard, an output that is NaN, a Boolean getter's
Error), with inputs converted by a * x + b. No FMU is built: fast."""
import ctypes
import math
import shutil
import subprocess

import numpy as np
import pytest

from sewfmu.scenarios.cosim import stepper, watchdog
from sewfmu.scenarios.cosim.fmi_calls import CosimError, Status
from sewfmu.scenarios.cosim.guardian import BEAT, WHERE, T
from sewfmu.scenarios.cosim.master import Master
from tests.fake_fmu import Failing, FakeInstance, Integrator, Switch, fake_scenario

STEP = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                        ctypes.c_int)
VALUES = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint),
                          ctypes.c_size_t, ctypes.c_void_p)


class Blowing(Integrator):
    """An integrator whose output x is NaN from `at` on (the sum check's case)."""

    def __init__(self, at: float, **kwargs):
        super().__init__(**kwargs)
        self.at = at

    def step(self, t, h):
        super().step(t, h)
        if t >= self.at:
            self.x = math.nan
        return Status.OK


class Grumbling(Switch):
    """A switch whose steps from `warn` on return Warning (the run goes on) and whose Boolean
    getter returns Error from `fail` on."""

    def __init__(self, at, warn=math.inf, fail=math.inf):
        super().__init__(at)
        self.warn, self.fail, self.t = warn, fail, 0.0

    def step(self, t, h):
        super().step(t, h)
        self.t = t
        return Status.WARNING if t >= self.warn else Status.OK


class CalledInstance(FakeInstance):
    """A fake instance as the compiled loop sees an FMU: C functions (ctypes callbacks) with
    FMI 2.0's signatures, calling the fake's own Python calls, which note each call in `trace`;
    c's inputs taken as 2·x + 0.5 of its sources' outputs (a unit conversion's arithmetic)."""

    component = None
    trace: list = []

    def prepare(self, outputs=None):
        if self.name == "c":
            self.in_scales = [(2.0, 0.5)] * len(self.inputs)
        super().prepare(outputs)

    def bind(self):
        def step(component, t, h, no_set_prior):
            self.trace.append((self.name, "doStep", t, h))
            self.no_set_prior.add(bool(no_set_prior))
            return self.model.step(t, h)

        def given(python, buffer):
            def call(component, vr, n, values):
                # the loop passes this instance's own buffers
                assert values == ctypes.addressof(buffer) and n == len(buffer)
                return python()
            return VALUES(call)

        self.functions = {"do_step": STEP(step),
                          "set_real": given(self._set_reals, self.in_buf),
                          "get_real": given(self._get_reals, self.out_buf),
                          "get_boolean": given(self._get_booleans, self.bool_buf)}

    def _function(self, call):
        return self.functions[call]

    def _do_step(self, t, h):
        self.trace.append((self.name, "doStep", t, h))
        return super()._do_step(t, h)

    def _set_reals(self):
        self.trace.append((self.name, "set", tuple(self.in_buf)))
        return super()._set_reals()

    def _get_reals(self):
        self.trace.append((self.name, "get"))
        return super()._get_reals()

    def _get_booleans(self):
        self.trace.append((self.name, "get Boolean"))
        status = super()._get_booleans()
        model = self.model
        return Status.ERROR if getattr(model, "t", 0.0) >= getattr(model, "fail", math.inf) \
            else status


@pytest.fixture(scope="module", autouse=True)
def _watched():
    """The board of a watched run, as every run after the process's first writes it."""
    with watchdog.watching(Master(fake_scenario({}, [], stop_time=1.0, step=0.1), {})):
        pass


@pytest.fixture(autouse=True)
def _compiled(monkeypatch):
    if stepper.library() is None:
        pytest.skip("no C compiler for the compiled loop")
    # fake instances are no native sewfmu FMUs: let them in, as far as `enabled` says
    monkeypatch.setattr(stepper, "_refused",
                        lambda master: None if stepper.enabled else "the Python loop")


def _run(monkeypatch, compiled: bool, models) -> tuple[Master, object, list]:
    """(master, its result or its error's text, the trace of calls) of a run over `models`."""
    monkeypatch.setattr(stepper, "enabled", compiled)
    monkeypatch.setattr(stepper, "CHUNK", 7)            # chunks end mid-record-interval too
    trace = []
    monkeypatch.setattr(CalledInstance, "trace", trace)
    made = models()
    scenario = fake_scenario(made, ["a.x -> b.u", "a.x_dot -> b.u_dot", "b.y -> c.u",
                                    "a.x -> c.u_dot"], stop_time=1.0, step=0.01,
                             parameters={"a": {"u": 1.0, "u_dot": 0.5}}, record_every=3)

    def make(declaration, log):
        return CalledInstance(declaration.name, made[declaration.name], log)

    master = Master(scenario, {}, make_instance=make)
    board = watchdog.board()
    beat = board.q[BEAT]
    try:
        outcome = master.run()
    except CosimError as err:
        outcome = str(err)
    assert (master.k > 0) and any(t[1] == "doStep" for t in trace)
    # what the guardian reads: the beats, the time and the call last written
    paper = watchdog.board()
    trace.append(("board", paper.q[BEAT] - beat if paper is board else None, paper.d[T],
                  paper.q[WHERE]))
    return master, outcome, trace


def _same(monkeypatch, models) -> str | None:
    (c, said, calls), (p, expected, python_calls) = (_run(monkeypatch, on, models)
                                                    for on in (True, False))
    assert calls == python_calls
    assert [i.no_set_prior for i in c.instances] == [i.no_set_prior for i in p.instances] \
        == [{True}] * 3
    assert c.k == p.k and c.t == p.t and c._failed_at == p._failed_at
    (tc, cc), (tp, cp) = c.recorder.arrays(), p.recorder.arrays()
    assert np.array_equal(tc, tp) and list(cc) == list(cp)
    for column in cc:
        assert np.array_equal(cc[column], cp[column], equal_nan=True), column
    if isinstance(expected, str):
        assert said == expected
        return expected
    assert not isinstance(said, str), said
    assert said.log == expected.log
    return None


def test_a_run_is_the_python_loops_call_for_call(monkeypatch):
    said = _same(monkeypatch, lambda: {"a": Integrator(gain=1.5, x0=0.1),
                                       "b": Grumbling(at=0.9, warn=0.5),
                                       "c": Integrator(gain=-1.0)})
    assert said is None


@pytest.mark.parametrize("models, words", [
    (lambda: {"a": Failing(at=0.42, gain=1.0), "b": Switch(at=0.5), "c": Integrator()},
     "a failed during step from t = 0.42 to 0.43 s: the fabric tore"),
    (lambda: {"a": Integrator(), "b": Switch(at=0.5), "c": Blowing(at=0.3)},
     "c failed during step from t = 0.3 to 0.31 s: output x is nan"),
    (lambda: {"a": Integrator(), "b": Grumbling(at=0.5, fail=0.6), "c": Integrator()},
     "b failed during step from t = 0.6 to 0.61 s"),
], ids=["doStep Discard", "NaN output", "Boolean getter's Error"])
def test_a_failed_step_is_the_python_loops_line(monkeypatch, models, words):
    said = _same(monkeypatch, models)
    assert said is not None and said.startswith(words), said


@pytest.mark.parametrize("compiler", ["gcc", "x86_64-w64-mingw32-gcc"])
def test_the_loop_compiles_warning_free(compiler, tmp_path):
    cc = shutil.which(compiler)
    if cc is None:
        pytest.skip(f"no {compiler}")
    done = subprocess.run([cc, "-std=c99", "-Wall", "-Wextra", "-pedantic", "-O2",
                           "-ffp-contract=off", "-c", str(stepper.SOURCE), "-o",
                           str(tmp_path / "loop.o")], capture_output=True, text=True)
    assert done.returncode == 0 and not done.stderr.strip(), done.stderr
