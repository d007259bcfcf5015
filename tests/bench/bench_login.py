"""Benchmark of an operator's log-in to the answer (not a test: run it by hand).

    .venv/bin/python tests/bench/bench_login.py [--runs 5]

A station on the shipped rotor types whose archive has one operator account; per run, in
a headless Chromium with no session: the log-in form sent (account and password) at
t0; the Start screen; the serial typed; Start measuring clicked; the Correct screen's
offer ("Go to the correction") seen, the page read every 20 ms.  The median and worst of
log-in -> answer, and of the part before the click on Start (the log-in itself: the
argon2 check, the page, the form), against the demo's physics (2.0 s of revolutions).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "helpers"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "station"))

from accounts import with_accounts


def one(base: str, driver: object) -> tuple[float, float]:
    """(log-in -> answer, log-in -> Start clicked) [s]."""
    from selenium.webdriver.common.by import By
    from test_station_browser import _button, _see, _type

    d: object = driver
    d.delete_all_cookies()  # type: ignore[attr-defined]
    d.get(base + "/")  # type: ignore[attr-defined]
    _see(d, "Log in")
    time.sleep(0.5)  # the form mounted
    t0 = time.monotonic()
    d.execute_script(  # type: ignore[attr-defined]
        "const f = document.querySelector('form.login'); f.account.value = 'kim';"
        "f.password.value = 'a-long-password'; f.submit();"
    )
    _see(d, "New rotor")
    _type(d, "serial number", f"L-{time.monotonic_ns()}")
    _button(d, "Start measuring").click()
    started = time.monotonic() - t0
    while time.monotonic() - t0 < 60:
        body = d.find_element(By.TAG_NAME, "body").text.lower()  # type: ignore[attr-defined]
        if "go to the correction" in body:
            return time.monotonic() - t0, started
        time.sleep(0.02)
    raise AssertionError("no answer within 60 s")


def main() -> None:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from test_station_browser import served

    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=5)
    n = ap.parse_args().runs
    options = webdriver.ChromeOptions()
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage"):
        options.add_argument(arg)
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        (tmp / "pw").write_text("a-long-password\n")
        url = f"sqlite:///{tmp / 'a.sqlite'}"
        with_accounts(url, ("kim", "operator", "a-long-password"))
        driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
        got = []
        with served(tmp) as base:
            for _ in range(n):
                got.append(one(base, driver))
                print(
                    f"  log-in -> answer {got[-1][0]:.2f} s (Start clicked at {got[-1][1]:.2f} s)"
                )
        driver.quit()
    total, before = [g[0] for g in got], [g[1] for g in got]
    print(
        f"log-in -> the correction offered: median {statistics.median(total):.2f} s, worst "
        f"{max(total):.2f} s of {n}; of it log-in -> Start clicked median "
        f"{statistics.median(before):.2f} s, worst {max(before):.2f} s (the physics: 2.0 s)"
    )


if __name__ == "__main__":
    main()
