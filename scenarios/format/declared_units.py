"""The declared unit of every parameter and input of sewfmu's FMUs, for a scenario's checks (is
`shaft.omega0` a parameter? which unit is "955 rpm" converted to?) and a sweep's axes, and the
range of every parameter (a converted value a rounding beyond a bound is that bound).

The FMUs' slave classes declare them (components/registry.py reads them there), but importing
those classes cost every process the models, the slave layer and ctypes before anything ran,
while the FMU imports its own copy of them anyway. So they are worked out from the classes once
per version of the model code (the content hash of components/, files/code_hash.py) and kept
in the cache folder (files/cache_root.py), in the folder FOLDER of its subfolder, as one small
JSON file named by that hash; a later process reads it. Writing one removes the tables of other
versions not written for STALE_DAYS. A file that does not say what it must (another hash
inside, an FMU missing, not JSON, units that do not match the digest written with them: a
table changed by hand or damaged on disk would convert "955 rpm" into a wrong unit without a
word) is not used: the classes are read again and the file written anew. Without a cache
folder (SEWFMU_CACHE_DIR=""), or where it cannot be written, the classes are read in every
process, as before.
"""
from __future__ import annotations

import hashlib
import importlib
import json
import re
import time
from pathlib import Path

import sewfmu.components
from sewfmu.components.registry import FMUS
from sewfmu.components.registry import parameter_units as _from_classes
from sewfmu.scenarios.files.cache_root import SUBFOLDER, configured_root
from sewfmu.scenarios.files.code_hash import hash_of

FOLDER = "declared-units"           # in the cache's SUBFOLDER (files/cache_root.py)
STALE_DAYS = 30                     # tables of other code versions not written since go

MODEL_CODE_DIR = Path(sewfmu.components.__file__).resolve().parent   # what the slave classes are
_NAME = re.compile(r"[0-9a-f]{12}\.json")      # the tables' names: nothing else is removed
# this process's: code hash -> (units, bounds), each FMU -> parameter -> its unit, its range
_KNOWN: dict[str, tuple[dict, dict]] = {}


def parameter_units(fmu: str) -> dict[str, str]:
    """name -> declared unit of each parameter and input of one of sewfmu's FMUs (a copy)."""
    return dict(_table()[0][fmu])


def parameter_bounds(fmu: str) -> dict[str, tuple[float | None, float | None]]:
    """name -> the declared (min, max) of each parameter of one of sewfmu's FMUs (a value
    given with a unit that lands a rounding beyond one is that bound: format/declared_range)."""
    return {name: (low, high) for name, (low, high) in _table()[1][fmu].items()}


def _table() -> tuple[dict, dict]:
    key = hash_of(MODEL_CODE_DIR)       # as fmu_build/sources.py's model_code_hash
    if key in _KNOWN:
        return _KNOWN[key]
    root = configured_root()
    path = None if root is None else root / SUBFOLDER / FOLDER / f"{key}.json"
    table = _read(path, key) if path is not None else None
    if table is None:
        table = ({fmu: _from_classes(fmu) for fmu in FMUS},
                 {fmu: _bounds_from_classes(fmu) for fmu in FMUS})
        if path is not None:
            _write(path, key, table)
    _KNOWN[key] = table
    return table


def _bounds_from_classes(fmu: str) -> dict[str, list]:
    """The declared range of each parameter, from the slave class (components/parameters.py)."""
    from sewfmu.components.parameters import parameter_info  # with the classes, as the units

    module, slave = FMUS[fmu]
    cls = getattr(importlib.import_module(f"sewfmu.components.{module}"), slave)
    infos = parameter_info(cls.params_class) if cls.params_class else []
    return {info.name: [_number(b) for b in info.bounds] for info in infos}


def _number(bound) -> float | None:
    return None if bound is None else float(bound)


def _read(path, key: str) -> dict[str, dict[str, str]] | None:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        units, bounds = data["units"], data["bounds"]
        if data["model_code"] != key or set(units) != set(FMUS) or not all(
                isinstance(u, dict) and all(isinstance(n, str) and isinstance(v, str)
                                            for n, v in u.items()) for u in units.values()):
            return None
        if set(bounds) != set(FMUS) or not all(
                isinstance(b, dict) and all(isinstance(r, list) and len(r) == 2 and all(
                    x is None or type(x) is float for x in r) for r in b.values())
                for b in bounds.values()):
            return None
        return (units, bounds) if data["digest"] == _digest(units, bounds) else None
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


def _digest(units: dict, bounds: dict) -> str:
    """The table's own hash, written beside it: a table whose units or ranges were changed
    afterwards does not match it."""
    return hashlib.sha256(json.dumps([units, bounds], sort_keys=True).encode()).hexdigest()


def _write(path, key: str, table: tuple[dict, dict]) -> None:
    from sewfmu.scenarios.files.outputs import write_atomic  # only when the table is new

    units, bounds = table
    try:
        write_atomic(path, lambda f: json.dump({"model_code": key,
                                                "digest": _digest(units, bounds),
                                                "units": units, "bounds": bounds}, f, indent=1))
        old = time.time() - STALE_DAYS * 86400
        for other in path.parent.iterdir():
            if (_NAME.fullmatch(other.name) and other != path and other.is_file()
                    and other.stat().st_mtime < old):
                other.unlink()
    except OSError:                 # a cache that cannot be written: read the classes next time
        pass
