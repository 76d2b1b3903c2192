"""Where sewfmu keeps what it works out once and reuses across processes: $SEWFMU_CACHE_DIR
(relative: from the folder the process started in), else $XDG_CACHE_HOME/sewfmu/fmus, else
~/.cache/sewfmu/fmus; SEWFMU_CACHE_DIR="" turns it off. That folder may be the user's, so
sewfmu keeps to its subfolder SUBFOLDER there: the extracted FMUs (scenarios/cosim/fmu_cache.py),
in its folder "declared-units" the FMUs' declared units (scenarios/format/declared_units.py),
and in its folder "stepper" the compiled step loop (scenarios/cosim/stepper.py). A module of
its own, light, so that a scenario's checks find the folder without the engine."""
from __future__ import annotations

import os
from pathlib import Path

SUBFOLDER = "sewfmu-fmu-cache"

# the folder the process started in (see configured_root)
try:
    START_DIR: str | None = os.getcwd()
except OSError:                     # started in a removed folder
    START_DIR = None


def configured_root(start_dir: str | None = START_DIR) -> Path | None:
    """Where the cache is to be (not made here); None where it is turned off."""
    setting = os.environ.get("SEWFMU_CACHE_DIR")
    if setting == "":
        return None
    if setting:
        return Path(os.path.abspath(os.path.join(start_dir or os.getcwd(),
                                                 os.path.expanduser(setting))))
    # the XDG specification: a relative XDG_CACHE_HOME is invalid and ignored
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg and os.path.isabs(xdg) else Path.home() / ".cache"
    return base / "sewfmu" / "fmus"
