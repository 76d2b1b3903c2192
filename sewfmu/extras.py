"""The optional packages: which extra of pyproject.toml installs each, the pip command that adds
it to this sewfmu, and one refusal (MissingExtra) wherever a call needs one that is missing, so
that `to_pandas()`, a Dask sweep, a sensitivity study or another host says what to install
instead of ending in a bare ModuleNotFoundError."""
from __future__ import annotations

import importlib
import json
from urllib.parse import unquote, urlparse

from sewfmu.errors import Error

# the optional packages and the extra of pyproject.toml that installs each
EXTRAS = {"distributed": "dask", "dask": "dask", "libcosimpy": "interop", "ecospy": "interop",
          "pyssp_standard": "interop", "fmu_manipulation_toolbox": "interop", "tbb": "interop",
          "pandas": "pandas", "SALib": "design", "dash": "app", "plotly": "app"}


class MissingExtra(Error, ModuleNotFoundError):
    """An optional package that a call needs is not installed."""


def require(module: str, what: str):
    """`module` imported, or MissingExtra naming the extra that installs it ("`what` needs the
    optional package P: pip install ...")."""
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as err:
        top = (err.name or module).split(".")[0]
        extra = EXTRAS.get(top) or EXTRAS.get(module.split(".")[0])
        if extra is None:
            raise
        raise MissingExtra(f"{what} needs the optional package {top}: "
                           f"{install_command(extra)}", name=top) from None


def install_command(extra: str) -> str:
    """The pip command that adds an extra to this sewfmu, from where it was installed: its
    checkout (editable or not), its wheel, or the package index."""
    from importlib import metadata  # 30 ms: only when a command is to be named

    # (a build's sewfmu.egg-info in the working folder is a distribution too, without origin)
    found = [d.read_text("direct_url.json") for d in metadata.distributions(name="sewfmu")]
    try:
        origin = json.loads(next((t for t in found if t), "{}")) if found else None
    except ValueError:
        origin = {}
    if origin is None:                    # not installed: running from a checkout
        return f"pip install -e \".[{extra}]\" in sewfmu's checkout"
    url = origin.get("url", "")
    if not url.startswith("file://"):
        return f"pip install \"sewfmu[{extra}]\""
    where = unquote(urlparse(url).path)
    editable = "-e " if origin.get("dir_info", {}).get("editable") else ""
    return f"pip install {editable}\"{where}[{extra}]\""
