"""Every public function of sewfmu (sewfmu.__all__: sewfmu/api.py, the page's
sewfmu.app) called with hostile arguments, one at a time in each parameter: another type, None,
an int, NaN, bytes, a list, a dict, an empty or NUL-holding text, a path into /proc, a /proc file,
a file that does not exist, a folder where a file belongs, a name too long for the file system.
Only a sewfmu.Error of one line may come out (or the call may take the value), never Python's
TypeError, FileNotFoundError, OSError or ValueError. sewfmu.build(dest='/proc/x') gave
FileNotFoundError and sewfmu.show(123) TypeError.

The long-running parts are replaced where an argument, once accepted, would start them (the
page's server, a sweep's pool, a study's optimizer, the FMU builder): what is checked is the
door. The slow test runs the studies and the sweep for real with the same arguments."""
import importlib
import inspect
import math

import pytest

import sewfmu

HOSTILE = {
    "object": object(), "None": None, "int": 123, "nan": math.nan, "bool": True,
    "bytes": b"punch_drive", "list": ["x"], "dict": {"a": 1}, "empty": "", "nul": "a\x00b",
    "proc": "/proc/x/y", "proc file": "/proc/self/status", "missing": "/nonexistent/dir/x.toml",
    "missing fmu": "/nonexistent/x.fmu", "too long": "x" * 5000,
}
FUNCTIONS = ["run", "check", "load", "compare", "show", "parameters", "scenarios", "read_value",
             "build", "sweep", "optimize", "fit", "sensitivity", "app"]


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    """Each function's arguments that work (a 1 ms punch drive, whose key figures are then
    refused: a run too short, in one line), in a folder of the test's own."""
    folder = tmp_path_factory.mktemp("api")
    short = folder / "short.toml"
    short.write_text(sewfmu.show("punch_drive").replace("revolutions = 10", "stop_time = 0.001")
                     .replace('shaft = "shaft"\n', 'accuracy = "off"\n'))
    trace = folder / "trace.csv"
    trace.write_text("time,punch.F2\n0,0\n0.0005,1\n0.001,2\n")
    study = dict(scenario=str(short), vary={"punch.F10": "15..40 N"})
    return folder, {
        "run": dict(scenario=str(short)), "check": dict(scenario=str(short)),
        "load": dict(scenario=str(short)), "compare": dict(scenario=str(short)),
        "show": dict(scenario="punch_drive"), "parameters": dict(name="punch_drive"),
        "scenarios": {}, "read_value": dict(text="1"),
        "build": dict(fmi=2, dest=str(folder / "fmus"), names=["MainShaft"]),
        "sweep": dict(scenario=str(short), grid={"shaft.omega0": [100.0]}, workers=1),
        "optimize": dict(study, minimize="F2_peak", max_evaluations=2),
        "fit": dict(scenario=str(short), data=str(trace), free={"punch.F10": "15..40 N"},
                    max_evaluations=2),
        "sensitivity": dict(study, figures=["F2_peak"], method="morris", samples=2, workers=1),
        "app": {},
    }


def _function(name):
    return importlib.import_module("sewfmu.app").app if name == "app" else getattr(sewfmu, name)


def _cases():
    for name in FUNCTIONS:
        for parameter in inspect.signature(_function(name)).parameters:
            for hostile in HOSTILE:
                yield pytest.param(name, parameter, hostile, id=f"{name}-{parameter}-{hostile}")


def _stand_ins(monkeypatch, base_folder):
    """Where an accepted argument would start something long: a stand-in that returns."""
    def module(name):
        return importlib.import_module(name)

    monkeypatch.setattr(module("sewfmu.app.serve"), "serve", lambda *a, **k: None)
    monkeypatch.setattr(module("sewfmu.scenarios.runs.sweep"), "run_sweep",
                        lambda *a, **k: [{"status": "ok", "error": ""}])
    monkeypatch.setattr(module("sewfmu.scenarios.design.optimize"), "optimize",
                        lambda *a, **k: None)
    monkeypatch.setattr(module("sewfmu.scenarios.design.fit"), "fit", lambda *a, **k: None)
    monkeypatch.setattr(module("sewfmu.scenarios.design.sensitivity"), "sensitivity",
                        lambda *a, **k: None)
    monkeypatch.setattr(module("sewfmu.scenarios.fmu_build.build"), "build_fmu",
                        lambda name, folder, fmi=2: folder / f"{name}.fmu")


def _call_and_judge(function, kwargs):
    try:
        function(**kwargs)
    except sewfmu.Error as err:
        message = str(err)
        assert message.strip() and "\n" not in message.strip(), repr(message)
        assert "bug in sewfmu" not in message, message
    except BaseException as err:     # the finding: what the door let through
        pytest.fail(f"{type(err).__name__} came out: {' '.join(str(err).split())[:300]}")


# the page's function is the page engineer's (sewfmu/app/): what it still lets through
PAGE_OPEN = {("app", "scenarios", h) for h in ("object", "None", "int", "nan", "bool")}


@pytest.mark.parametrize("name, parameter, hostile", list(_cases()))
def test_a_hostile_argument_gives_one_sewfmu_error_line_or_is_taken(
        base, monkeypatch, request, name, parameter, hostile):
    if (name, parameter, hostile) in PAGE_OPEN:
        request.applymarker(pytest.mark.xfail(reason="sewfmu.app(scenarios=) iterates its "
                                                     "argument unchecked (sewfmu/app/)"))
    folder, calls = base
    _stand_ins(monkeypatch, folder)
    monkeypatch.chdir(folder)        # a relative path taken is the test's folder
    kwargs = dict(calls[name])
    kwargs[parameter] = HOSTILE[hostile]
    _call_and_judge(_function(name), kwargs)


def test_the_brief_s_two_calls():
    with pytest.raises(sewfmu.OutputError, match=r"dest: '/proc/x'.*|build: '/proc/x'"):
        sewfmu.build(dest="/proc/x", names=["MainShaft"])
    with pytest.raises(sewfmu.ScenarioError, match="show: expected a catalogue name.*got int"):
        sewfmu.show(123)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["sweep", "optimize", "fit", "sensitivity"])
@pytest.mark.parametrize("hostile", ["object", "int", "nan", "proc", "too long", "missing"])
def test_the_studies_and_the_sweep_run_for_real_with_hostile_arguments(base, monkeypatch, name,
                                                                       hostile):
    folder, calls = base
    monkeypatch.chdir(folder)
    for parameter in inspect.signature(_function(name)).parameters:
        kwargs = dict(calls[name])
        kwargs[parameter] = HOSTILE[hostile]
        _call_and_judge(_function(name), kwargs)


def test_a_run_s_methods_refuse_hostile_arguments_in_one_line():
    """Run.mechanism(10**9) drew a billion frames (the process ran out of memory), revolution(1.5)
    and revolution(None) were TypeErrors."""
    run = sewfmu.run("punch_drive", set={"experiment.revolutions": 1})
    for method, parameter in (("revolution", "k"), ("mechanism", "frames")):
        for hostile in (*HOSTILE.values(), 1.5, -1, 10 ** 9, 10 ** 100):
            _call_and_judge(getattr(run, method), {parameter: hostile})
    assert len(run.mechanism(frames=4)["crank_deg"]) == 4


def _raising_generator():
    yield 100.0
    raise ValueError("the caller's generator fails")


class _HugeLength:
    def __len__(self):
        return 10 ** 30

    def __iter__(self):
        return iter([100.0])


class _LengthRaises:
    def __len__(self):
        raise RuntimeError("len fails")


class _IterRaises:
    def __iter__(self):
        raise RuntimeError("iter fails")


class _KeyStrRaises:
    def __str__(self):
        raise RuntimeError("str fails")

    def __hash__(self):
        return 1


class _FloatReprRaises(float):
    def __repr__(self):
        raise RuntimeError("repr fails")

    def __format__(self, spec):
        raise RuntimeError("format fails")


class _TextSplitRaises(str):
    def split(self, *args):
        raise RuntimeError("split fails")

    def strip(self, *args):
        raise RuntimeError("strip fails")

    def __repr__(self):
        raise RuntimeError("repr fails")


@pytest.mark.parametrize("grid, says", [
    ({"shaft.omega0": _raising_generator()}, "grid: reading it raised ValueError: the caller's"),
    ({"shaft.omega0": _HugeLength()}, "grid: reading it raised OverflowError"),
    ({"shaft.omega0": _LengthRaises()}, "grid: reading it raised RuntimeError: len fails"),
    ({"shaft.omega0": _IterRaises()}, "grid: reading it raised RuntimeError: iter fails"),
    ({_KeyStrRaises(): [100.0]}, "grid: reading it raised RuntimeError: str fails"),
    # read as the plain values they hold: the one point out of range is refused by its number
    ({"shaft.omega0": [_FloatReprRaises(100.0), _FloatReprRaises(5000.0)]}, "= 5000 rad/s"),
    ({"shaft.omega0": _TextSplitRaises("100, 5000 rad/s")}, "= 5000 rad/s"),
])
def test_a_hostile_object_in_grid_is_one_line_naming_the_argument(grid, says):
    """From the attack: each of these leaked its own exception out of sewfmu.sweep."""
    with pytest.raises(sewfmu.ScenarioError) as bad:
        sewfmu.sweep("punch_drive", grid=grid, max_runs=4)
    assert says in str(bad.value) and "\n" not in str(bad.value), str(bad.value)


@pytest.mark.parametrize("given, says", [
    ({_KeyStrRaises(): 1.0}, "set: reading it raised RuntimeError: str fails"),
    ({"shaft.omega0": object()}, "a value is a number, true or false, or a text"),
    ({"shaft.omega0": [100.0]}, "a value is a number, true or false, or a text"),
])
def test_a_hostile_object_in_set_is_one_line_naming_the_argument(given, says):
    for call in (sewfmu.load, sewfmu.check, sewfmu.run):
        with pytest.raises(sewfmu.ScenarioError) as bad:
            call("punch_drive", set=given)
        assert says in str(bad.value) and "\n" not in str(bad.value), str(bad.value)


def test_a_subclass_s_own_methods_are_not_asked_for_its_value():
    sc = sewfmu.check("punch_drive", set={"shaft.omega0": _FloatReprRaises(150.0),
                                          "punch.F30": _TextSplitRaises("20 N")})
    assert sc.instances["shaft"].parameters["omega0"] == 150.0
    assert sc.instances["punch"].parameters["F30"] == 20.0
