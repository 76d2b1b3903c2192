"""The values a user types on the page, read as the command line reads `--set`: a TOML scalar
(a number, true or false, a quoted string) or else the text itself ("955 rpm"), then given to
`sewfmu.check(scenario, set=...)`, whose refusal (one line, a sewfmu.Error) is what the page
shows. Also what reproduces a run: its command line and its scenario as TOML."""
from __future__ import annotations

import itertools
import math
import shlex
import tomllib
from typing import Any

import sewfmu

# the experiment's keys the page offers beside the instances' parameters: key -> (unit, meaning)
EXPERIMENT = {"revolutions": ("rev", "shaft revolutions to run"),
              "stop_time": ("s", "end of the run"),
              "step": ("s", "communication step")}
# and the build of sewfmu's FMUs the run takes (experiment.fmus), for a co-simulated scenario
# that has any
FMUS_MEANING = "sewfmu's FMUs: python, or native (compiled C, the same numbers)"


def value_of(text: str) -> Any:
    """A typed value as `--set` reads it (sewfmu.read_value): a TOML scalar, else the text (a
    value with its unit)."""
    try:
        value = sewfmu.read_value(text)
    except sewfmu.Error:              # nested too deeply: the text, which check() refuses
        return text
    return value if isinstance(value, (int, float, bool, str)) else text


def shown(value: Any) -> str:
    """A value as an input shows it: numbers to 6 significant digits (an unchanged input is not
    sent, so the rounding never reaches a run)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:.6g}" if math.isfinite(value) else str(value)
    return str(value)


def inputs_of(source: str) -> list[dict]:
    """Every value the page offers for a scenario: each instance's parameters and the
    experiment's keys, as {name, value (text), unit, range, meaning}."""
    rows = [{"name": f"{r['instance']}.{r['parameter']}", "value": shown(r["value"]),
             "unit": r.get("unit") or "", "range": str(r.get("range") or ""),
             "meaning": r.get("meaning") or ""} for r in sewfmu.parameters(source)]
    scenario = sewfmu.load(source)
    for key, (unit, meaning) in EXPERIMENT.items():
        value = getattr(scenario, key, None)
        if key == "stop_time" and scenario.revolutions is not None:
            continue                      # a scenario of revolutions: its end is those
        if value is not None:
            rows.append({"name": f"experiment.{key}", "value": shown(value), "unit": unit,
                         "range": "> 0", "meaning": meaning})
    if scenario.study is None and \
            not all(inst.fmu in scenario.fmu_files for inst in scenario.instances.values()):
        rows.append({"name": "experiment.fmus", "value": scenario.fmus, "unit": "",
                     "range": "python, native", "meaning": FMUS_MEANING})
    return rows


def short_run(source: str) -> dict | None:
    """The values that make a scenario's run short (one revolution, or ten steps), given with
    their units so that reading them loads the units too: a run or a check of them warms a
    process (its FMUs loaded, its unit registry built) before the user's own. None for a
    scenario that is computed rather than run (a study)."""
    scenario = sewfmu.load(source)
    if scenario.study is not None:
        return None
    if scenario.revolutions is not None:
        return {"experiment.revolutions": f"{min(scenario.revolutions, 1)!r} rev"}
    return {"experiment.stop_time": f"{min(scenario.stop_time, 10 * scenario.step)!r} s"}


def changed_values(source: str, typed: dict[str, str], defaults: dict[str, str]) -> dict:
    """The values typed that differ from the scenario's, checked as a run checks them before
    its first step: {name: text}. A bad one raises sewfmu.Error with its one line."""
    changed = {}
    for name, text in typed.items():
        text = readable(name, text)
        if text == defaults.get(name) or _same_number(text, defaults.get(name)):
            continue
        if not text:
            raise _error(f"{name}: give a value (its scenario's is {defaults.get(name)})")
        changed[name] = text
    # as a run checks them before its first step (declared ranges too): a bad value starts nothing
    checked(sewfmu.check, source, {name: value_of(text) for name, text in changed.items()})
    return changed


def check_points(source: str, changed: dict[str, str], grid: dict[str, list]) -> None:
    """Every point of a sweep (the changed values, then one value of each swept parameter)
    checked as a run checks its values before its first step (sewfmu.check: declared ranges,
    what the FMU refuses, the run's size), before the sweep's process starts: the first bad one
    a sewfmu.Error naming the point. About a millisecond a point."""
    base = {name: value_of(text) for name, text in changed.items()}
    names = list(grid)
    for values in itertools.product(*(grid[name] for name in names)):
        point = dict(zip(names, values))
        try:
            checked(sewfmu.check, source, {**base, **point})
        except sewfmu.Error as err:
            where = ", ".join(f"{name} = {shown(value)}" for name, value in point.items())
            raise _error(f"sweep point {where}: {' '.join(str(err).split())}") from None


# characters of a typed value the page reads ("-1.2345678901234567e-300 rad/s" is 31): a longer
# one is refused before any parser works through it (5000 digits passed Python's limit of
# integer digits; a long text costs the unit parser time)
MAX_TEXT = 200
ACCEPTED = 'give a number, or a number with its unit like "955 rpm"'


def readable(name: str, text) -> str:
    """A typed value as text, stripped, that value_of reads: one past MAX_TEXT characters, or
    one whose reading raises anything (a parser's failure on odd text), is a sewfmu.Error."""
    text = "" if text is None else str(text).strip()
    if len(text) > MAX_TEXT:
        raise _error(f"{name}: a value of {len(text)} characters, at most {MAX_TEXT} are read; "
                     f"{ACCEPTED}")
    try:
        value_of(text)
    except Exception as err:        # any failure to read the text: its one line
        raise _unreadable(f"{name} = {text!r}", err) from None
    return text


def checked(check, source: str, values: dict) -> None:
    """check(source, set=values) (sewfmu.check or sewfmu.load), whatever it raises a
    sewfmu.Error: the value parser's own failure on odd text (ValueError, OverflowError, pint's
    errors) is still a value the user typed, said in one line that names it, not a 500."""
    try:
        check(source, set=values)
    except sewfmu.Error:
        raise
    except Exception as err:        # any parser failure: see the docstring
        culprit = next((name for name in values if _fails_oddly(check, source, name,
                                                                values[name])), None)
        raise _unreadable(f"{culprit} = {str(values[culprit])!r}" if culprit else
                          ", ".join(f"{n} = {str(v)!r}" for n, v in values.items()),
                          err) from None


def _fails_oddly(check, source: str, name: str, value) -> bool:
    """The value alone makes check raise something other than a sewfmu.Error."""
    try:
        check(source, set={name: value})
    except sewfmu.Error:
        return False
    except Exception:               # the failure checked() names the value of
        return True
    return False


def _unreadable(what: str, err: Exception) -> Exception:
    reason = " ".join(str(err).split()) or type(err).__name__
    return _error(f"set {what}: not a value sewfmu can read ({reason}); {ACCEPTED}")


def _same_number(text: str, default: str | None) -> bool:
    """"100.0" typed where the scenario has 100: the same value, not a change to send."""
    typed, given = value_of(text), value_of(default or "")
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (typed, given)) \
        and typed == given


def _error(line: str) -> Exception:
    return sewfmu.ScenarioError(line)


def command_line(scenario: str, changed: dict[str, str]) -> str:
    """The command that reproduces a run: `sewfmu run NAME --set a=b ...`."""
    sets = " ".join(f"--set {shlex.quote(f'{k}={v}')}" for k, v in changed.items())
    return f"sewfmu run {shlex.quote(scenario)}" + (f" {sets}" if sets else "")


def scenario_toml(text: str, changed: dict[str, str]) -> str:
    """A TOML scenario's text with the changed values written into it (an instance's parameter
    into its `parameters` table, an experiment key into [experiment])."""
    data = tomllib.loads(text)
    for name, typed in changed.items():
        inst, _, key = name.partition(".")
        if inst == "experiment":
            data.setdefault("experiment", {})[key] = value_of(typed)
        else:
            table = data.setdefault("instances", {}).setdefault(inst, {})
            table.setdefault("parameters", {})[key] = value_of(typed)
    return _toml(data)


def _toml(data: dict, prefix: str = "") -> str:
    """A small TOML writer for a scenario's tables: scalars, lists and inline tables of them."""
    plain = [f"{k} = {_scalar(v)}" for k, v in data.items()
             if not isinstance(v, dict) or k == "parameters"]
    tables = [(k, v) for k, v in data.items() if isinstance(v, dict) and k != "parameters"]
    parts = ["\n".join(plain)] if plain else []
    for key, table in tables:
        name = f"{prefix}{_key(key)}"
        if all(isinstance(v, dict) for v in table.values()) and table:
            parts.append(_toml(table, f"{name}."))
        else:
            parts.append(f"[{name}]\n{_toml(table, f'{name}.')}".rstrip())
    return "\n\n".join(p for p in parts if p) + ("\n" if not prefix else "")


def _key(key: str) -> str:
    return key if key.replace("_", "").replace("-", "").isalnum() else _scalar(key)


def _scalar(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ("nan" if value != value else
                                                         ("inf" if value > 0 else "-inf"))
    if isinstance(value, list):
        return "[" + ", ".join(_scalar(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_scalar(v)}" for k, v in value.items()) + " }"
    return str(value)
