"""FMU state (get, set, serialize) of a sewfmu FMU: the parameters, the inputs, the time, the
model's internal state and the FMI layer's own, as plain JSON-able values, so that a restored
state repeats the following steps bit for bit (components/slave.py's SewSlave takes it in)."""
from __future__ import annotations

import json
from typing import Any

from .pythonfmu_quirks import describe


class FmuState:
    """pythonfmu's state calls for SewSlave (which provides the attributes it saves)."""

    def _get_fmu_state(self) -> dict[str, Any]:
        return {"params": dict(self._params), "inputs": dict(self._inputs),
                "elapsed": self._elapsed, "time": self._time, "initialized": self._initialized,
                "broken": self._broken, "internal": self.save_internal(),
                "layer": self.save_layer(),
                "rates": [sorted(self._set_since_step), sorted(self._held)]}

    def _set_fmu_state(self, state: dict[str, Any]) -> None:
        try:
            if state["params"] != self._params:
                self._model = None
            internal, layer = state["internal"], state["layer"]   # a foreign state fails here
            fresh, held = state["rates"]
            self._params = dict(state["params"])
            self._inputs = dict(state["inputs"])
            self._elapsed = state["elapsed"]
            self._time = state["time"]
            self._initialized = state["initialized"]
            self._broken = state["broken"]
            self.restore_internal(internal)
            self.restore_layer(layer)
            self._set_since_step, self._held = set(fresh), set(held)
            self._held_stale = True
            self._cache = None
        except Exception as err:          # noqa: BLE001 - a damaged or foreign state
            self._error(f"SetFMUState: not a state of this FMU ({describe(err)}); the "
                        f"instance is left as it was")

    @staticmethod
    def _fmu_state_to_bytes(state: dict[str, Any]) -> bytes:
        return json.dumps(state).encode("utf-8")

    @staticmethod
    def _fmu_state_from_bytes(state: bytes) -> dict[str, Any]:
        try:
            return json.loads(state.decode("utf-8"))
        except Exception as err:          # noqa: BLE001 - refused by _set_fmu_state
            return {"unreadable": describe(err)}

    def save_layer(self) -> dict[str, Any]:
        """What the FMI layer keeps of its own, as plain JSON-able values."""
        return {}

    def restore_layer(self, saved: dict[str, Any]) -> None:
        pass
