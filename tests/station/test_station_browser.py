"""The operator station in a real browser: ``stand station`` served as a user starts it,
driven by headless Chromium through Selenium (Debian's chromium and chromium-driver, which
``.ci/run`` installs).  Each screen is saved as a picture (``STAND_DOCS_SCREENSHOTS=1``
writes them into docs/ as well, where README shows them)."""

from __future__ import annotations

import datetime as dt
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import pytest
from accounts import change, with_accounts

ROOT = Path(__file__).resolve().parents[2]
MIN_TEXT_PX = 16.0
"""The smallest text the Correct screen may show [CSS px] (docs/operator.md)."""
TOKEN = "station-test-token-1234"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
DRIVER = shutil.which("chromedriver")

pytestmark = pytest.mark.skipif(
    CHROMIUM is None or DRIVER is None,
    reason="Chromium and its driver are not installed (Debian: apt-get install chromium "
    "chromium-driver)",
)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@contextmanager
def served(tmp_path: Path, *extra: str) -> Iterator[str]:
    """``stand station`` in a child process, as a user starts it; its address."""
    port = _free_port()
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_CURRENT_TEST"}
    env["XDG_DATA_HOME"] = str(tmp_path / "data")
    log = (tmp_path / "station.log").open("w")
    proc = subprocess.Popen(
        [sys.executable, "-m", "stand.cli", "station", "--no-browser", "--port", str(port),
         "--runs-dir", str(tmp_path / "runs"), "--archive", f"sqlite:///{tmp_path / 'a.sqlite'}",
         *extra],
        stdout=log, stderr=subprocess.STDOUT, env=env,
    )  # fmt: skip
    try:
        end = time.monotonic() + 30
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
                break
            except OSError:
                if proc.poll() is not None or time.monotonic() > end:
                    raise AssertionError((tmp_path / "station.log").read_text()) from None
                time.sleep(0.2)
        yield f"http://127.0.0.1:{port}"
    finally:
        proc.terminate()
        proc.wait(15)
        log.close()


def _button(driver: Any, text: str, timeout_s: float = 30.0) -> Any:
    """The visible button whose text is ``text``, once it is there."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    xpath = f"//button[normalize-space(.)='{text}']"

    def found(d: Any) -> Any:
        return next((b for b in d.find_elements(By.XPATH, xpath) if b.is_displayed()), None)

    return WebDriverWait(driver, timeout_s, 0.1).until(found, f"no button {text!r}")


def _see(driver: Any, text: str, timeout_s: float = 30.0) -> None:
    """Wait until the page shows ``text`` (a page that navigates meanwhile replaces its
    body: the stale body is looked at again)."""
    from selenium.common.exceptions import StaleElementReferenceException
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    WebDriverWait(
        driver, timeout_s, 0.1, ignored_exceptions=(StaleElementReferenceException,)
    ).until(lambda d: text in d.find_element(By.TAG_NAME, "body").text, f"never saw {text!r}")


def _type(driver: Any, label: str, text: str) -> None:
    from selenium.webdriver.common.by import By

    driver.find_element(By.CSS_SELECTOR, f'input[aria-label="{label}"]').send_keys(text)


TEXT_SIZES = """
const out = [];
for (const el of document.querySelectorAll('.q-page *')) {
  if (el.closest('svg') || el.offsetParent === null) continue;
  if ([...el.childNodes].some(n => n.nodeType === 3 && n.textContent.trim()))
    out.push([parseFloat(getComputedStyle(el).fontSize), el.textContent.trim().slice(0, 40)]);
}
for (const t of document.querySelectorAll('.q-page svg text')) {
  out.push([parseFloat(t.getAttribute('font-size')) * t.getScreenCTM().a,
            'face: ' + t.textContent]);
}
return out;
"""
"""Every text on the page with its rendered size [CSS px] (an SVG text's scaled by its
drawing's transform to the screen)."""


def _text_sizes(driver: Any) -> list[tuple[float, str]]:
    return [(float(a), str(b)) for a, b in driver.execute_script(TEXT_SIZES)]


def _evaluated(tmp_path: Path) -> dt.date:
    """A machine evaluation of the shipped rotor types' stand archived where ``served``
    archives (its figures as the demo's); its due date."""
    from stand.actions import archive_evaluation, os_actor
    from stand.config import load_config

    rotors = ROOT / "stand" / "data" / "rotors"
    stand = load_config(str(next(rotors.glob("*.toml"))))[0].stand.stand_id()
    due = dt.datetime.now(dt.UTC).date() + dt.timedelta(days=30)
    archive_evaluation(f"sqlite:///{tmp_path / 'a.sqlite'}", os_actor(), "machine", stand,
                       {"verdict": "pass"}, simulated=True, software="test", due=due)  # fmt: skip
    return due


def _shot(driver: Any, tmp_path: Path, name: str) -> None:
    driver.save_screenshot(str(tmp_path / f"station-{name}.png"))
    if os.environ.get("STAND_DOCS_SCREENSHOTS"):
        shutil.copy(tmp_path / f"station-{name}.png", ROOT / "docs" / f"station-{name}.png")


def _requests(driver: Any) -> list[str]:
    """Every address the browser asked for since the last call (Chrome's network log)."""
    urls = []
    for entry in driver.get_log("performance"):
        msg = json.loads(entry["message"])["message"]
        if msg["method"] == "Network.requestWillBeSent":
            urls.append(msg["params"]["request"]["url"])
        elif msg["method"] == "Network.webSocketCreated":
            urls.append(msg["params"]["url"])
    return urls


@pytest.mark.realtime
def test_a_rotor_balanced_through_the_screens_in_a_real_browser(
    browser: Any, tmp_path: Path
) -> None:
    """Start, measure, correct (applied on the simulated stand), check, certificate and
    history, as an operator clicks them; a second browser sees the same measurement and
    cannot start another."""
    from selenium.webdriver.common.by import By

    with served(tmp_path) as base:
        browser.get(base + "/")
        _see(browser, "New rotor")
        _type(browser, "serial number", "D-1")
        _type(browser, "order", "O-77")
        _type(browser, "operator", "kim")
        _shot(browser, tmp_path, "start")
        first = browser.current_window_handle
        browser.switch_to.new_window("window")  # a second browser on the same station,
        browser.get(base + "/")  # open before the first starts: its Start comes while the
        _see(browser, "New rotor")  # 2 s run goes on, however loaded the machine is
        second = browser.current_window_handle
        browser.switch_to.window(first)
        _button(browser, "Start measuring").click()
        _see(browser, "measuring D-1")
        browser.switch_to.window(second)
        _button(browser, "Start measuring").click()
        _see(browser, "the station is measuring the initial run of D-1 already")
        browser.close()
        browser.switch_to.window(first)
        _button(browser, "Go to the correction")
        _see(browser, "precise")
        _shot(browser, tmp_path, "measure")
        _button(browser, "Go to the correction").click()
        _see(browser, "in hole")
        _shot(browser, tmp_path, "correct")
        for width, height in ((1024, 768), (1280, 800)):  # readable at two metres
            browser.set_window_size(width, height)
            sizes = _text_sizes(browser)
            smallest = min(sizes)
            face = min(x for x in sizes if x[1].startswith("face: "))
            print(f"Correct screen at {width} x {height}: smallest text {smallest}, on the "
                  f"faces {face}")  # fmt: skip
            assert smallest[0] >= MIN_TEXT_PX, (width, smallest)
        browser.set_window_size(1400, 950)
        _button(browser, "Apply the correction (simulated stand)").click()
        _see(browser, "masses put on the simulated rotor")
        _button(browser, "Start the check run").click()
        _button(browser, "See the check").click()
        _see(browser, "D-1: WITHIN TOLERANCE")
        body = browser.find_element(By.TAG_NAME, "body").text
        assert body.count("PASS") == 2 and "%" in body
        _see(browser, "Open the certificate")  # the run is filed after the answer shows
        _shot(browser, tmp_path, "check")
        link = browser.find_element(By.LINK_TEXT, "Open the certificate").get_attribute("href")
        pdf = browser.find_element(By.LINK_TEXT, "as PDF").get_attribute("href")
        with urllib.request.urlopen(pdf, timeout=120) as got:  # printed by Chromium
            assert got.headers["content-type"] == "application/pdf"
            assert got.read(5) == b"%PDF-"
        browser.get(link)
        assert "D-1" in browser.find_element(By.TAG_NAME, "body").text
        due = _evaluated(tmp_path)  # a machine evaluation archived: History says when next
        browser.get(base + "/history")
        _see(browser, f"machine evaluation (ISO 21940-21) PASS on {dt.datetime.now(dt.UTC).date()}")
        _see(browser, f"next due {due}")
        _type(browser, "serial number", "D-1")
        _button(browser, "Search").click()
        _see(browser, "pass (check)")
        rows = browser.find_elements(By.CSS_SELECTOR, "tbody tr")
        assert len(rows) == 2 and all("D-1" in r.text for r in rows)
        browser.set_window_size(1280, 800)  # History on a 1280 px screen: no scrollbar
        browser.refresh()
        _type(browser, "serial number", "D-1")
        _button(browser, "Search").click()
        _see(browser, "pass (check)")
        _shot(browser, tmp_path, "history")
        heads = [h.text for h in browser.find_elements(By.CSS_SELECTOR, "thead th")]
        assert [h for h in heads if h][:2] == ["report", "run"], heads  # the report first
        wide, room = browser.execute_script(
            "const m = document.querySelector('.q-table__middle');"
            "return [m.scrollWidth, m.clientWidth];"
        )
        assert wide <= room, (wide, room)
        stamp = dt.datetime.now().astimezone().strftime("%Z")
        assert all(stamp in r.text for r in browser.find_elements(By.CSS_SELECTOR, "tbody tr"))
        browser.set_window_size(1400, 950)


@pytest.mark.realtime
def test_a_drilled_correction_through_the_screens(browser: Any, tmp_path: Path) -> None:
    """The demo auger corrected by drilling: the Correct screen gives each hole's drill, depth
    and angle, numbered in drilling order on the face; the simulated stand takes the holes
    out at their centres of mass, and the check run passes."""
    rotors = tmp_path / "rotors"
    rotors.mkdir()
    shutil.copy(ROOT / "stand" / "data" / "rotors" / "demo-auger-drilled.toml", rotors)
    with served(tmp_path, "--config-dir", str(rotors)) as base:
        browser.get(base + "/")
        _see(browser, "New rotor")
        _type(browser, "serial number", "H-1")
        _button(browser, "Start measuring").click()
        _button(browser, "Go to the correction").click()
        _see(browser, "DRILL Ø20 mm")
        _see(browser, "depth to the tip")
        _shot(browser, tmp_path, "correct-drill")
        _button(browser, "Apply the correction (simulated stand)").click()
        _see(browser, "masses put on the simulated rotor")
        _button(browser, "Start the check run").click()
        _button(browser, "See the check").click()
        _see(browser, "H-1: WITHIN TOLERANCE")
        from selenium.webdriver.common.by import By

        body = browser.find_element(By.TAG_NAME, "body").text
        urr = [float(x) for x in re.findall(r"(\d+\.\d) %", body)]  # the URR per plane
        assert body.count("PASS") == 2 and len(urr) >= 2 and min(urr) >= 95.0, body


def test_the_screens_load_nothing_from_outside_and_need_the_token(
    browser: Any, tmp_path: Path
) -> None:
    """With a token every request must carry it (typed once into the form, never in a
    URL, then the cookie, also on the websocket); every script, style and font comes from
    the station; the station's log never holds the token."""
    with served(tmp_path, "--token", TOKEN) as base:
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(base + f"/?token={TOKEN}", timeout=10)
        assert refused.value.code == 401
        from selenium.webdriver.common.by import By

        browser.get(base + "/")
        browser.find_element(By.NAME, "token").send_keys(TOKEN + "\n")
        _see(browser, "New rotor")
        for name in ("Measure", "Correct", "Check", "History", "Start"):
            _button(browser, name).click()
            time.sleep(0.5)
        _see(browser, "New rotor")
        browser.get(base + "/history")  # a new page load: the cookie alone lets it in
        _see(browser, "History")
        urls = _requests(browser)
        host = urlsplit(base).netloc
        outside = [u for u in urls if urlsplit(u).scheme not in ("data", "blob")
                   and urlsplit(u).netloc != host]  # fmt: skip
        assert len(urls) > 10 and not outside, outside
        assert any("/_nicegui_ws/" in u for u in urls)  # the page's socket, through the gate
    assert TOKEN not in (tmp_path / "station.log").read_text()


def _tab_to(driver: Any, what: str, timeout_s: float = 30.0) -> Any:
    """Press Tab until the focus is on the field labelled ``what`` or the button reading
    ``what`` (which may appear later: a run still being archived); that element.  Fails
    after ``timeout_s`` naming what the focus went through last."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.keys import Keys

    seen: list[str] = []
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        ActionChains(driver).send_keys(Keys.TAB).perform()
        el = driver.switch_to.active_element
        name = el.get_attribute("aria-label") or el.text.strip()
        seen = [*seen[-20:], name[:40]]
        if name.casefold() == what.casefold():  # buttons show their text in capitals
            return el
        time.sleep(0.02)
    raise AssertionError(f"Tab never reached {what!r}; it went last through {seen}")


@pytest.mark.realtime
def test_the_screens_work_from_the_keyboard_alone(browser: Any, tmp_path: Path) -> None:
    """Tab and Enter only: the start form filled and the run started, stopped by hand, on
    to the correction, back to the start (an operator without a mouse or touch screen)."""
    from selenium.webdriver.common.keys import Keys

    # a tolerance so tight the run is never precise: it goes on until stopped (or the 8 s
    # scene ends), so the test waits for states, not for a machine's speed
    strict = tmp_path / "rotors"
    strict.mkdir()
    text = (ROOT / "stand" / "data" / "rotors" / "demo-auger.toml").read_text()
    (strict / "demo-auger.toml").write_text(text.replace("grade_mm_s = 6.3", "grade_mm_s = 0.1"))
    with served(tmp_path, "--config-dir", str(strict)) as base:
        browser.get(base + "/")
        _see(browser, "New rotor")
        for label, text in (("serial number", "K-1"), ("order", "O-1"), ("operator", "lee")):
            _tab_to(browser, label).send_keys(text)
        _tab_to(browser, "Start measuring").send_keys(Keys.ENTER)
        _see(browser, "vibration at the supports")  # the first estimate: an answer to stop on
        _stop_on_screen(browser, "STOP")
        _tab_to(browser, "Stop").send_keys(Keys.ENTER)
        _tab_to(browser, "Go to the correction").send_keys(Keys.ENTER)
        _see(browser, "in hole")
        _tab_to(browser, "Start").send_keys(Keys.ENTER)  # the Start screen, from the top bar
        _see(browser, "New rotor")


@pytest.mark.realtime
def test_the_mes_job_fills_start_and_a_started_one_starts(browser: Any, tmp_path: Path) -> None:
    """A job order sent over OPC UA (asyncua as the MES) fills the Start screen within the
    screen's poll; one sent with StoreAndStart starts by itself; the run is archived under
    the job and the job is Running (or Ended, had the run passed)."""
    sys.path.insert(0, str(ROOT / "tests" / "helpers"))
    from mes import send_job

    from stand.archive import Archive
    from stand.archive.jobs import jobs_of
    from stand.archive.query import Filters, history
    from stand.config import load_config

    rotors = ROOT / "stand" / "data" / "rotors"
    stand = load_config(str(rotors / "demo-auger.toml"))[0].stand.stand_id()
    port = _free_port()
    with served(tmp_path, "--opcua", "--opcua-port", str(port)) as base:
        endpoint = f"opc.tcp://127.0.0.1:{port}/stand/"
        browser.get(base + "/")
        _see(browser, "New rotor")
        assert send_job(endpoint, "MES-7", "demo-auger-drilled", "SN-7", operator="ana") == 1
        _see(browser, "job order MES-7 from the MES")
        values = browser.execute_script(
            "return ['serial number', 'operator'].map(l => "
            'document.querySelector(`input[aria-label="${l}"]`).value)'
        )
        assert values == ["SN-7", "ana"]
        _see(browser, "demo-auger-drilled")
        _shot(browser, tmp_path, "start-job")
        assert send_job(endpoint, "MES-8", "demo-auger", "SN-8", start=True) == 1
        _see(browser, "measuring SN-8")  # started by itself: the MES asked for it
        _button(browser, "Go to the correction", 60).click()
        url = f"sqlite:///{tmp_path / 'a.sqlite'}"
        end = time.monotonic() + 60  # filed after the answer is shown: a hang guard
        while not (found := history(url, Filters(serial="SN-8"))) and time.monotonic() < end:
            time.sleep(0.2)
    with Archive(url) as archive:
        states = {j["job_id"]: j for j in jobs_of(archive, stand)}
    (run,) = found
    assert run["job"] == "MES-8" and states["MES-8"]["run_id"] == run["id"]
    assert states["MES-8"]["state"] == ("Ended" if run["verdict"] == "pass" else "Running")
    assert states["MES-7"]["state"] == "AllowedToStart"  # shown, never started


def _in_view(browser: Any, css: str) -> None:
    """Every element ``css`` names wholly inside the window at 1024 x 768 and 1280 x 800."""
    for width, height in ((1024, 768), (1280, 800)):
        browser.set_window_size(width, height)
        time.sleep(0.3)  # laid out again
        found = browser.execute_script(
            "return [...document.querySelectorAll(arguments[0])].map(e => "
            "[e.getBoundingClientRect().bottom, innerHeight, e.innerText]);", css)  # fmt: skip
        assert found and all(b <= h for b, h, _ in found), (css, width, found)
    browser.set_window_size(1400, 950)


def _apart(browser: Any, one: str, other: str) -> None:
    """The first elements ``one`` and ``other`` name do not overlap on the screen (once a
    note has slid in: Quasar animates it)."""
    time.sleep(0.8)
    a, b = browser.execute_script(
        "return [arguments[0], arguments[1]].map(c => { const r = document.querySelector(c)"
        ".getBoundingClientRect(); return [r.left, r.top, r.right, r.bottom]; });",
        one, other)  # fmt: skip
    assert a[2] <= b[0] or b[2] <= a[0] or a[3] <= b[1] or b[3] <= a[1], (a, b)


def _stop_on_screen(browser: Any, word: str) -> None:
    """The Stop button (its text ``word`` as shown) wholly inside the window at 1024 x 768
    and at 1280 x 800; the window back to its size after."""
    for width, height in ((1024, 768), (1280, 800)):
        browser.set_window_size(width, height)
        top, bottom, inner = browser.execute_script(
            "const b = [...document.querySelectorAll('button')].find("
            "x => x.innerText.trim().toUpperCase() === arguments[0]);"
            "const r = b.getBoundingClientRect(); return [r.top, r.bottom, innerHeight];",
            word,
        )
        assert 0 <= top and bottom <= inner, (word, width, height, top, bottom, inner)
    browser.set_window_size(1400, 950)


def _fetch(base: str, path: str, cookies: list[dict[str, Any]]) -> tuple[int, bytes]:
    """GET ``path`` with the browser's cookies: the status and the body."""
    jar = "; ".join(f"{c['name']}={c['value']}" for c in cookies)
    req = urllib.request.Request(base + path, headers={"Cookie": jar})
    try:
        with urllib.request.urlopen(req, timeout=120) as r:
            return r.status, r.read()
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read()


def _post(
    base: str, path: str, cookies: list[dict[str, Any]], form: dict[str, str]
) -> tuple[int, bytes]:
    """POST the form ``form`` to ``path`` with the browser's cookies: status and body."""
    import urllib.parse

    jar = "; ".join(f"{c['name']}={c['value']}" for c in cookies)
    req = urllib.request.Request(base + path, data=urllib.parse.urlencode(form).encode(),
                                 headers={"Cookie": jar}, method="POST")  # fmt: skip
    try:
        with urllib.request.urlopen(req, timeout=120) as r:
            return r.status, r.read()
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read()


def _log_in(browser: Any, account: str, password: str) -> None:
    """The log-in form filled and sent, once it is mounted (NiceGUI mounts the page after
    its first HTML: an element found before may go stale)."""
    from selenium.common.exceptions import StaleElementReferenceException
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    def fill(d: Any) -> bool:
        d.find_element(By.NAME, "account").clear()
        d.find_element(By.NAME, "account").send_keys(account)
        d.find_element(By.NAME, "password").send_keys(password + "\n")
        return True

    WebDriverWait(browser, 30, 0.2, ignored_exceptions=(StaleElementReferenceException,)).until(
        fill, "no log-in form"
    )


@pytest.mark.realtime
def test_accounts_log_in_their_rights_and_a_released_certificate(
    browser: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With accounts the station asks who works it; the operator is the account; an
    operator may measure but not release a certificate (403, saying why); a setter logs in
    with a badge and its PIN and releases it (badge and PIN again), bound to the run,
    signed and journaled (the station and this test's commands share the stand's data
    folder, so its keys: one stand)."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))  # the station's (served)
    from selenium.webdriver.common.by import By

    from stand.archive.audit import entries, file_sha256
    from stand.archive.query import Filters, history
    from stand.cli import main

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    (tmp_path / "pw").write_text("a-long-password\n")
    with_accounts(
        url,
        ("kim", "operator", "a-long-password"),
        ("ana", "setter", "a-long-password", "BADGE-0042", "8642"),
    )
    with served(tmp_path) as base:
        browser.get(base + "/")
        _see(browser, "Log in")
        _shot(browser, tmp_path, "login")
        _log_in(browser, "kim", "wrong-password")
        _see(browser, "wrong account, password, badge or PIN")
        _log_in(browser, "kim", "a-long-password")
        _see(browser, "kim (operator)")
        fixed = browser.execute_script(  # the operator is the account, not to be typed over
            "const i = document.querySelector('input[aria-label=\"operator\"]');"
            "return [i.value, i.readOnly];"
        )
        assert fixed == ["kim", True], fixed
        _type(browser, "serial number", "A-1")
        _button(browser, "Start measuring").click()
        _button(browser, "Go to the correction", 60).click()
        end = time.monotonic() + 60  # filed after the answer is shown: a hang guard
        while not (found := history(url, Filters(serial="A-1"))) and time.monotonic() < end:
            time.sleep(0.2)
        (run,) = found
        assert run["operator"] == "kim"
        status, body = _fetch(base, f"/report/{run['id']}/pdf", browser.get_cookies())
        assert status == 200 and body.startswith(b"%PDF"), body[:100]  # unsigned: every reader
        release = f"/report/{run['id']}/release"
        form = {"password": "a-long-password", "meaning": "released"}
        status, body = _post(base, release, browser.get_cookies(), form)
        assert status == 403 and b"kim (operator) may not release a certificate" in body, body
        _button(browser, "Log out").click()
        _see(browser, "Log in")
        time.sleep(0.5)  # the log-in page mounted (a scanner types into the field it finds)
        browser.find_element(By.NAME, "badge").send_keys("BADGE-0042\n")  # code, then Enter
        browser.switch_to.active_element.send_keys("8642\n")  # Enter moved on to the PIN
        _see(browser, "ana (setter)")
        _shot(browser, tmp_path, "who")
        status, body = _fetch(base, release, browser.get_cookies())
        assert status == 405, body  # a GET never signs
        status, body = _post(base, release, browser.get_cookies(), {"password": "a-long-password"})
        assert status == 400 and b"confirm the meaning" in body, body
        status, body = _post(base, release, browser.get_cookies(), {**form, "password": "guess"})
        assert status == 403 and b"ana: wrong password" in body, body
        by_badge = {"badge": "BADGE-0042", "pin": "8641", "meaning": "released"}
        status, body = _post(base, release, browser.get_cookies(), by_badge)
        assert status == 403 and b"ana: wrong badge or PIN" in body, body
        status, pdf = _post(base, release, browser.get_cookies(), {**by_badge, "pin": "8642"})
        assert status == 200 and pdf.startswith(b"%PDF"), pdf[:100]
    kept = tmp_path / "released.pdf"
    kept.write_bytes(pdf)
    (release,) = entries(url, action="release")
    assert release["who"] == "ana" and release["new_sha256"] == file_sha256(kept)
    assert release["old_sha256"] == run["file_sha256"]  # bound to the run
    assert main(["audit", "check", str(kept), "--archive", url]) == 0


@pytest.mark.realtime
def test_the_screens_in_the_accounts_language(browser: Any, tmp_path: Path) -> None:
    """An account in Ukrainian works the station in Ukrainian (Start, Measure, Correct);
    a lone stand started with --lang de speaks German; a certificate in another language
    than the screen's."""
    from stand.archive.query import Filters, history

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    (tmp_path / "pw").write_text("a-long-password\n")
    with_accounts(url, ("olena", "operator", "a-long-password"))
    change(url, "olena", language="uk")
    strict = tmp_path / "rotors"  # a grade no run proves: it measures until stopped
    strict.mkdir()
    text = (ROOT / "stand" / "data" / "rotors" / "demo-auger.toml").read_text()
    (strict / "demo-auger.toml").write_text(text.replace("grade_mm_s = 6.3", "grade_mm_s = 0.1"))
    with served(tmp_path, "--config-dir", str(strict)) as base:
        browser.get(base + "/")
        _see(browser, "Log in")
        _log_in(browser, "olena", "a-long-password")
        _see(browser, "Новий ротор")
        _stop_on_screen(browser, "ПОЧАТИ ВИМІРЮВАННЯ")  # the header leaves Start in view
        _button(browser, "Почати вимірювання").click()  # no serial: a note, in Ukrainian
        _see(browser, "спершу введіть серійний номер ротора")
        _apart(browser, ".q-notification", ".logout")  # the note leaves Log out free
        _type(browser, "серійний номер", "U-1")
        _button(browser, "Почати вимірювання").click()
        _see(browser, "вібрація опор")  # the first estimate, in Ukrainian
        _see(browser, "звуження інтервалу 95 % площини 1 до цілі")  # the engine's words too
        _stop_on_screen(browser, "СТОП")  # the longest header of the three leaves Stop in view
        _button(browser, "Стоп").click()
        _button(browser, "До корекції", 60).click()
        _see(browser, "Корекція U-1")
        _see(browser, "опорна мітка")
        _shot(browser, tmp_path, "correct-uk")
        _stop_on_screen(browser, "ПОЧАТИ КОНТРОЛЬНИЙ ПУСК")  # kept in view, at its foot
        _in_view(browser, ".instruction")  # every plane's instruction, without scrolling
        shown = browser.execute_script("return document.querySelector('.q-page').innerText")
        assert "г" in shown and not re.search(r"\d g\b|\bmm\b", shown), shown  # Cyrillic units
        end = time.monotonic() + 60  # filed after the answer is shown: a hang guard
        while not (found := history(url, Filters(serial="U-1"))) and time.monotonic() < end:
            time.sleep(0.2)
        (run,) = found  # the certificate in the customer's language, not the screen's
        status, page = _fetch(base, f"/report/{run['id']}?lang=de", browser.get_cookies())
        assert status == 200 and b'<html lang="de">' in page and b"Wuchtprotokoll" in page
        status, page = _fetch(base, f"/report/{run['id']}?lang=xx", browser.get_cookies())
        assert status == 400 and b"lang" in page, page
        browser.get(base + "/")  # the next rotor: the first one's certificates stay there
        _see(browser, "Новий ротор")  # the form is there before a word is typed into it
        _type(browser, "серійний номер", "U-2")
        _button(browser, "Почати вимірювання").click()
        _see(browser, "вимірювання U-2", 60)
        for lang in ("de", "en"):
            status, page = _fetch(base, f"/report/{run['id']}?lang={lang}", browser.get_cookies())
            assert status == 200 and f'<html lang="{lang}">'.encode() in page, (lang, status)
        _button(browser, "Стоп").click()
    german = tmp_path / "de"
    german.mkdir()
    with served(german, "--lang", "de", "--config-dir", str(strict)) as base:
        browser.get(base + "/")
        _see(browser, "Neuer Rotor")
        _see(browser, "Einzelplatz: keine Benutzerkonten")
        _type(browser, "Seriennummer", "D-1")
        _button(browser, "Messung starten").click()
        _see(browser, "Schwingung an den Lagern")  # the first estimate, in German
        _stop_on_screen(browser, "STOPP")  # the longer header still leaves Stop in view
        _button(browser, "Stopp").click()
        _button(browser, "Zur Korrektur", 60).click()
        _see(browser, "Korrektur für D-1")


@pytest.mark.realtime
def test_the_setup_screen_by_role(browser: Any, tmp_path: Path) -> None:
    """A setter loads a rotor type from a file at the Setup screen (the upload, the reason,
    the table), journaled as the account; the tolerance panel tells the setter why not; an
    engineer sees the tolerance and calibration panels, and a tolerance typed as "2,500"
    is refused as ambiguous, "2.5" saved after old and new are shown."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    from stand.archive.audit import entries
    from stand.config import load_config

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    (tmp_path / "pw").write_text("a-long-password\n")
    with_accounts(url, ("ana", "setter", "a-long-password"), ("eva", "engineer", "a-long-password"))
    folder = tmp_path / "rotors"
    folder.mkdir()
    text = (ROOT / "stand" / "data" / "rotors" / "demo-auger.toml").read_text()
    (folder / "demo-auger.toml").write_text(text)
    new = tmp_path / "auger-b.toml"
    new.write_text(text.replace('type = "demo-auger"', 'type = "auger-b"'))
    with served(tmp_path, "--config-dir", str(folder)) as base:
        browser.get(base + "/")
        _see(browser, "Log in")
        _log_in(browser, "ana", "a-long-password")
        _see(browser, "ana (setter)")
        _button(browser, "Setup").click()
        _see(browser, "Load a rotor type")
        _see(browser, "ana (setter) may not change a tolerance: it takes engineer")
        browser.find_element(By.CSS_SELECTOR, "input[type=file]").send_keys(str(new))
        _see(browser, "auger-b.toml")  # uploaded: the uploader names the file
        _type(browser, "reason", "order 4711 needs it")
        _button(browser, "Load").click()
        _see(browser, "rotor type loaded and journaled")
        cells = browser.execute_script(
            "return [...document.querySelectorAll('.q-table tbody tr td:first-child')]"
            ".map(c => c.innerText.trim());"
        )
        assert cells == ["auger-b", "demo-auger"], cells
        _shot(browser, tmp_path, "setup")
        _button(browser, "Log out").click()
        _see(browser, "Log in")
        _log_in(browser, "eva", "a-long-password")
        _see(browser, "eva (engineer)")
        _button(browser, "Setup").click()
        _button(browser, "Recalibrate from the archive")  # an engineer's panels: all four
        _button(browser, "Save the tolerance")
        _shot(browser, tmp_path, "setup-engineer")
        # the tolerance as typed, asked once with old and new, then saved
        grade = browser.find_element(By.CSS_SELECTOR, 'input[aria-label="G [mm/s]"]')
        assert grade.get_attribute("value") == "6.3"  # auger-b's, the first type
        grade.send_keys(Keys.CONTROL, "a")
        grade.send_keys("2,500")  # thousands or decimals? never guessed
        reasons = browser.find_elements(By.CSS_SELECTOR, 'input[aria-label="reason"]')
        reasons[2].send_keys("drawing rev. C")  # load, tooling, tolerance, calibration
        _button(browser, "Save the tolerance").click()
        _see(browser, "2,500 could be read two ways")
        grade.send_keys(Keys.CONTROL, "a")
        grade.send_keys("2.5")
        _button(browser, "Save the tolerance").click()
        _see(browser, "G 6.3 -> 2.5 mm/s, maximum speed 1500 -> 1500 rpm?")
        _shot(browser, tmp_path, "setup-confirm")
        _button(browser, "Save").click()
        _see(browser, "tolerance changed and journaled")
    assert (folder / "auger-b.toml").read_text() != new.read_text()
    assert load_config(str(folder / "auger-b.toml"))[0].tolerance.grade_mm_s == 2.5
    loaded, tightened = entries(url, action="config")
    assert (loaded["who"], loaded["subject"], loaded["reason"]) == (
        "ana",
        "auger-b.toml",
        "order 4711 needs it",
    )
    assert (tightened["who"], tightened["reason"]) == ("eva", "drawing rev. C")
