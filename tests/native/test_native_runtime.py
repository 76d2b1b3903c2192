"""The runtime's own paths on a toy model (toy/toy.c), through its FMI 2.0 glue loaded with
ctypes: a step whose state would not be finite and a step the model refuses are discarded
with the instance as it was (state, time, extrapolation), a two-input Taylor chain whose rate
acts as zero unless set with its value, a model that cannot be built."""
from __future__ import annotations

import ctypes
import shutil
import subprocess
from pathlib import Path

import pytest
from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

from sewfmu.scenarios.fmu_build.native import RUNTIME

TOY = Path(__file__).resolve().parent / "toy" / "toy.c"
OK, DISCARD, ERROR = 0, 2, 3
K, U, U_DOT, X, U_NOW = range(5)


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    if not shutil.which("gcc"):
        pytest.skip("no gcc")
    out = tmp_path_factory.mktemp("toy") / "toy.so"
    subprocess.run(["gcc", "-std=c99", "-O2", "-ffp-contract=off", "-Wall", "-Wextra", "-Werror",
                    "-shared", "-fPIC", f"-I{RUNTIME}", f"-I{RUNTIME / 'fmi2'}", str(TOY),
                    *(str(RUNTIME / f) for f in ("sew_slave.c", "sew_state.c", "fmi2_glue.c")),
                    "-o", str(out), "-lm"], check=True)
    return ctypes.CDLL(str(out))


class Toy:
    def __init__(self, lib):
        self.lib, self.lines = lib, []
        self.cb = fmi2CallbackFunctions()
        self.cb.logger = fmi2CallbackLoggerTYPE(
            lambda env, name, status, category, message: self.lines.append(message.decode()))
        lib.fmi2Instantiate.restype = ctypes.c_void_p
        lib.fmi2Instantiate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                                        ctypes.c_char_p, ctypes.c_void_p, ctypes.c_int,
                                        ctypes.c_int]
        self.c = lib.fmi2Instantiate(b"toy", 1, b"toy-token", b"", ctypes.byref(self.cb), 0, 0)
        assert self.c
        for f in ("fmi2SetReal", "fmi2GetReal"):
            getattr(lib, f).argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint),
                                        ctypes.c_size_t, ctypes.POINTER(ctypes.c_double)]
        lib.fmi2DoStep.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                                   ctypes.c_int]
        for f in ("fmi2EnterInitializationMode", "fmi2ExitInitializationMode",
                  "fmi2FreeInstance"):
            getattr(lib, f).argtypes = [ctypes.c_void_p]
        lib.fmi2SetupExperiment.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_double,
                                            ctypes.c_double, ctypes.c_int, ctypes.c_double]

    def set(self, **values) -> int:
        vrs = [globals()[n.upper()] for n in values]
        return self.lib.fmi2SetReal(self.c, (ctypes.c_uint * len(vrs))(*vrs), len(vrs),
                                    (ctypes.c_double * len(vrs))(*values.values()))

    def get(self, *vrs) -> list[float]:
        out = (ctypes.c_double * len(vrs))()
        assert self.lib.fmi2GetReal(self.c, (ctypes.c_uint * len(vrs))(*vrs), len(vrs),
                                    out) == OK
        return list(out)

    def start(self) -> int:
        self.lib.fmi2SetupExperiment(self.c, 0, 0.0, 0.0, 0, 0.0)
        self.lib.fmi2EnterInitializationMode(self.c)
        return self.lib.fmi2ExitInitializationMode(self.c)

    def step(self, t, h) -> int:
        return self.lib.fmi2DoStep(self.c, t, h, 1)


@pytest.fixture
def toy(library):
    inst = Toy(library)
    yield inst
    library.fmi2FreeInstance(inst.c)


def test_a_step_that_leaves_the_state_not_finite_is_discarded_as_if_not_taken(toy):
    toy.set(u=1.0, u_dot=2.0)
    assert toy.start() == OK
    assert toy.step(0.0, 0.5) == OK
    before = toy.get(X, U_NOW)
    toy.set(u=6.0)                                  # x would become infinite
    assert toy.step(0.5, 0.5) == DISCARD
    assert "discarded: the internal state's element 0 would be inf" in toy.lines[-1]
    assert toy.get(X) == before[:1]
    toy.set(u=1.0)
    assert toy.step(0.5, 0.5) == OK                 # the time did not move
    assert toy.get(X) == [before[0] + 1.0 * 1.0 * 0.5]


def test_a_step_the_model_refuses_is_discarded_and_its_scribbles_undone(toy):
    assert toy.start() == OK
    toy.set(u=4.0, u_dot=100.0)                     # u extrapolated past 10 inside the step?
    assert toy.step(0.0, 0.5) == OK                 # no: the model sees u at the step's start
    x = toy.get(X)
    toy.set(u=11.0)
    assert toy.step(0.5, 0.5) == DISCARD
    assert toy.lines[-1].endswith("discarded: u = 11 is too large for a step")
    assert toy.get(X) == x


def test_a_rate_counts_only_while_it_is_set_with_its_value(toy):
    assert toy.start() == OK
    toy.set(u=1.0, u_dot=2.0)
    assert toy.step(0.0, 0.25) == OK
    assert toy.get(U_NOW) == [0.0 + 1.0 * 1.0 + 2.0 * (1.0 * (0.25 / 1))]
    toy.set(u=3.0)                                  # the value alone: its rate acts as zero
    assert toy.step(0.25, 0.25) == OK
    assert toy.get(U_NOW) == [3.0]
    toy.set(u_dot=-4.0)                              # the rate alone counts again
    assert toy.step(0.5, 0.25) == OK
    # (extrapolated from the instant an input was last set: elapsed 0.25 s)
    assert toy.get(U_NOW) == [0.0 + 3.0 * 1.0 + -4.0 * (1.0 * (0.25 / 1))]


def test_a_model_that_cannot_be_built_gives_nan_outputs_and_refuses_every_step(toy):
    assert toy.set(k=3.0) == OK
    out = (ctypes.c_double * 1)()
    assert toy.lib.fmi2GetReal(toy.c, (ctypes.c_uint * 1)(X), 1, out) == ERROR
    assert out[0] != out[0]                         # NaN
    assert "outputs unavailable: parameter k: 3 is unlucky" in toy.lines[-1]
    assert toy.start() == ERROR
    assert toy.lines[-1].endswith("parameter k: 3 is unlucky; every doStep of this instance "
                                  "will be refused")
    assert toy.step(0.0, 0.1) == ERROR
