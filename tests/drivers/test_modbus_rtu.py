"""Modbus RTU on a serial line: the simulated inverter served on one end of a null-modem
cable (two pseudo-terminals wired back to back), read by a Modbus RTU client of another
implementation (minimalmodbus, on pyserial; not pymodbus) and by the product's client;
a device that is not a serial line refused in one line before it is opened.

Tolerances: speeds are whole counts of 0.1 rpm, angles of 0.1 deg (the map's scaling).
"""

from __future__ import annotations

import math
import os
import time
from pathlib import Path

import pytest

from stand.core.motor import Motor
from stand.drivers.modbus.client import ModbusDrive
from stand.drivers.modbus.table import (
    CONTROL_RUN,
    STATUS_AT_SPEED,
    STATUS_GUARD_CLOSED,
    STATUS_READY,
    STATUS_STANDSTILL,
    ModbusTable,
)
from stand.errors import DriveError
from stand.sim.drive import SimDrive, SimInverter
from tests.helpers.null_modem import null_modem

MOTOR = Motor(0.35, 25.0, 40.0, 0.5)
LINE = {"transport": "rtu", "baudrate": 38400, "parity": "N", "stopbits": 1}
MAP = ModbusTable(device="/dev/null", unit=5, status=20, speed=21, angle=22, fault=23,
                  **LINE)  # type: ignore[arg-type]  # fmt: skip


def test_another_rtu_client_reads_and_commands_the_simulated_inverter() -> None:
    import minimalmodbus

    sim = SimDrive(MOTOR, MAP, gamma_rad=0.0)
    with null_modem() as (inverter, ours), SimInverter(sim, device=inverter):
        other = minimalmodbus.Instrument(ours, MAP.unit, mode=minimalmodbus.MODE_RTU)
        other.serial.baudrate, other.serial.parity, other.serial.timeout = 38400, "N", 2.0
        status, speed, angle, fault = other.read_registers(MAP.status, 4)
        assert status & STATUS_READY and status & STATUS_STANDSTILL
        assert status & STATUS_GUARD_CLOSED and (speed, angle, fault) == (0, 0, 0)
        other.write_register(MAP.set_point, 6000)  # 600.0 rpm
        other.write_register(MAP.control, CONTROL_RUN)
        sim.start_clock(time.monotonic())
        time.sleep(600 * math.pi / 30 / MOTOR.accel_rad_s2 + 0.3)  # the run-up, and more
        status, speed, _, _ = other.read_registers(MAP.status, 4)
        assert speed == 6000 and status & STATUS_AT_SPEED
        other.serial.close()


def test_our_client_on_the_serial_line_reads_what_the_map_says() -> None:
    sim = SimDrive(MOTOR, MAP, gamma_rad=0.3)
    with null_modem() as (inverter, ours), SimInverter(sim, device=inverter):
        drive = ModbusDrive(MAP.model_copy(update={"device": ours}), timeout_s=2.0)
        st = drive.read()
        assert st.ready and st.standstill and st.guard_closed and st.fault_code == 0
        assert st.angle_rad == pytest.approx((-0.3) % (2 * math.pi), abs=2 * math.pi / 3600)
        drive.close()


@pytest.mark.parametrize("kind", ["fifo", "file", "folder", "missing"])
def test_a_device_that_is_not_a_serial_line_is_one_line(tmp_path: Path, kind: str) -> None:
    device = tmp_path / "ttyUSB0"
    if kind == "fifo":
        os.mkfifo(device)  # opened, it would hang
    elif kind == "file":
        device.write_bytes(b"\x01\x03")
    elif kind == "folder":
        device.mkdir()
    with pytest.raises(DriveError) as caught:
        ModbusDrive(MAP.model_copy(update={"device": str(device)}), timeout_s=1.0)
    message = str(caught.value)
    assert message.startswith(f"drive modbus rtu {device} unit 5: the serial line")
    assert "\n" not in message
