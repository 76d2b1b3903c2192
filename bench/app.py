"""`sewfmu app`'s speed, as the issue asks it: the default punch drive from clicking Run to its
figures on the page, beside `sewfmu.run` in a warm process; and the page's first load (to its
loaded document and to its value inputs shown). Headless Chromium through selenium, the server
a subprocess on a free port.

    .venv/bin/python bench/app.py [--repeat 3]
"""
import argparse
import re
import signal
import socket
import statistics
import subprocess
import sys
import time

from selenium import webdriver
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

import sewfmu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    sewfmu.run("punch_drive")                                    # warm: FMUs extracted, loaded
    api = []
    for _ in range(args.repeat):
        start = time.perf_counter()
        sewfmu.run("punch_drive")
        api.append(time.perf_counter() - start)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    server = subprocess.Popen([sys.executable, "-m", "sewfmu", "app", "--port", str(port)],
                              stdout=subprocess.PIPE, text=True)
    url = re.search(r"http://\S+", server.stdout.readline()).group(0)
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                "--window-size=1280,1000"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=webdriver.ChromeService("/usr/bin/chromedriver"),
                              options=options)
    wait = WebDriverWait(driver, 300, poll_frequency=0.02)
    try:
        loads, shown, page, job = [], [], [], []
        for k in range(args.repeat + 1):
            start = time.perf_counter()
            driver.get(url)
            wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, 'input[aria-label="punch.c2"]'))
            shown.append(time.perf_counter() - start)
            loads.append(driver.execute_script(
                "return performance.getEntriesByType('navigation')[0].loadEventEnd") / 1e3)
            start = time.perf_counter()
            driver.find_element(By.ID, "run").click()
            wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "tr[data-run]"))
            page.append(time.perf_counter() - start)
            status = driver.find_element(By.ID, "status").text         # "done in 1.2 s"
            job.append(float(re.search(r"done in ([0-9.]+) s", status).group(1)))
        # the first of each: the server's own first use (its fork server, the FMUs' extraction)
        print(f"sewfmu.run('punch_drive'), warm process: {statistics.median(api):.2f} s "
              f"(median of {len(api)})")
        print(f"the page, Run clicked to figures:        {statistics.median(page[1:]):.2f} s "
              f"(median of {len(page) - 1}; the very first {page[0]:.2f} s), "
              f"{statistics.median(page[1:]) / statistics.median(api):.2f} x")
        print(f"  of which the run's process, started to its figures sent: "
              f"{statistics.median(job[1:]):.2f} s")
        print(f"the page's first load: document {statistics.median(loads[1:]):.2f} s, "
              f"its inputs shown {statistics.median(shown[1:]):.2f} s (the very first "
              f"{shown[0]:.2f} s)")
    finally:
        driver.quit()
        server.send_signal(signal.SIGTERM)
        server.wait(60)


if __name__ == "__main__":
    main()
