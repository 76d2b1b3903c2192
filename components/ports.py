"""The ports of sewfmu's FMUs as their slave classes declare them: inputs, outputs and calculated
parameters with units, and the range an input may take (components/slave.py declares the
variables from them)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence


@dataclass(frozen=True)
class Port:
    """An input, output or calculated parameter of an FMU."""
    name: str
    unit: str
    description: str
    start: float = 0.0             # inputs only
    feedthrough: bool = False      # outputs only: depends on the inputs at the same instant
    kind: str = "Real"             # "Real" or "Boolean"
    discrete: bool = False         # outputs: a value of the last step, not to interpolate
    source: str = ""               # linkage outputs: where in the model's motion the value is
                                   # ("E.x", "joints.M.vy"); default: the port's name
    bound: float | None = -1.0     # inputs: the largest magnitude the mechanism can see; -1:
                                   # SIGNAL_SCALE of the unit; None: unbounded (a cumulative angle)


# The largest magnitude an input of each unit has in a running sewing-machine mechanism (an
# order of magnitude above the hardest case of the catalogue): the declared min/max of an
# input. A value beyond it is refused at doStep: it is a co-simulation that diverges (the punch
# pressed metres into the fabric) or a value in another unit, never a figure to compute with.
SIGNAL_SCALE: dict[str, float] = {
    "m": 0.1, "m/s": 100.0, "m/s2": 1e6, "m/s3": 1e9, "N": 1e5, "N/s": 1e10,
    "rad/s": 2000.0, "rad/s2": 1e7,
}


def shaft_inputs(omega: float) -> tuple[Port, Port, Port]:
    """The main shaft's motion, the inputs of every linkage (extrapolated inside a step), starting
    at the setup position φ = 0 and turning at `omega`: the mechanism's own default speed, so
    that a host that starts the inputs at their start values runs it at that speed."""
    return (
        Port("phi", "rad", "shaft angle, cumulative (the crank angle of the linkage)"),
        Port("omega", "rad/s", "shaft speed", start=omega),
        Port("epsilon", "rad/s2", "shaft angular acceleration"),
    )


SHAFT_TAYLOR = (("phi", "omega", "epsilon"),)


def input_bound(port: Port) -> float | None:
    """The largest magnitude an input takes: its own, or its unit's SIGNAL_SCALE."""
    return SIGNAL_SCALE.get(port.unit) if port.bound == -1.0 else port.bound


def input_ranges(inputs: Sequence[Port]) -> tuple[tuple[str, float, str], ...]:
    """(name, bound, unit) of every bounded input."""
    return tuple((p.name, input_bound(p), p.unit) for p in inputs if input_bound(p) is not None)


def held_note(name: str, rate_of: dict[str, str]) -> str:
    """What a rate input's description says of a host that does not set it."""
    if name not in rate_of:
        return ""
    return (f"; acts as zero unless set each time {rate_of[name]} is (a host that sets only "
            f"{rate_of[name]} gets it held between steps)")
