"""The FMUs of the linkages driven by the main shaft: a linkage FMU only declares its model and
its outputs, each read from the model's motion where its port's `source` says."""
from __future__ import annotations

from operator import attrgetter

from .ports import SHAFT_TAYLOR, shaft_inputs
from .slave import SewSlave


class LinkageSlave(SewSlave):
    """An FMU of a linkage driven by the main shaft: its model's `motion(φ, ω, ε)` at the
    extrapolated shaft inputs gives every output (all direct feedthrough), each read from the
    motion where its port's `source` says. A linkage FMU only declares."""

    taylor_inputs = SHAFT_TAYLOR
    speed = 100.0                  # rad/s: the start value of the input omega

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        cls.inputs = shaft_inputs(cls.speed)
        # each output's path into the motion, split once; where every path is an attribute
        # path (no dict on the way), one attrgetter reads them all
        cls._paths = tuple(tuple((port.source or port.name).split(".")) for port in cls.outputs)
        cls._read_motion = attrgetter(*(port.source or port.name for port in cls.outputs)) \
            if len(cls.outputs) > 1 else None

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._by_attributes = type(self)._read_motion is not None

    def current_outputs(self):
        return dict(zip(self._row_names, self.output_row()))

    def output_row(self):
        u = self.extrapolated_inputs(self._elapsed)
        model = self._model               # built already but before the first step
        motion = (model if model is not None else self.model()).motion(u["phi"], u["omega"],
                                                                         u["epsilon"])
        if self._by_attributes:
            try:
                return list(map(float, type(self)._read_motion(motion)))
            except AttributeError:        # a dict on the way (joints by name): by _pick
                self._by_attributes = False
        return [float(_pick(motion, path)) for path in type(self)._paths]


def _pick(value, path: tuple[str, ...]):
    for key in path:
        value = value[key] if isinstance(value, dict) else getattr(value, key)
    return value
