"""The stand's cycle through the station's screens in headless Chromium: a rotor type with
a ``[drive]`` started on the simulated stand, the Measure screen's drive line, the Correct
screen's stops at the mark and its turn of plane 2."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from test_station_browser import ROOT, _button, _see, _shot, _type, served


def _choose(driver: Any, label: str, option: str) -> None:
    """Pick ``option`` in the select labelled ``label`` (Quasar's q-select: its menu)."""
    from selenium.webdriver.common.by import By

    field = driver.find_element(
        By.XPATH, f"//label[contains(@class,'q-select')][.//div[normalize-space(.)='{label}']]"
    )
    field.click()
    item = f"//div[contains(@class,'q-item')][normalize-space(.)='{option}']"
    _see(driver, option)
    driver.find_element(By.XPATH, item).click()


@pytest.mark.parametrize("family", ["modbus", "cia402"])
def test_the_cycle_through_the_screens(browser: Any, tmp_path: Path, family: str) -> None:
    rotors = tmp_path / "rotors"
    rotors.mkdir()
    text = (ROOT / "examples" / f"drive-{family}.toml").read_text(encoding="utf-8")
    eds = str(ROOT / "drivers" / "cia402" / "cia402_servo.eds")  # the copy's folder is another
    (rotors / "demo-auger.toml").write_text(text.replace("../drivers/cia402/cia402_servo.eds", eds))
    with served(tmp_path, "--config-dir", str(rotors)) as base:
        browser.set_window_size(1024, 768)
        browser.get(base + "/")
        _see(browser, "New rotor")
        _type(browser, "serial number", "DR-1")
        _choose(browser, "source", "simulated: demo-drive")
        _button(browser, "Start measuring").click()
        _see(browser, "drive: ")
        _see(browser, "guard closed")
        _shot(browser, tmp_path, "measure-drive")
        _button(browser, "Go to the correction").click()
        _see(browser, "turned to the mark")
        _button(browser, "Turn plane 2 to the mark").click()
        _see(browser, "plane 2's correction place is at the mark")
        _shot(browser, tmp_path, "correct-drive")
        from selenium.webdriver.common.by import By
        from selenium.webdriver.support.ui import WebDriverWait

        def card(i: int) -> str:
            xpath = f"//div[contains(@class,'q-card')][contains(., 'plane {i}: at radius')]"
            return str(browser.find_element(By.XPATH, xpath).text)

        # plane 2's place is at the mark now, and plane 1's card no longer says it is
        WebDriverWait(browser, 10, 0.1).until(lambda d: "turned to the mark" in card(2))
        assert "turned to the mark" not in card(1)
