"""native/models/parameters.c, the twin of components/parameters.py's check_value, held against
Python itself through ctypes: its repr of a float is Python's repr over random doubles (random
bits, subnormals, the doubles at and next to every power of two, where the gap below is half the
gap above, short decimals, the edges of fixed notation), and its check gives ParameterError's
words, or accepts, for every allowed kind and unit, the "meant in" hint included. One slow test
holds the Windows build (mingw-w64, under Wine) to the same repr: mingw's own strtod misreads
some decimals next to powers of two, which parameters.c therefore does not use."""
from __future__ import annotations

import ctypes
import math
import random
import shutil
import struct
import subprocess

import pytest

from sewfmu.components.parameters import (
    ANY,
    CHOICE,
    FRACTION,
    MACHINE_SCALE,
    NONNEGATIVE,
    POSITIVE,
    ParameterError,
    ParameterInfo,
    check_value,
)
from tests.native.model_twin import NATIVE, WHY, library
from tests.native.no_python_hosts import CFLAGS, MINGW, Wine, find_wine, windows_path

# parameters.h's SewAllowed, in its order
ALLOWED = (POSITIVE, NONNEGATIVE, FRACTION, ANY, CHOICE)


class _ParamInfo(ctypes.Structure):
    """parameters.h's SewParamInfo."""
    _fields_ = [("name", ctypes.c_char_p), ("unit", ctypes.c_char_p), ("allowed", ctypes.c_int),
                ("n_choices", ctypes.c_int), ("choices", ctypes.c_int * 4)]


@pytest.fixture(scope="module")
def parameters_c():
    lib = library("parameters")
    lib.sew_py_repr.argtypes = ctypes.c_double, ctypes.c_char_p, ctypes.c_size_t
    lib.sew_py_repr.restype = None
    lib.sew_check_value.argtypes = (ctypes.POINTER(_ParamInfo), ctypes.c_double,
                                    ctypes.c_char_p)
    lib.sew_check_value.restype = ctypes.c_int
    return lib


def c_repr(lib, x: float) -> str:
    out = ctypes.create_string_buffer(64)
    lib.sew_py_repr(x, out, len(out))
    return out.value.decode()


def _double(bits: int) -> float:
    return struct.unpack("<d", struct.pack("<Q", bits))[0]


def repr_cases(rng: random.Random) -> list[float]:
    """Doubles where a shortest repr is easy to get wrong, and random ones."""
    xs = [0.0, 5e-324, 2.2250738585072014e-308, 1.7976931348623157e308, 0.1, 0.3, 1 / 3,
          1e16, 1e17, 9999999999999998.0, 1e-4, 1e-5, 9.999999999999999e-05, 123456789.0,
          12345678901234567.0, 2.0 ** 53, 2.0 ** 53 + 2, 1e22, 1e23, 5e-324 * 3, math.pi]
    for k in range(-1074, 1024):                     # every power of two and its neighbours
        p = 2.0 ** k
        xs += [p, math.nextafter(p, 0.0), math.nextafter(p, math.inf)]
    xs += [_double(rng.getrandbits(63)) for _ in range(6000)]                # random bits
    xs += [_double(rng.getrandbits(52)) for _ in range(3000)]                # subnormals
    xs += [float(f"{rng.getrandbits(rng.randint(1, 56))}e{rng.randint(-330, 310)}")
           for _ in range(3000)]                                             # short decimals
    xs += [rng.uniform(-1, 1) * 10.0 ** rng.randint(-6, 18) for _ in range(3000)]
    finite = [x for x in xs if math.isfinite(x)]
    return finite + [-x for x in finite]


def test_the_c_repr_is_pythons_repr(parameters_c):
    rng = random.Random(46)
    wrong = [(x, c_repr(parameters_c, x)) for x in repr_cases(rng)
             if c_repr(parameters_c, x) != repr(x)]
    for x in (math.nan, math.inf, -math.inf, -0.0):
        if c_repr(parameters_c, x) != repr(x):
            wrong.append((x, c_repr(parameters_c, x)))
    assert not wrong, f"{len(wrong)} differ, e.g. " + ", ".join(
        f"{x!r} as {c!r}" for x, c in wrong[:5])


def test_the_c_repr_of_a_power_of_two_whose_nearest_digits_do_not_read_back(parameters_c):
    """-2**-24: printf's nearest 16 digits (...062) read back as the double below it, whose gap
    is half the gap above; Python gives the neighbour above."""
    x = -2.0 ** -24
    assert float(f"{x:.15e}") != x
    assert c_repr(parameters_c, x) == repr(x) == "-5.960464477539063e-08"


def _units() -> list[str]:
    return [*MACHINE_SCALE, "1", "m/s"]             # "1", "m/s": no scale, no bound


def check_cases(rng: random.Random):
    """(ParameterInfo, value) over every allowed kind and unit: values inside, at and beyond
    the bounds, some of them too large in SI but fitting in the unit of the hint."""
    for allowed in ALLOWED:
        for unit in _units():
            choices = (0, 1) if allowed == CHOICE else ()
            info = ParameterInfo(f"p_{allowed}", 1.0, unit, "", allowed, choices)
            scale = MACHINE_SCALE.get(unit, 1.0)
            values = [0.0, -0.0, 1.0, -1.0, 0.5, 2.0, scale, -scale, math.nextafter(scale, 2e9),
                      math.nan, math.inf, -math.inf, 1e300, -1e300]
            values += [rng.uniform(-1, 1) * scale * 10.0 ** rng.uniform(-3, 4)
                       for _ in range(40)]
            for value in values:
                yield info, value


def test_the_c_check_is_pythons_check_value(parameters_c):
    rng = random.Random(46)
    for info, value in check_cases(rng):
        c_info = _ParamInfo(info.name.encode(), info.unit.encode(), ALLOWED.index(info.allowed),
                            len(info.choices), (ctypes.c_int * 4)(*info.choices))
        why = ctypes.create_string_buffer(WHY)
        refused = parameters_c.sew_check_value(ctypes.byref(c_info), value, why) != 0
        # SewSlave.model makes a choice's value int (of a finite value: int(nan) raises)
        py_value = int(value) if info.allowed == CHOICE and math.isfinite(value) else value
        try:
            check_value(info, py_value)
        except ParameterError as err:
            assert refused and why.value.decode() == str(err), \
                f"{info.allowed} {info.unit} {value!r}: C {why.value.decode()!r}"
        else:
            assert not refused, \
                f"{info.allowed} {info.unit} {value!r}: C refuses, {why.value.decode()!r}"


# a program that writes sew_py_repr of each double (as hex bits, one a line) of a file
REPR_MAIN = r"""
#include <stdio.h>
#include <string.h>
#include "parameters.h"
int main(int argc, char **argv)
{
    unsigned long long bits;
    double x;
    char out[64];
    FILE *in = argc > 1 ? fopen(argv[1], "r") : NULL;
    if (in == NULL) return 2;
    while (fscanf(in, "%llx", &bits) == 1) {
        memcpy(&x, &bits, sizeof x);
        sew_py_repr(x, out, sizeof out);
        printf("%s\n", out);
    }
    fclose(in);
    return 0;
}
"""


@pytest.mark.slow
def test_the_windows_build_gives_pythons_repr(tmp_path):
    loader = find_wine()
    if not shutil.which(MINGW) or not loader:
        pytest.skip(f"needs {MINGW} and Wine (Debian: apt-get install mingw-w64 wine64)")
    (tmp_path / "main.c").write_text(REPR_MAIN)
    exe = tmp_path / "repr.exe"
    subprocess.run([MINGW, *CFLAGS, "-static", f"-I{NATIVE / 'models'}",
                    f"-I{NATIVE / 'runtime'}", str(tmp_path / "main.c"),
                    str(NATIVE / "models" / "parameters.c"), "-o", str(exe)], check=True)
    xs = repr_cases(random.Random(46)) + [math.nan, math.inf, -math.inf, -0.0]
    (tmp_path / "in.txt").write_text("".join(
        f"{struct.unpack('<Q', struct.pack('<d', x))[0]:x}\n" for x in xs))
    wine = Wine(loader, tmp_path / "wine")
    try:
        done = wine.run(exe, windows_path(tmp_path / "in.txt"))
    finally:
        wine.close()
    assert done.returncode == 0, done.stderr
    got = done.stdout.split()
    assert len(got) == len(xs)
    wrong = [(x, c) for x, c in zip(xs, got) if c != repr(x)]
    assert not wrong, f"{len(wrong)} differ, e.g. " + ", ".join(
        f"{x!r} as {c!r}" for x, c in wrong[:5])
