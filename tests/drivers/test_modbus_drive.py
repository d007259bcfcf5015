"""The simulated inverter read by a Modbus client of another implementation (pyModbusTCP,
not pymodbus), and the product's client against it: the register map as documented, the
motor's run-up, a stop at an angle, and a link that fails named in one line.

Tolerances: speeds are whole counts of 0.1 rpm (``speed_per_rpm = 10``), angles of 0.1 deg
(3600 counts a revolution); the run-up is timed by the monotonic clock, so its check
allows a busy machine's late reading (the speed only grows until the set point).
"""

from __future__ import annotations

import math
import time

import pytest
from pyModbusTCP.client import ModbusClient

from stand.core.motor import Motor
from stand.drivers.modbus.client import ModbusDrive
from stand.drivers.modbus.table import (
    CONTROL_INDEX,
    CONTROL_RUN,
    STATUS_AT_SPEED,
    STATUS_GUARD_CLOSED,
    STATUS_IN_POSITION,
    STATUS_READY,
    STATUS_STANDSTILL,
    ModbusTable,
)
from stand.errors import DriveError
from stand.sim.drive import SimDrive, SimInverter
from stand.sim.tables import DriveFaults

MOTOR = Motor(0.35, 25.0, 40.0, 0.5)
MAP = ModbusTable(host="127.0.0.1", unit=3, status=20, speed=21, angle=22, fault=23,
                  speed_per_rpm=10.0, counts_per_rev=3600)  # fmt: skip


def _other(port: int) -> ModbusClient:
    client = ModbusClient(host="127.0.0.1", port=port, unit_id=MAP.unit, timeout=2.0,
                          auto_open=True)  # fmt: skip
    return client


def test_another_client_reads_and_commands_the_simulated_inverter() -> None:
    sim = SimDrive(MOTOR, MAP, gamma_rad=0.0)
    with SimInverter(sim) as server:
        c = _other(server.port)
        status, speed, angle, fault = c.read_holding_registers(MAP.status, 4)
        assert status & STATUS_READY and status & STATUS_STANDSTILL
        assert status & STATUS_GUARD_CLOSED and (speed, angle, fault) == (0, 0, 0)
        assert c.write_single_register(MAP.set_point, 6000)  # 600.0 rpm
        assert c.write_single_register(MAP.control, CONTROL_RUN)
        sim.start_clock(time.monotonic())
        ramp = 600 * math.pi / 30 / MOTOR.accel_rad_s2
        time.sleep(ramp + 0.3)
        status, speed, _, _ = c.read_holding_registers(MAP.status, 4)
        assert speed == 6000 and status & STATUS_AT_SPEED
        assert c.write_single_register(MAP.target, 900)  # 90.0 deg
        assert c.write_single_register(MAP.control, CONTROL_INDEX)
        for _ in range(200):
            status, speed, angle, _ = c.read_holding_registers(MAP.status, 4)
            if status & STATUS_IN_POSITION:
                break
            time.sleep(0.02)
        assert status & STATUS_IN_POSITION and speed == 0 and angle == 900
        assert math.degrees(sim.true_angle_rad()) == pytest.approx(90.0, abs=1e-6)
        c.close()


def test_our_client_reads_what_the_map_says() -> None:
    sim = SimDrive(MOTOR, MAP, gamma_rad=0.3)
    with SimInverter(sim) as server:
        drive = ModbusDrive(MAP.model_copy(update={"port": server.port}), timeout_s=1.0)
        st = drive.read()
        assert st.ready and st.standstill and st.guard_closed and st.fault_code == 0
        # the angle counts from the reference mark passing its sensor (at 0.3 rad)
        assert st.angle_rad == pytest.approx((-0.3) % (2 * math.pi), abs=2 * math.pi / 3600)
        drive.close()


def test_a_fault_and_an_open_guard_are_reported_and_a_run_refused() -> None:
    sim = SimDrive(MOTOR, MAP, 0.0, DriveFaults(guard_open=True, fault_code=42))
    with SimInverter(sim) as server:
        drive = ModbusDrive(MAP.model_copy(update={"port": server.port}), timeout_s=1.0)
        drive.run(50.0)
        sim.start_clock(time.monotonic())
        time.sleep(0.2)
        st = drive.read()
        assert st.fault_code == 42 and not st.ready and not st.guard_closed
        assert st.speed_rad_s == 0.0  # the interlock: nothing turned
        drive.close()


def test_nobody_listening_is_one_line_naming_the_drive() -> None:
    with pytest.raises(DriveError, match=r"^drive modbus 127\.0\.0\.1:9 unit 3: does not answer"):
        ModbusDrive(MAP.model_copy(update={"port": 9}), timeout_s=0.2)


def test_a_reading_out_of_the_map_is_named() -> None:
    sim = SimDrive(MOTOR, MAP.model_copy(update={"counts_per_rev": 7200}), 0.0)
    sim.path = sim.path.then(0.0, 0.0)  # at rest
    with SimInverter(sim) as server:
        sim.start_clock(time.monotonic())
        c = _other(server.port)
        c.write_single_register(MAP.target, 5000)
        c.write_single_register(MAP.control, CONTROL_INDEX)  # turns to 250 deg of 7200
        time.sleep(1.5)
        drive = ModbusDrive(MAP.model_copy(update={"port": server.port}), timeout_s=1.0)
        with pytest.raises(DriveError, match="angle register 22: 5000 counts, the map says 3600"):
            drive.read()
        drive.close()
        c.close()
