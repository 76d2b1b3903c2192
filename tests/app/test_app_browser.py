"""`sewfmu app` in a real browser (headless Chromium through selenium): a value set and run gives
the figures sewfmu.run gives with that value; a value with its unit; a bad value is the alert's
one line and the next good run runs; two tabs at once keep their own runs; Cancel; a phone's
width; the sweep panel; SIGTERM ends the server and every run's process. The server runs as a
subprocess on a free port. Slow: left out of the fast loop. The screenshots in docs/app.md are
taken here (SEWFMU_APP_PICTURES=docs writes them into docs/)."""
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

import sewfmu
from tests.processes import processes_in

pytestmark = pytest.mark.slow
webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed "
                                "(pip install -e '.[test]')")
pytest.importorskip("dash", reason="the extra app is not installed (pip install -e '.[app]')")
from selenium.common.exceptions import WebDriverException  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402

from tests.paths import REPO  # noqa: E402

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
DRIVER = shutil.which("chromedriver")
DOCS = REPO / "docs"
WAIT = 120            # s: generous; the conditions are waited for, never timed
SHORT = "2"           # experiment.revolutions of the runs here


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_server(tmp: Path, *args):
    """`sewfmu app` in a session of its own, its temporary folder under tmp; (process, url)."""
    env = {**os.environ, "TMPDIR": str(tmp)}
    process = subprocess.Popen([sys.executable, "-m", "sewfmu", "app", "--port",
                                str(_free_port()), *args], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, env=env,
                               start_new_session=True)
    line = process.stdout.readline()
    found = re.search(r"http://\S+", line)
    if not found:
        process.kill()
        pytest.fail(f"sewfmu app did not start: {line}{process.stderr.read()}")
    return process, found.group(0)


def stop_server(process) -> int:
    if process.poll() is None:
        process.send_signal(signal.SIGTERM)
    try:
        return process.wait(60)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        raise


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    process, url = start_server(tmp_path_factory.mktemp("app"))
    yield url
    assert stop_server(process) == 0


@pytest.fixture(scope="module")
def browser():
    if not CHROMIUM or not DRIVER:
        pytest.skip("headless Chromium and its driver are not installed (Debian: apt-get "
                    "install chromium chromium-driver; .ci/run does it)")
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                "--window-size=1280,1000", "--hide-scrollbars"):
        options.add_argument(arg)
    try:
        driver = webdriver.Chrome(service=webdriver.ChromeService(DRIVER), options=options)
    except WebDriverException as err:
        pytest.skip(f"Chromium does not start here: {err.msg}")
    yield driver
    driver.quit()


@pytest.fixture
def page(browser, server):
    browser.set_window_size(1280, 1000)
    browser.get(f"{server}?scenario=punch_drive")
    value_input(browser, "punch.c2")
    return browser


def wait(driver, condition, timeout=WAIT):
    return WebDriverWait(driver, timeout, poll_frequency=0.1).until(lambda d: condition())


def value_input(driver, name):
    return wait(driver, lambda: driver.find_element(By.CSS_SELECTOR, f'input[aria-label="{name}"]'))


def type_value(driver, name, text):
    field = value_input(driver, name)
    field.send_keys(Keys.CONTROL, "a")
    field.send_keys(Keys.BACKSPACE)
    field.send_keys(text)
    wait(driver, lambda: field.get_attribute("value") == text)


def rows(driver):
    return driver.find_elements(By.CSS_SELECTOR, "tr[data-run]")


def run_and_wait(driver, count_before):
    """Run; wait for the run's row in the table (or a new alert)."""
    said = alert(driver)
    driver.find_element(By.ID, "run").click()
    wait(driver, lambda: len(rows(driver)) > count_before or alert(driver) not in ("", said))
    assert len(rows(driver)) > count_before, alert(driver)


def alert(driver) -> str:
    return driver.find_element(By.CSS_SELECTOR, '#alert[role="alert"]').text.strip()


def figures(driver) -> dict[str, str]:
    return {e.get_attribute("data-figure"): e.text
            for e in driver.find_elements(By.CSS_SELECTOR, "[data-figure]")}


def shown(value, unit):
    """A key figure as the page writes it: the number, then the unit."""
    text = f"{value:.6g}" if isinstance(value, float) else str(value)
    return text if unit in ("", "1") else f"{text} {unit}"


def assert_figures_are_the_api_s(driver, values):
    want = sewfmu.run("punch_drive", set=values)
    got = figures(driver)
    for name in ("F2_peak", "F2_weld_mean", "contact_onset_deg", "contact_loss_deg",
                 "n_contacts"):
        assert got[name] == shown(want.figures[name], want.units[name]), name


def test_a_value_set_and_run_gives_the_api_s_figures_and_the_mechanism_moves(page):
    type_value(page, "experiment.revolutions", SHORT)
    type_value(page, "shaft.omega0", "300")
    run_and_wait(page, 0)
    assert_figures_are_the_api_s(page, {"experiment.revolutions": 2, "shaft.omega0": 300.0})
    assert page.find_element(By.CSS_SELECTOR, '[data-view="plot"] .js-plotly-plot')
    assert page.find_element(By.CSS_SELECTOR, '[data-view="animation"] .js-plotly-plot')
    title = "return document.querySelector('#mechanism .js-plotly-plot').layout.title.text"
    first_title = page.execute_script(title)
    cursor = "return document.querySelector('#plot .js-plotly-plot').layout.shapes[0].x0"
    before = page.execute_script(cursor)
    page.find_element(By.ID, "play").click()
    wait(page, lambda: page.execute_script(cursor) != before)
    wait(page, lambda: page.execute_script(title) != first_title)
    page.find_element(By.ID, "play").click()
    links = {a.text for a in page.find_elements(By.CSS_SELECTOR, "tr[data-run] a")}
    assert {"results.csv", "summary.json", "scenario.toml", "command.txt"} <= links
    command = page.find_element(By.CSS_SELECTOR, "tr[data-run] code").text
    assert command == ("sewfmu run punch_drive --set experiment.revolutions=2 "
                       "--set shaft.omega0=300") or "shaft.omega0=300" in command


def test_a_value_with_its_unit(page):
    type_value(page, "experiment.revolutions", SHORT)
    type_value(page, "shaft.omega0", "955 rpm")
    run_and_wait(page, 0)
    assert_figures_are_the_api_s(page, {"experiment.revolutions": 2, "shaft.omega0": "955 rpm"})


def test_a_bad_value_is_one_line_and_nothing_runs_then_the_next_good_run_runs(page):
    type_value(page, "experiment.revolutions", SHORT)
    type_value(page, "shaft.omega0", "fast")
    page.find_element(By.ID, "run").click()
    wait(page, lambda: alert(page))
    assert "shaft.omega0" in alert(page) and "\n" not in alert(page)
    assert rows(page) == []
    type_value(page, "shaft.omega0", "200")
    run_and_wait(page, 0)
    assert alert(page) == ""
    assert_figures_are_the_api_s(page, {"experiment.revolutions": 2, "shaft.omega0": 200.0})


def test_two_tabs_running_at_once_keep_their_own_runs(page, server):
    first = page.current_window_handle
    type_value(page, "experiment.revolutions", SHORT)
    type_value(page, "shaft.omega0", "120")
    page.switch_to.new_window("tab")
    second = page.current_window_handle
    page.get(f"{server}?scenario=punch_drive")
    type_value(page, "experiment.revolutions", SHORT)
    type_value(page, "shaft.omega0", "280")
    page.find_element(By.ID, "run").click()
    page.switch_to.window(first)
    page.find_element(By.ID, "run").click()
    for handle, omega in ((first, 120.0), (second, 280.0)):
        page.switch_to.window(handle)
        wait(page, lambda: len(rows(page)) == 1)
        assert_figures_are_the_api_s(page, {"experiment.revolutions": 2, "shaft.omega0": omega})
        assert len(rows(page)) == 1
    page.switch_to.window(second)
    page.close()
    page.switch_to.window(first)


def test_cancel_ends_the_run(page):
    type_value(page, "experiment.revolutions", "2000")
    page.find_element(By.ID, "run").click()
    status = page.find_element(By.ID, "status")
    wait(page, lambda: "%" in status.text and not status.text.endswith(" 0 %"))
    page.find_element(By.ID, "cancel").click()
    wait(page, lambda: status.text == "cancelled")
    assert rows(page) == [] and alert(page) == ""
    type_value(page, "experiment.revolutions", SHORT)
    run_and_wait(page, 0)


@pytest.mark.parametrize("width, name", [(390, "phone"), (1280, "desktop")])
def test_nothing_scrolls_sideways(browser, server, width, name, tmp_path):
    browser.set_window_size(width, 1000 if width > 500 else 844)
    browser.get(f"{server}?scenario=punch_drive")
    type_value(browser, "experiment.revolutions", SHORT)
    run_and_wait(browser, 0)
    if name == "desktop":               # two runs overlaid in the picture
        type_value(browser, "shaft.omega0", "200")
        run_and_wait(browser, 1)
    wide = browser.execute_script("return [document.documentElement.scrollWidth, "
                                  "window.innerWidth]")
    assert wide[0] <= wide[1], wide
    # the picture for docs/app.md: every run drawn (two series each), the parts below the values
    traces = "return document.querySelector('#plot .js-plotly-plot').data.length"
    wait(browser, lambda: browser.execute_script(traces) == 2 * len(rows(browser)))
    browser.find_element(By.TAG_NAME, "summary").click()        # the values folded away
    if name == "desktop":
        high = browser.execute_script("return document.documentElement.scrollHeight")
        browser.set_window_size(width, min(high + 140, 2000))
    browser.execute_script("document.getElementById('status').scrollIntoView()")
    time.sleep(1.0)                     # the plots redrawn to the new size before the picture
    # SEWFMU_APP_PICTURES=docs: the pictures of docs/app.md, taken anew
    folder = DOCS if os.environ.get("SEWFMU_APP_PICTURES") == "docs" else tmp_path
    assert browser.save_screenshot(str(folder / f"app_{name}.png"))


def choose(driver, dropdown_id, text):
    """Pick an option of a dcc.Dropdown: open it, click the option."""
    box = wait(driver, lambda: driver.find_element(By.ID, dropdown_id))
    box.click()
    option = wait(driver, lambda: next((o for o in driver.find_elements(
        By.CSS_SELECTOR, '[role="option"]') if o.text.strip() == text), None))
    option.click()
    wait(driver, lambda: text in driver.find_element(By.ID, dropdown_id).text)
    driver.find_element(By.TAG_NAME, "h1").click()          # closed again


def test_the_sweep_panel_plots_a_figure_against_a_value(page):
    type_value(page, "experiment.revolutions", SHORT)
    choose(page, "sweep-param", "shaft.omega0")
    for field, text in (("sweep.from", "100"), ("sweep.to", "300"), ("sweep.points", "3")):
        type_value(page, field, text)
    page.find_element(By.ID, "sweep-run").click()
    status = page.find_element(By.ID, "sweep-status")
    wait(page, lambda: status.text.startswith("3 points") or
         page.find_element(By.ID, "sweep-alert").text)
    assert status.text == "3 points, 0 failed", page.find_element(By.ID, "sweep-alert").text
    choose(page, "sweep-figure", "F2_weld_mean")
    plot = "return document.querySelector('#sweep-plot .js-plotly-plot')"
    data = plot + ".data[0]"
    wait(page, lambda: "F2_weld_mean" in page.execute_script(plot + ".layout.yaxis.title.text"))
    trace = page.execute_script(data)
    assert trace["x"] == [100.0, 200.0, 300.0]
    want = sewfmu.run("punch_drive", set={"experiment.revolutions": 2, "shaft.omega0": 200.0})
    assert trace["y"][1] == pytest.approx(want.figures["F2_weld_mean"], rel=1e-9)


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux's /proc")
def test_sigterm_ends_the_server_and_every_run(browser, tmp_path):
    process, url = start_server(tmp_path)
    try:
        browser.set_window_size(1280, 1000)
        browser.get(f"{url}?scenario=punch_drive")
        type_value(browser, "experiment.revolutions", "2000")
        browser.find_element(By.ID, "run").click()
        status = browser.find_element(By.ID, "status")
        wait(browser, lambda: "%" in status.text)
        assert len(processes_in("session", process.pid)) >= 2          # the server and the run's process
    finally:
        code = stop_server(process)
    assert code == 0, process.stderr.read()
    # the tab outlives the server: it says so, not a progress bar standing still
    wait(browser, lambda: "server does not answer" in alert(browser))
    # the fork server and multiprocessing's resource tracker end when they read the end of
    # their pipes: after the server, soon
    end = time.monotonic() + 30
    while [pid for pid in processes_in("session", process.pid) if pid != process.pid] and \
            time.monotonic() < end:
        time.sleep(0.2)
    left = {pid: Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ")[:120]
            for pid in processes_in("session", process.pid) if pid != process.pid}
    assert not left, left
    assert not list(tmp_path.glob("sewfmu_app_*")), "the results folder was left behind"


def test_the_server_serves_a_run_s_own_files_and_nothing_else(page, server):
    import urllib.error
    import urllib.request

    type_value(page, "experiment.revolutions", SHORT)
    run_and_wait(page, 0)
    links = {a.text: a.get_attribute("href") for a in
             page.find_elements(By.CSS_SELECTOR, "tr[data-run] a")}
    with urllib.request.urlopen(links["command.txt"]) as answer:
        assert answer.read().decode().strip() == "sewfmu run punch_drive --set " \
                                                 "experiment.revolutions=2"
    with urllib.request.urlopen(links["scenario.toml"]) as answer:
        assert "revolutions = 2" in answer.read().decode()
    with urllib.request.urlopen(links["report.html"]) as answer:      # made when asked for
        assert "report.html" in answer.read().decode()
    run_id = links["results.csv"].rstrip("/").split("/")[-2]
    for path in (f"runs/{run_id}/punch_drive.png", f"runs/{run_id}/%2e%2e",
                 "runs/0123456789abcdef/results.csv", f"runs/{run_id[:-1]}/results.csv"):
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(server + path)
        assert refused.value.code == 404, path
    # a path with a slash in a part (/runs/../.., ..%2f) is no file's route: 404 too, not the page
    for path in ("runs/../../etc/passwd", f"runs/{run_id}/..%2fsummary.json",
                 f"runs/{run_id}/results.csv/x", f"runs/{run_id}/"):
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(server + path)
        body = refused.value.read().decode()
        assert refused.value.code == 404, path
        assert "root:" not in body and "F2_peak" not in body and "_dash-" not in body, path
