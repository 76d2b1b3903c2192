"""sewfmu: sewing-machine mechanisms as FMI co-simulation FMUs, and scenarios that connect them.

    import sewfmu
    r = sewfmu.run("punch_drive", set={"shaft.omega0": 300.0})
    r.summary["F2_weld_mean"], r.series["time"], r.series["punch.F2"], r.units["punch.F2"]

run, sweep, compare, load, build and show do what the command line's commands of those names
do (docs/api.md). Public: this module and sewfmu.components (the models); sewfmu.scenarios is
internal (docs/architecture.md).
"""
from sewfmu._version import __version__
from sewfmu.api import Run, Scenario, ScenarioError, Sweep, build, compare, load, run, scenarios, show, sweep

__all__ = ["__version__", "run", "sweep", "compare", "load", "build", "show", "scenarios",
           "Run", "Sweep", "Scenario", "ScenarioError", "CosimError", "Diverged"]


def __getattr__(name: str):
    """The run errors on first use: they live with the engine (fmpy), which `import sewfmu`
    does not load, so that the command line answers Ctrl-C from its first tenth of a second."""
    if name == "CosimError":
        from sewfmu.scenarios.cosim.fmi_calls import CosimError  # the engine: on first use
        return CosimError
    if name == "Diverged":
        from sewfmu.scenarios.cosim.divergence import Diverged  # the engine: on first use
        return Diverged
    raise AttributeError(f"module 'sewfmu' has no attribute {name!r}")
