"""Where scenarios come from: the catalogue that ships with sewfmu (catalogue/*.toml), a TOML
file (scenarios/format/scenario.py reads it), or an SSP system (scenarios/format/ssp_import.py)."""
from __future__ import annotations

import codecs
import hashlib
import tomllib
from importlib import resources
from pathlib import Path

from sewfmu.components.parameters import did_you_mean
from sewfmu.scenarios.format.parse import from_dict
from sewfmu.scenarios.format.scenario import Scenario
from sewfmu.scenarios.format.values import ScenarioError, short


def _catalogue_folder() -> Path:
    return Path(str(resources.files("sewfmu.scenarios") / "catalogue"))


def catalogue() -> dict[str, Path]:
    """The scenarios that ship with sewfmu: name -> path."""
    return {p.stem: p for p in _catalogue_folder().iterdir() if p.name.endswith(".toml")}


def resolve(name_or_path: str) -> Path:
    path = Path(name_or_path)
    folder = ScenarioError(f"{path_text(path)} is a folder, not a scenario: give a .toml file "
                           f"(or an .ssp) in it")
    if path.suffix.lower() in (".toml", ".ssp", ".ssd") and _is_folder(path):
        raise folder
    if path.suffix.lower() in (".ssp", ".ssd"):
        return path
    if path.suffix == ".toml":
        if not path.is_file():
            raise ScenarioError(f"scenario file {path_text(path)} does not exist")
        return path
    # a catalogue name: its file looked up directly (listing the catalogue costs 0.6 ms a run)
    if name_or_path == path.name and not name_or_path.startswith("."):
        shipped = _catalogue_folder() / f"{name_or_path}.toml"
        try:
            if shipped.is_file():
                return shipped
        except OSError:                  # a name no file can have: not in the catalogue
            pass
    known = catalogue()
    if name_or_path not in known and _is_folder(path):      # not a catalogue name: a folder
        raise folder
    if name_or_path not in known:
        raise ScenarioError(f"unknown scenario {short(name_or_path)}"
                            f"{did_you_mean(name_or_path, known)} (catalogue: "
                            f"{', '.join(sorted(known))}; or give a path to a .toml file)")
    return known[name_or_path]


def _is_folder(path: Path) -> bool:
    try:
        return path.is_dir()
    except (OSError, ValueError):       # a name too long, a NUL: no folder
        return False


def path_text(path: Path) -> str:
    """A path for a message: whole up to 200 characters, else cut, its length said."""
    text = str(path)
    return text if len(text) <= 200 else f"{text[:120]}...{text[-40:]} ({len(text):,} characters)"


def load(name_or_path: str) -> Scenario:
    """A catalogue scenario, a TOML scenario file, or an SSP system (.ssp or .ssd)."""
    path = resolve(name_or_path)
    if path.suffix.lower() in (".ssp", ".ssd"):
        from sewfmu.scenarios.format.ssp_import import load_ssp  # only for an SSP file (start-up time)

        return load_ssp(path)
    try:
        text = _text_of(path.read_bytes(), path)
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ScenarioError(f"{path}: not valid TOML: {err}") from None
    except RecursionError:
        raise ScenarioError(f"{path}: nested too deeply to be a scenario (tables or arrays "
                            f"within each other hundreds of levels deep)") from None
    except ScenarioError:       # _text_of's, itself a ValueError
        raise
    except ValueError:          # tomllib's int(): Python reads at most 4300 digits
        raise ScenarioError(f"{path}: an integer of more than 4300 digits, beyond the range of "
                            f"any value") from None
    except OSError as err:
        raise ScenarioError(f"{path}: cannot read: {err.strerror or err}") from None
    scenario = from_dict(data, path.stem, str(path))
    scenario.digest = hashlib.sha256(text.encode("utf-8")).hexdigest()
    return scenario


def _text_of(raw: bytes, path: Path) -> str:
    """A scenario file's text: UTF-8 (TOML's encoding), with or without a byte-order mark; a
    UTF-16 file (with its mark, as some Windows editors save) is read too. Anything else is an
    error that says where the first byte that is not UTF-8 is."""
    for mark, codec in ((codecs.BOM_UTF8, "utf-8"), (codecs.BOM_UTF16_LE, "utf-16-le"),
                        (codecs.BOM_UTF16_BE, "utf-16-be")):
        if raw.startswith(mark):
            raw, encoding = raw[len(mark):], codec
            break
    else:
        encoding = "utf-8"
    try:
        return raw.decode(encoding)
    except UnicodeDecodeError as err:
        line = raw[:err.start].count(b"\n") + 1
        raise ScenarioError(f"{path}: line {line}: byte 0x{raw[err.start]:02x} is not "
                            f"{encoding.upper()} text; save the file as UTF-8") from None
