"""sewfmu: sewing-machine mechanisms as FMI co-simulation FMUs, and scenarios that connect them.

    import sewfmu
    r = sewfmu.run("punch_drive", set={"shaft.omega0": 300.0})
    r.summary["F2_weld_mean"], r.series["time"], r.series["punch.F2"], r.units["punch.F2"]

run, sweep, compare, load, build and show do what the command line's commands of those names
do (docs/api.md). Public: this module and sewfmu.components (the models); sewfmu.scenarios is
internal (docs/architecture.md).
"""
import sewfmu.scenarios  # noqa: F401  the internal package: sewfmu.scenarios() of old (its __init__)
from sewfmu._version import __version__

__all__ = ["__version__", "run", "sweep", "compare", "load", "check", "build", "show", "parameters",
           "catalogue", "read_value",
           "Run", "Sweep", "Scenario", "Instance", "Connection", "Error", "ScenarioError",
           "CosimError", "OutputError",
           "Diverged", "MissingExtra", "optimize", "fit", "sensitivity", "app"]

# every public name, loaded on first use: `import sewfmu` (and so the command line) starts at
# once and answers Ctrl-C from its first moment; name -> the module that defines it
_HOME = {**{name: "sewfmu.api" for name in ("run", "sweep", "compare", "load", "check", "build", "show",
                                            "catalogue",
                                            "parameters", "read_value", "Run", "Sweep", "Scenario",
                                            "ScenarioError", "InaccurateRun")},
         "Error": "sewfmu.errors",
         # to build a scenario in Python (docs/scenarios.md)
         "Instance": "sewfmu.scenarios.format.scenario",
         "Connection": "sewfmu.scenarios.format.scenario",
         "MissingExtra": "sewfmu.extras",
         "OutputError": "sewfmu.scenarios.files.outputs",
         "CosimError": "sewfmu.scenarios.cosim.fmi_calls",
         "Diverged": "sewfmu.scenarios.cosim.divergence",
         # the design studies (docs/design.md)
         **{name: "sewfmu.api" for name in ("optimize", "fit", "sensitivity")},
         "app": "sewfmu.app"}             # the page (docs/app.md)


def __getattr__(name: str):
    if name not in _HOME:
        raise AttributeError(f"module 'sewfmu' has no attribute {name!r}")
    import importlib  # light, but only when a public name is first used

    value = getattr(importlib.import_module(_HOME[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
