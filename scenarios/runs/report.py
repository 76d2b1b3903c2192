"""report.html: one self-contained page a colleague can open, on a phone or a wide screen.

Everything is inside the file: the pictures as data: URIs, the style inline, no script and
nothing fetched from the network. A report has sections, each a heading with tables, pictures and
notes; `run_report`, `study_report` and `sweep_report` assemble them from what a command wrote.
"""
from __future__ import annotations

import base64
import html
import math
from dataclasses import dataclass, field
from pathlib import Path

from sewfmu.scenarios.files.outputs import write_atomic
from sewfmu.scenarios.fmu_build.sources import VERSION

STYLE = """
body { font: 15px/1.45 system-ui, -apple-system, "Segoe UI", sans-serif; margin: 0; color: #222;
       background: #fafafa; }
main { max-width: 1100px; margin: 0 auto; padding: 12px 16px 40px; }
h1 { font-size: 1.45em; margin: 0.6em 0 0.2em; }
h2 { font-size: 1.15em; margin: 1.6em 0 0.5em; border-bottom: 1px solid #ddd; }
p.lead { color: #555; margin-top: 0; }
.scroll { overflow-x: auto; }
table { border-collapse: collapse; margin: 0.4em 0 1em; font-size: 0.93em; }
th, td { padding: 3px 10px; border-bottom: 1px solid #e4e4e4; text-align: left;
         vertical-align: top; overflow-wrap: anywhere; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.set td { font-weight: 600; }
figure { margin: 0.5em 0 1.2em; }
figure img { max-width: 100%; height: auto; border: 1px solid #e4e4e4; background: white; }
figcaption { color: #555; font-size: 0.9em; }
.pictures { display: flex; flex-wrap: wrap; gap: 16px; }
.pictures figure { flex: 1 1 360px; min-width: 0; }
/* a phone: each row of a table of three columns or more becomes a card, one "column: value"
   line per cell, so that no value hides beyond the screen's edge */
@media (max-width: 640px) {
  main { padding: 8px 10px 32px; }
  table.cards, table.cards tbody, table.cards tr, table.cards td { display: block; }
  table.cards { width: 100%; }
  table.cards thead { display: none; }
  table.cards tr { border-bottom: 1px solid #d0d0d0; padding: 4px 0; }
  table.cards td { border: none; padding: 1px 4px; text-align: left; }
  table.cards td::before { content: attr(data-label) ": "; color: #666; font-weight: normal; }
}
"""


@dataclass
class Section:
    title: str
    blocks: list[str] = field(default_factory=list)     # HTML fragments

    def table(self, header: list[str], rows: list[list], numeric: set[int] = frozenset(),
              marked: list[bool] | None = None, keep: int = 1) -> None:
        """A table; one wider than a wide screen is split into tables of fewer columns, each
        repeating the first `keep` columns (which say what a row is)."""
        for columns in _column_groups(header, rows, keep):
            self._table([header[j] for j in columns], [[row[j] for j in columns] for row in rows],
                        {i for i, j in enumerate(columns) if j in numeric}, marked)

    def _table(self, header: list[str], rows: list[list], numeric: set[int],
               marked: list[bool] | None) -> None:
        head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
        labels = [html.escape(h, quote=True) for h in header]
        body = []
        for k, row in enumerate(rows):
            cells = "".join(f'<td data-label="{labels[j]}"{NUMERIC if j in numeric else ""}>'
                            f"{html.escape(_text(v))}</td>" for j, v in enumerate(row))
            cls = ' class="set"' if marked and marked[k] else ""
            body.append(f"<tr{cls}>{cells}</tr>")
        cards = ' class="cards"' if len(header) >= 3 else ""
        self.blocks.append(f'<div class="scroll"><table{cards}><thead><tr>{head}</tr></thead>'
                           f'<tbody>{"".join(body)}</tbody></table></div>')

    def pictures(self, items: list[tuple[str, Path]]) -> None:
        figures = []
        for caption, path in items:
            mime = "image/gif" if Path(path).suffix == ".gif" else "image/png"
            data = base64.b64encode(Path(path).read_bytes()).decode("ascii")
            figures.append(f'<figure><img src="data:{mime};base64,{data}" '
                           f'alt="{html.escape(caption)}"><figcaption>{html.escape(caption)}'
                           f"</figcaption></figure>")
        if figures:
            self.blocks.append(f'<div class="pictures">{"".join(figures)}</div>')

    def note(self, text: str) -> None:
        self.blocks.append(f"<p>{html.escape(text)}</p>")


NUMERIC = ' class="num"'

# what a table may take of a wide screen's line (main is 1100 px wide), and the width of a
# character of the table's font with a cell's padding, estimated on the safe side
WIDE_SCREEN_PX = 1000
CHAR_PX, PADDING_PX = 8.5, 22


def _column_groups(header: list[str], rows: list[list], keep: int) -> list[list[int]]:
    """Indices of the columns of each table a wide table is split into."""
    widths = [PADDING_PX + CHAR_PX * max(len(_text(v)) for v in [h] + [r[j] for r in rows])
              for j, h in enumerate(header)]
    keep = min(keep, len(header))
    groups, current = [], list(range(keep))
    for j in range(keep, len(header)):
        if len(current) > keep and sum(widths[i] for i in current) + widths[j] > WIDE_SCREEN_PX:
            groups.append(current)
            current = list(range(keep))
        current.append(j)
    groups.append(current)
    return groups


def _text(value) -> str:
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if value != value or math.isinf(value):
            return str(value)
        return f"{value:.6g}" if abs(value) < 1e6 else f"{value:.4e}"
    return "" if value is None else str(value)


def write(path: Path, title: str, lead: str, sections: list[Section]) -> None:
    body = "".join(f"<section><h2>{html.escape(s.title)}</h2>{''.join(s.blocks)}</section>"
                   for s in sections)
    page = (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{html.escape(title)}</title><style>{STYLE}</style></head>"
            f'<body><main><h1>{html.escape(title)}</h1><p class="lead">{html.escape(lead)}</p>'
            f"{body}</main></body></html>\n")
    write_atomic(Path(path), lambda f: f.write(page))


def provenance_sections(provenance: dict) -> list[Section]:
    """What was run: the scenario, master, step, versions; every parameter (the scenario's own
    values in bold)."""
    run = Section("What was run")
    sc = provenance["scenario"]
    run.table(["", ""], [["scenario", sc["name"]], ["file", sc["source"]],
                         ["sha256", sc.get("sha256") or ""],
                         ["master", provenance["master"]], ["step", f"{provenance['step']:g} s"],
                         ["end time", f"{provenance['end_time']:.6g} s"],
                         ["sewfmu", provenance["sewfmu"]]]
              + [[f"FMU {name}", f"{version} ({provenance['fmu_builds'][name]})"
                  if name in provenance.get("fmu_builds", {}) else version]
                 for name, version in provenance["fmus"].items()])
    params = Section("Parameters (the scenario's own values in bold)")
    rows, marked = [], []
    for inst, spec in provenance["instances"].items():
        for name, p in spec["parameters"].items():
            rows.append([inst, spec["fmu"], name, p["value"], p["unit"]])
            marked.append(bool(p["set"]))
    params.table(["instance", "FMU", "parameter", "value", "unit"], rows, numeric={3},
                 marked=marked)
    return [run, params]


def comparison_section(rows: list[tuple], title: str, units: dict[str, str]) -> Section:
    section = Section(title)
    section.table(["figure", "co-simulation", "monolithic", "difference", "unit"],
                  [[k, a, b, d, units.get(k, "")] for k, a, b, d in rows], numeric={1, 2, 3})
    return section


# --- the three kinds of report ---------------------------------------------------------------
def run_report(path: Path, scenario, runs: list[tuple], pictures: list[tuple[str, Path]],
               against_monolithic: dict[str, list]) -> None:
    """A scenario's run (or its [compare] variants): figures, pictures, the monolithic
    comparison where computed, and what was run."""
    sections = []
    labels = [label for label, _, _ in runs]
    keys = [k for k, v in runs[0][2].items()
            if k not in ("scenario", "master", "provenance") and not isinstance(v, (dict, list))]
    figures = Section("Key figures" + (" (last revolution)" if scenario.analysis else ""))
    units = runs[0][2].get("units", {})
    figures.table(["figure", *(labels if labels != [""] else ["value"]), "unit"],
                  [[k, *(own.get(k) for _, _, own in runs), units.get(k, "")] for k in keys],
                  numeric=set(range(1, len(runs) + 1)))
    sections.append(figures)
    for label, _, own in runs:                # the estimated coupling error of each figure
        found = own.get("coupling_error")
        if not found or found.get("none"):
            continue
        errors = Section("Bound of the coupling error" + (f", {label}" if label else ""))
        if found.get("failed"):
            errors.table(["method", "no bound"], [[found["method"], found["failed"]]])
        else:       # a figure without a bound says why in the bound's place
            errors.table(["figure", f"± (from {found['method']})", "unit"],
                         [[k, e, units.get(k, "")] for k, e in found["figures"].items()]
                         + [[k, f"none: {why}", ""] for k, why in found.get("untrusted", {}).items()],
                         numeric={1})
        sections.append(errors)
    for label, rows in against_monolithic.items():
        sections.append(comparison_section(
            rows, "Against the monolithic solution (one ODE, DOP853, rtol 1e-8)"
                  + (f", {label}" if label else ""), units))
    if pictures:
        shown = Section("Pictures")
        shown.pictures(pictures)
        sections.append(shown)
    what = provenance_sections(runs[0][2]["provenance"])
    if scenario.compare:
        what[0].note(f"The runs differ in {scenario.compare['parameter']} only: "
                     f"{', '.join(_text(v) for v in scenario.compare['values'])}; the parameter "
                     f"table shows the first run's values.")
    sections.extend(what)
    write(path, f"sewfmu: {scenario.name}", scenario.description, sections)


def study_report(path: Path, name: str, study, headline: dict, picture: Path) -> None:
    figures = Section("Headline figures")
    rows = []
    for key, value in headline.items():
        unit = study.units.get(key, "")
        if isinstance(value, dict):
            rows += [[f"{key} [{sub}]", v, unit] for sub, v in value.items()]
        else:
            rows.append([key, value, unit])
    figures.table(["figure", "value", "unit"], rows, numeric={1})
    shown = Section("Pictures")
    shown.pictures([(study.description, picture)])
    what = Section("What was run")
    what.table(["", ""], [["study", name], ["sewfmu", VERSION]])
    write(path, f"sewfmu: {name}", study.description, [figures, shown, what])


def sweep_report(path: Path, scenario, rows: list[dict], swept: list[str],
                 picture: Path | None) -> None:
    what = Section("What was run")
    failed = sum(1 for r in rows if r["status"] != "ok")
    what.table(["", ""], [["scenario", scenario.name], ["file", scenario.source],
                          ["master", scenario.master], ["step", f"{scenario.step:g} s"],
                          ["swept", ", ".join(swept)], ["points", len(rows)],
                          ["failed", failed]])
    table = Section("Points")
    columns = ["index", *swept, "status"]
    columns += [k for k in rows[0] if k not in columns and k not in ("key", "error")]
    units = {"stop_time": "s", "wall_time_s": "s", **scenario.figure_units()}
    table.table([f"{c} [{units[c]}]" if units.get(c) and c not in swept else c
                 for c in columns] + ["error"],
                [[r.get(c) for c in columns] + [r.get("error", "")] for r in rows],
                numeric=set(range(len(columns))) - {columns.index("status")},
                keep=1 + len(swept))
    sections = [what, table]
    if picture is not None and Path(picture).exists():
        shown = Section("Pictures")
        shown.pictures([("every figure against every swept parameter", picture)])
        sections.append(shown)
    write(path, f"sewfmu sweep: {scenario.name}", scenario.description, sections)
