"""Reference files read as user input: a reference CSV (`_ref.csv`, `_in.csv`, a carried
`_out.csv`), a Cross-Check `.opt`, the experiment they describe, and the names that become file
names. Whatever the bytes, the answer is the parsed content or a ScenarioError of one line that
names the file, the line (and column) and what would be accepted: a reference that is wrong
must never pass an FMU, fail one without saying why, or run for ever.

- a CSV: UTF-8 text (a byte-order mark is allowed), a header `time, <variable>, ...` with unique
  names, the same number of cells in every row, numbers (`1e-3`, `nan`, `inf`, `true`, `false`)
  in every cell of a compared column; the time finite and strictly increasing (an inputs file:
  non-decreasing, a time given twice being a jump of the inputs, as fmpy reads it). A column with
  no number at all is text (String, Binary), not compared; a column that mixes is refused, since
  it would otherwise drop out of the comparison unseen.
- a `.opt`: lines `Name, value` of StartTime, StopTime, StepSize, RelTol, each at most once,
  finite; StepSize > 0, RelTol in (0, 1).
- the experiment: StopTime after StartTime, at most MAX_STEPS steps, a step the time can
  resolve, the reference's rows within the run.
- a model's name (modelName, from inside an FMU: data, not a path) used as a file or folder name
  only when it is a plain name, and every file written checked to stay inside the folder given.
"""
from __future__ import annotations

import codecs
import csv
import io
import math
import re
from pathlib import Path

import numpy as np

from sewfmu.scenarios.format.values import ScenarioError

OPTIONS = ("StartTime", "StopTime", "StepSize", "RelTol")
# a run longer than this is a mistake in the file (10^7 steps of a Python FMU take hours, and
# its result would not fit a comparison in memory), not a reference anyone recorded
MAX_STEPS = 10 ** 7
# ASCII digits only: float() also reads other scripts' digits and '1_000', which no CSV writer
# produces and which would make a damaged cell a number
_NUMBER = re.compile(r"[+-]?(?:(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|nan|inf|infinity)",
                     re.IGNORECASE)
_BOOLEAN = {"true": 1.0, "false": 0.0}
_ACCEPTED = "a number (1.5, -2e-3, nan, inf) or true/false"
# characters no file name may hold on any system sewfmu runs on
_NOT_IN_NAMES = set('/\\:*?"<>|')


def shown(text: str, limit: int = 40) -> str:
    """A piece of a file in a message: quoted, escaped (a newline in a cell stays one line), and
    cut short."""
    return repr(text if len(text) <= limit else text[:limit] + "...")


def number(text: str) -> float | None:
    """A cell's number (a Boolean as 1 or 0), None if it is not one."""
    cell = text.strip()
    if cell.lower() in _BOOLEAN:
        return _BOOLEAN[cell.lower()]
    return float(cell) if _NUMBER.fullmatch(cell) else None


def text_of(raw: bytes, where) -> str:
    """The file's text: UTF-8 (a byte-order mark allowed, as spreadsheets write one), no NUL."""
    if raw.startswith(codecs.BOM_UTF8):
        raw = raw[len(codecs.BOM_UTF8):]
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        line = raw[:err.start].count(b"\n") + 1
        raise ScenarioError(f"{where}, line {line}: byte 0x{raw[err.start]:02x} is not UTF-8 "
                            f"text; a reference file is UTF-8 text") from None
    if "\0" in text:
        line = text[:text.index("\0")].count("\n") + 1
        raise ScenarioError(f"{where}, line {line}: a NUL character; a reference file is text, "
                            f"not binary data") from None
    return text


def _header(row: list[str], line: int, where) -> list[str]:
    names = [h.strip().strip('"').strip() for h in row]
    if names[0] != "time":
        raise ScenarioError(f"{where}, line {line}: the first column is {shown(names[0])}; a "
                            f"reference CSV's header starts with time, then one column per "
                            f"variable")
    seen: dict[str, int] = {}
    for j, name in enumerate(names, 1):
        if not name:
            raise ScenarioError(f"{where}, line {line}, column {j}: a column without a name; "
                                f"each column of the header names a variable")
        if name in seen:
            # two columns of one name: one of them would never be compared
            raise ScenarioError(f"{where}, line {line}: the column {shown(name)} appears twice "
                                f"(columns {seen[name]} and {j}); each variable once")
        seen[name] = j
    return names


def _rows(text: str, where) -> tuple[list[str], list[tuple[int, list[str]]], int]:
    """The header, the data rows with their line numbers, the header's line."""
    reader = csv.reader(io.StringIO(text, newline=""))
    header, header_line, rows = None, 0, []
    try:
        for row in reader:
            if not row or (len(row) == 1 and not row[0].strip()):
                continue                    # a blank line (a trailing one, most often)
            if header is None:
                header, header_line = _header(row, reader.line_num, where), reader.line_num
            elif len(row) != len(header):
                raise ScenarioError(f"{where}, line {reader.line_num}: {len(row)} cells, the "
                                    f"header has {len(header)}; every row has one cell per "
                                    f"column")
            else:
                rows.append((reader.line_num, row))
    except csv.Error as err:
        raise ScenarioError(f"{where}, line {reader.line_num}: not CSV ({err}); a reference is "
                            f"comma-separated text") from None
    if header is None:
        raise ScenarioError(f"{where}: empty; a reference CSV has a header (time, then one "
                            f"column per variable) and rows of numbers")
    return header, rows, header_line


def parse_csv(raw: bytes | str, where, inputs: bool = False) -> tuple[dict[str, np.ndarray],
                                                                      list[str]]:
    """The columns of a reference CSV as numbers, and the text columns (not compared). `inputs`:
    an `_in.csv`, whose every column is a finite number the FMU is given, and whose time may
    repeat (a jump of the inputs)."""
    text = text_of(raw, where) if isinstance(raw, bytes) else raw
    header, rows, header_line = _rows(text, where)
    least = 1 if inputs else 2
    if len(rows) < least:
        raise ScenarioError(f"{where}: {len(rows)} rows of values below the header; "
                            f"{'an inputs file needs one' if inputs else 'a reference needs two'}"
                            f" or more (the run's start and its end)")
    cells = [[number(row[j]) for line, row in rows] for j in range(len(header))]
    columns, text_columns = {}, []
    for j, (name, values) in enumerate(zip(header, cells)):
        missing = [k for k, v in enumerate(values) if v is None]
        if len(missing) == len(values) and j > 0 and not inputs:
            text_columns.append(name)       # String, Binary: not compared (docs/regression.md)
            continue
        if missing:
            line, row = rows[missing[0]]
            others = "" if len(missing) == len(values) else ", and the column's other cells are"
            raise ScenarioError(f"{where}, line {line}, column {name}: {shown(row[j])} is not a "
                                f"number{others}; {_ACCEPTED}")
        columns[name] = np.array(values, dtype=float)
    _check_time(columns["time"], rows, where, inputs)
    if len(columns) < 2:
        # a reference without a column of numbers would pass any FMU
        text = f" ({', '.join(shown(n, 20) for n in text_columns[:3])}: text)" \
            if text_columns else ""
        raise ScenarioError(f"{where}, line {header_line}: no column of numbers beside time"
                            f"{text}; {'inputs are' if inputs else 'a reference is'} time and "
                            f"at least one variable of numbers")
    if inputs:
        for name, values in columns.items():
            bad = np.flatnonzero(~np.isfinite(values))
            if len(bad):
                line, row = rows[int(bad[0])]
                raise ScenarioError(f"{where}, line {line}, column {name}: "
                                    f"{shown(row[header.index(name)])}; an input is a finite "
                                    f"number (the FMU is given it)")
    return columns, text_columns


def _check_time(times: np.ndarray, rows, where, inputs: bool) -> None:
    bad = np.flatnonzero(~np.isfinite(times))
    if len(bad):
        line, row = rows[int(bad[0])]
        raise ScenarioError(f"{where}, line {line}, column time: {shown(row[0])}; the time is a "
                            f"finite number of seconds")
    steps = np.diff(times)
    # rows out of order would be compared with the wrong times (false alarms); a time given
    # twice in a reference is two values for one instant, of which only one could be right
    wrong = np.flatnonzero(steps < 0 if inputs else steps <= 0)
    if len(wrong):
        k = int(wrong[0])
        rule = "never decreases" if inputs else "increases from row to row, each time once"
        raise ScenarioError(f"{where}, line {rows[k + 1][0]}: the time {times[k + 1]:g} s "
                            f"follows {times[k]:g} s (line {rows[k][0]}); the time {rule}")


def parse_options(raw: bytes | str, where) -> dict[str, float]:
    """A Cross-Check `.opt`: {option: value}, each given at most once, each checked."""
    text = text_of(raw, where) if isinstance(raw, bytes) else raw
    options: dict[str, float] = {}
    lines: dict[str, int] = {}
    # the line numbers an editor shows: \r\n, \r and \n end a line, nothing else does
    for line, content in enumerate(text.replace("\r\n", "\n").replace("\r", "\n").split("\n"), 1):
        if not content.strip():
            continue
        name, comma, value = content.partition(",")
        name = name.strip()
        if not comma:
            raise ScenarioError(f"{where}, line {line}: {shown(content)} is not `Name, value`; "
                                f"a .opt file has lines such as `StepSize, 0.001`")
        if name not in OPTIONS:
            raise ScenarioError(f"{where}, line {line}: unknown option {shown(name)}; a .opt "
                                f"file gives {', '.join(OPTIONS)}")
        if name in options:
            raise ScenarioError(f"{where}, line {line}: {name} again (first on line "
                                f"{lines[name]}); each option once")
        options[name], lines[name] = _option(name, value, f"{where}, line {line}"), line
    return options


def _option(name: str, text: str, where: str) -> float:
    value = number(text)
    if value is None or not math.isfinite(value) or text.strip().lower() in _BOOLEAN:
        raise ScenarioError(f"{where}: {name} is {shown(text.strip())}; a finite number")
    if name == "StepSize" and value <= 0:
        raise ScenarioError(f"{where}: StepSize is {value:g}; a step longer than 0 s")
    if name == "RelTol" and not 0 < value < 1:
        raise ScenarioError(f"{where}: RelTol is {value:g}; a relative tolerance between 0 and "
                            f"1, such as 1e-6")
    return value


def read_options(path: Path) -> dict[str, float]:
    return parse_options(Path(path).read_bytes(), path)


def check_experiment(where, start: float, stop: float, step: float, rel_tol: float,
                     times: np.ndarray | None = None) -> None:
    """A run the reference can be checked with: from start to a later stop, in at most
    MAX_STEPS steps of a length the time can resolve, every row of the reference within it."""
    for name, value in (("StartTime", start), ("StopTime", stop), ("StepSize", step),
                        ("RelTol", rel_tol)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value):
            raise ScenarioError(f"{where}: {name} is {value!r}; a finite number")
    if not stop > start:
        raise ScenarioError(f"{where}: StopTime {stop:g} s is not after StartTime {start:g} s; "
                            f"a reference runs from its start to a later stop")
    if not 0 < step <= (stop - start) * (1 + 1e-9):
        raise ScenarioError(f"{where}: StepSize {step:g} s; a step longer than 0 and at most the "
                            f"run ({stop - start:g} s)")
    steps = (stop - start) / step
    if not steps <= MAX_STEPS:
        raise ScenarioError(f"{where}: StepSize {step:g} s from {start:g} to {stop:g} s is "
                            f"{steps:.3g} steps; at most {MAX_STEPS:.0e} (a longer step or a "
                            f"shorter run)")
    # t + step must differ from t: at |t| = 1e12 s a step of 1e-5 s is lost in the rounding
    if step < 1e-12 * max(abs(start), abs(stop)):
        raise ScenarioError(f"{where}: StepSize {step:g} s is below what times near "
                            f"{max(abs(start), abs(stop)):g} s can resolve; a step of at least "
                            f"{1e-12 * max(abs(start), abs(stop)):g} s")
    if not 0 < rel_tol < 1:
        raise ScenarioError(f"{where}: RelTol {rel_tol:g}; a relative tolerance between 0 and 1")
    if times is not None:
        slack = 1e-9 * max(abs(start), abs(stop), stop - start)
        if times[0] < start - slack or times[-1] > stop + slack:
            # a row outside the run would be compared with a value the run never had
            raise ScenarioError(f"{where}: the reference's rows run from {times[0]:g} to "
                                f"{times[-1]:g} s, outside the run from StartTime {start:g} to "
                                f"StopTime {stop:g} s; the rows lie within the run")


def plain_name(name, where) -> str:
    """A model's name (modelName, from inside an FMU) as a file or folder name: refused unless it
    is a plain name, since `../..`, `/etc` or `C:\\x` would lead out of the folder given."""
    if not isinstance(name, str) or not name or name.startswith(".") or name != name.strip() \
            or len(name.encode("utf-8", "replace")) > 200 \
            or any(c in _NOT_IN_NAMES or ord(c) < 32 or ord(c) == 127 for c in name):
        raise ScenarioError(f"{where}: the modelName {shown(str(name))} is not a plain file name; "
                            f"references are kept under the model's name, which must be one "
                            f"name (no / \\ : * ? \" < > |, control characters or leading '.', "
                            f"at most 200 bytes)")
    return name


def inside(folder: Path, path: Path, where) -> Path:
    """`path`, refused unless it resolves inside `folder` (links followed): every file a
    reference writes stays in the folder the user named."""
    root = Path(folder).resolve()
    resolved = Path(path).resolve()
    if resolved != root and root not in resolved.parents:
        raise ScenarioError(f"{where}: {path} leads to {resolved}, outside {folder} (a link?); "
                            f"references are written inside the folder given")
    return path
