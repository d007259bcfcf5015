"""The stand's cycle through the station's screens in headless Chromium: a rotor type with
a ``[drive]`` started on the simulated stand, the Measure screen's drive line, the Correct
screen's stops at the mark and its turn of plane 2; meanwhile (the inverter's run) a
node-opcua client watches the machine's MachineryItemState and MachineryOperationMode
follow the cycle, as an MES would."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from test_station_browser import ROOT, _button, _free_port, _see, _shot, _type, served

from tests.helpers.foreign import NodeUaClient


def _stand_id(rotors: Path) -> str:
    """The stand id the station serves OPC UA as (its rotor types' ``[stand] id``)."""
    from stand.config import load_config

    (config,) = rotors.glob("*.toml")
    return load_config(str(config))[0].stand.stand_id()


def _states_until(mes: NodeUaClient, *wanted: tuple[str, str]) -> None:
    """Read the client's state changes until each (machine, state) in ``wanted`` is the
    last one seen of its machine; each change's Id is the Foundation's NodeId of its state."""
    last: dict[str, str] = {}
    while any(last.get(machine) != state for machine, state in wanted):
        got = mes.next(60)
        if "machine" in got:
            assert got["known"], got
            last[got["machine"]] = got["state"]


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
    ua_port = _free_port()
    extra = ("--opcua", "--opcua-port", str(ua_port)) if family == "modbus" else ()
    with served(tmp_path, "--config-dir", str(rotors), *extra) as base:
        mes = None
        if extra:
            mes = NodeUaClient(f"opc.tcp://127.0.0.1:{ua_port}/stand/", _stand_id(rotors),
                               script="ua_state.js")  # fmt: skip
            _states_until(mes, ("item", "NotExecuting"), ("mode", "Processing"))
        browser.set_window_size(1024, 768)
        browser.get(base + "/")
        _see(browser, "New rotor")
        _type(browser, "serial number", "DR-1")
        _choose(browser, "source", "simulated: demo-drive")
        _button(browser, "Start measuring").click()
        _see(browser, "drive: ")
        _see(browser, "guard closed")
        if mes is not None:  # running a rotor; a simulated one is a rehearsal: Setup
            _states_until(mes, ("item", "Executing"), ("mode", "Setup"))
        _shot(browser, tmp_path, "measure-drive")
        _button(browser, "Go to the correction").click()
        _see(browser, "turned to the mark")
        if mes is not None:  # the cycle ended: the machine no longer executes
            _states_until(mes, ("item", "NotExecuting"))
            mes.close()
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
