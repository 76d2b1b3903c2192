"""Pictures: each mechanism's animation has its frames and draws the recorded run where the run
put it; report.html is self-contained, says what the run gave, and renders in headless Chromium."""
import json
import math
import re
import shutil
import subprocess

import numpy as np
import pytest
from PIL import Image

from sewfmu.cli import main
from sewfmu.components.feed import FeedLinkage
from sewfmu.components.punch_linkage import PunchLinkage
from sewfmu.components.takeup import TakeupLinkage
from sewfmu.scenarios.format.loader import catalogue, load
from sewfmu.scenarios.mechanisms import mechanism
from sewfmu.scenarios.mechanisms.animation import FRAMES, animate
from sewfmu.scenarios.runs.runner import simulate

pytestmark = [pytest.mark.slow]

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
needs_chromium = pytest.mark.skipif(
    CHROMIUM is None, reason="headless Chromium is not installed (Debian: apt-get install "
                             "chromium; .ci/run installs it)")


@pytest.fixture(autouse=True)
def _fmus(fmu_dir, monkeypatch):
    monkeypatch.setenv("SEWFMU_FMU_DIR", str(fmu_dir))


def _recorded_point(scenario: str, result, i: int) -> tuple[float, float]:
    """The marked point of each animation, in mm, from the recorded columns alone (the punch's
    height is drawn from the fabric surface, so only its differences are absolute)."""
    col = result.columns
    if scenario == "feed":
        return col["feed.M_x"][i] * 1e3, col["feed.M_y"][i] * 1e3
    if scenario == "takeup":
        return col["takeup.E_z"][i] * 1e3, col["takeup.E_x"][i] * 1e3
    if scenario == "carriage_startstop":
        return col["drive.x"][i] * 1e3, 0.0
    if scenario == "punch_split":
        return 0.0, col["body.y"][i] * 1e3
    return 0.0, col["punch.y"][i] * 1e3


def _red_centre(frame: Image.Image) -> tuple[float, float]:
    rgb = np.asarray(frame.convert("RGB")).astype(int)
    red = (rgb[..., 0] > 200) & (rgb[..., 1] < 70) & (rgb[..., 2] < 70)
    rows, cols = np.nonzero(red)
    assert len(rows) > 5, "no red marker in the frame"
    return float(cols.mean()), float(rows.mean())


def _one_scenario_per_animated_mechanism() -> list[str]:
    """The first catalogue scenario of every mechanism whose descriptor names an animation."""
    chosen = {}
    for name in sorted(catalogue()):
        analysis = load(name).analysis
        if analysis and mechanism(analysis).animated and analysis not in chosen \
                and not load(name).study:       # a study is computed: nothing moves
            chosen[analysis] = name
    return sorted(chosen.values())


@pytest.mark.parametrize("name", _one_scenario_per_animated_mechanism())
def test_the_animation_shows_the_recorded_run(tmp_path, name):
    result = simulate(load(name))
    anim = animate(result, tmp_path / f"{name}.gif")
    assert anim.path.stat().st_size < 2 * 1024 * 1024
    gif = Image.open(anim.path)
    assert gif.n_frames == len(anim.samples) == FRAMES >= 24
    # the frames are recorded samples spread over the last revolution, in order
    phi = result.columns["shaft.phi"]
    step = np.diff(phi[anim.samples])
    assert phi[anim.samples[0]] >= phi[-1] - 2 * math.pi - 1e-9
    assert np.all(step >= 0)
    if result.scenario.master != "adaptive":      # uniform samples: frames every 10°
        assert np.all(step > 0) and np.ptp(step) < 0.2 * step.mean()
    for k in (0, 9, 18, 27):
        i = anim.samples[k]
        x, y = _recorded_point(name, result, i)
        if name.startswith("punch"):    # the drawing's fabric surface is the punch's y = 0
            y += anim.tracked[0][1] - _recorded_point(name, result, anim.samples[0])[1]
        assert anim.tracked[k] == pytest.approx((x, y), abs=1e-9)
        gif.seek(k)
        col, row = _red_centre(gif)
        want_col, want_row = anim.pixel(x, y)
        assert abs(col - want_col) < 2.5 and abs(row - want_row) < 2.5, (k, col, row, want_col,
                                                                         want_row)


def test_the_linkages_drawn_agree_with_the_recorded_points():
    """The joints in a frame come from the linkage model at the recorded crank angle; they meet
    the points the FMUs recorded (M, E, the slider's ξ)."""
    for name, model_of, check in (
            ("feed", lambda r: FeedLinkage(),
             lambda m, r, i: (m.motion(r["shaft.phi"][i]).joints["M"].x, r["feed.M_x"][i])),
            ("takeup", lambda r: TakeupLinkage(),
             lambda m, r, i: (m.motion(r["shaft.phi"][i]).E.y, r["takeup.E_x"][i])),
            ("punch_drive", lambda r: PunchLinkage(),
             lambda m, r, i: (m.slider(m.alpha0 - r["shaft.phi"][i], 0, 0).y - m.y_top
                              + m.p.xi0, r["linkage.xi"][i]))):
        result = simulate(load(name))
        model = model_of(result)
        for i in np.linspace(0, len(result.time) - 1, 7).astype(int):
            drawn, recorded = check(model, result.columns, i)
            assert drawn == pytest.approx(recorded, abs=1e-12), name


def test_animate_is_refused_for_a_study(capsys, tmp_path):
    assert main(["run", "feed_ratio", "--animate", "--out", str(tmp_path / "o")]) == 1
    assert "animate: the study feed_ratio is computed" in capsys.readouterr().err


def _self_contained(page: str) -> None:
    assert "<script" not in page.lower()
    links = re.findall(r"""(?:src|href)\s*=\s*["']([^"']*)""", page, re.I)
    assert links and all(link.startswith("data:") for link in links), links
    assert "url(" not in page and "@import" not in page


def test_a_run_report_is_self_contained_with_figures_pictures_and_provenance(tmp_path):
    out = tmp_path / "run"
    assert main(["run", "punch_drive", "--report", "--out", str(out)]) == 0
    page = (out / "report.html").read_text(encoding="utf-8")
    _self_contained(page)
    summary = json.loads((out / "summary.json").read_text())
    for key in ("F2_weld_mean", "contact_onset_deg", "F2_peak"):
        assert key in page and f"{summary[key]:.6g}" in page
    assert page.count('src="data:image/png;base64,') == 1
    assert page.count('src="data:image/gif;base64,') == 1
    assert "monolithic" in page and "c3" in page and summary["provenance"]["sewfmu"] in page
    assert (out / "punch_drive.gif").exists()


def _chromium(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu",
                           "--hide-scrollbars", *args], capture_output=True, text=True,
                          timeout=120)


@needs_chromium
def test_the_report_renders_in_headless_chromium_on_a_phone_and_a_wide_screen(tmp_path):
    out = tmp_path / "run"
    assert main(["run", "takeup", "--report", "--out", str(out)]) == 0
    url = (out / "report.html").resolve().as_uri()
    dom = _chromium("--dump-dom", url).stdout
    summary = json.loads((out / "summary.json").read_text())
    text = re.sub(r"<[^>]+>", " ", dom)
    assert f"{summary['stroke_mm']:.6g}" in text and "stroke_mm" in text
    for width, height in ((390, 2400), (1280, 1800)):
        shot = tmp_path / f"shot_{width}.png"
        _chromium(f"--screenshot={shot}", f"--window-size={width},{height}", url)
        image = np.asarray(Image.open(shot).convert("RGB"))
        assert image.shape[1] == width
        # the page drew something: text, tables and pictures, not a blank or an error page
        assert len(np.unique(image.reshape(-1, 3), axis=0)) > 200
        # the pictures are drawn (the animation's pale blue coupler triangle shows)
        blue = (abs(image[..., 0].astype(int) - 0xbd) < 25) & (abs(image[..., 2].astype(int)
                                                                  - 0xd8) < 25)
        assert blue.sum() > 200


def test_study_and_sweep_reports(tmp_path):
    study = tmp_path / "study"
    assert main(["run", "takeup_tolerance", "--report", "--out", str(study)]) == 0
    page = (study / "report.html").read_text(encoding="utf-8")
    _self_contained(page)
    headline = json.loads((study / "summary.json").read_text())
    assert f"{headline['nominal_stroke_mm']:.6g}" in page
    sweep = tmp_path / "sweep"
    assert main(["sweep", "punch_drive", "--grid", "shaft.omega0=100,200", "--set",
                 "experiment.revolutions=2", "--quiet", "--workers", "2", "--report",
                 "--out", str(sweep)]) == 0
    page = (sweep / "report.html").read_text(encoding="utf-8")
    _self_contained(page)
    assert "shaft.omega0" in page and "F2_weld_mean [N]" in page
    assert page.count("data:image/png;base64,") == 1


# Lays the report out in a frame of the given width (headless Chromium's window is at least
# 500 px wide, so a phone's 390 px is a frame inside it) and lists every table cell that does not
# lie wholly on the screen or inside the box that holds its table (a part scrolled out of sight).
_PROBE = """<!DOCTYPE html><html><body style="margin:0">
<iframe id="frame" style="border:0" width="{width}" height="3000" srcdoc="{page}"></iframe>
<script>
document.getElementById('frame').addEventListener('load', () => {{
  const doc = document.getElementById('frame').contentDocument;
  const width = doc.documentElement.clientWidth, hidden = [];
  for (const cell of doc.querySelectorAll('td, th')) {{
    const r = cell.getBoundingClientRect(), box = cell.closest('.scroll').getBoundingClientRect();
    if (r.width === 0 && r.height === 0) continue;           // a header row hidden on purpose
    if (r.left < -0.5 || r.right > Math.min(width, box.right) + 0.5)
      hidden.push(cell.textContent.slice(0, 30));
  }}
  const page = doc.documentElement.scrollWidth > width ? 'page scrolls sideways' : '';
  document.body.setAttribute('data-hidden', JSON.stringify({{width, page, hidden}}));
}});
</script></body></html>"""


def _hidden_cells(page, width: int, tmp_path) -> dict:
    import html as markup

    probe = tmp_path / f"probe_{width}_{page.parent.name}.html"
    probe.write_text(_PROBE.format(width=width, page=markup.escape(
        page.read_text(encoding="utf-8"), quote=True)), encoding="utf-8")
    dom = _chromium(f"--window-size={max(width, 500) + 40},2000", "--virtual-time-budget=5000",
                    "--dump-dom", probe.as_uri()).stdout
    found = re.search(r'data-hidden="([^"]*)"', dom)
    assert found, dom[-2000:]
    return json.loads(markup.unescape(found.group(1)))


@needs_chromium
def test_every_value_of_a_report_is_visible_on_a_phone_and_a_wide_screen(tmp_path):
    """390 px (a phone) and 1280 px: no table cell hides beyond the screen or in a box that
    scrolls sideways, for a run with three overlaid runs and a sweep over three parameters (16
    columns: the F2 figures came last and were hidden at 1280 px)."""
    run = tmp_path / "run"
    assert main(["run", "punch_speed", "--set", "experiment.revolutions=2", "--report",
                 "--out", str(run)]) == 0
    sweep = tmp_path / "sweep"
    assert main(["sweep", "punch_drive", "--grid", "shaft.omega0=100,300", "--grid",
                 "punch.F30=5,10", "--grid", "punch.c2=1e5,2e5", "--set",
                 "experiment.revolutions=2", "--quiet", "--workers", "2", "--report",
                 "--out", str(sweep)]) == 0
    for page in (run / "report.html", sweep / "report.html"):
        for width in (390, 1280):
            seen = _hidden_cells(page, width, tmp_path)
            assert seen["width"] == width
            assert not seen["page"] and not seen["hidden"], (page.parent.name, width, seen)
    text = (sweep / "report.html").read_text(encoding="utf-8")
    assert "F2_weld_mean [N]" in text and "F2_peak [N]" in text
