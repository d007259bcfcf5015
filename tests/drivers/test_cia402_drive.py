"""The simulated CiA 402 servo driven by the ``canopen`` library's own 402 profile (not our
client), and our client against it: the state machine's states, profile velocity and
profile position, the interlock, a fault, a silent node, hostile ``[drive.cia402]`` tables.

Tolerances: velocities are whole units of 0.1 rpm; positions whole counts of 4096 a
revolution (0.09 deg); a run-up is timed by the monotonic clock, so its check waits for
the at-speed flag rather than a time.
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any

import pytest

from stand.config import config_from_dict
from stand.core.motor import Motor
from stand.drivers.cia402.table import Cia402Table
from stand.drivers.drive import DriveContext, drive_family_of
from stand.errors import ConfigError, DriveError
from stand.sim.servo import SimServo, eds_path
from stand.sim.tables import DriveFaults

MOTOR = Motor(0.35, 25.0, 40.0, 0.5)
TABLE = Cia402Table(node_id=10, eds=str(eds_path()), counts_per_rev=4096, velocity_per_rpm=10.0)
ROOT = Path(__file__).resolve().parents[2]


def _library_node(bus: dict[str, Any]) -> tuple[Any, Any, Any]:
    import can
    import canopen

    b = can.Bus(**bus)
    network = canopen.Network(b)
    network.notifier = can.Notifier(b, network.listeners, 0.05)
    node = canopen.BaseNode402(10, str(eds_path()))
    network.add_node(node)
    node.setup_402_state_machine(read_pdos=False)
    return node, network, b


def _until(check: Any, timeout_s: float = 10.0) -> None:
    end = time.monotonic() + timeout_s
    while not check():
        assert time.monotonic() < end, "never"
        time.sleep(0.02)


def test_the_librarys_402_profile_walks_the_simulated_servo() -> None:
    sim = SimServo(MOTOR, TABLE, gamma_rad=0.0)
    with sim.serve(TABLE, None) as (_, bus):
        node, network, b = _library_node(bus)
        try:
            assert node.state == "SWITCH ON DISABLED"
            node.op_mode = "PROFILED VELOCITY"
            node.sdo[0x60FF].raw = 6000  # 600.0 rpm
            node.state = "OPERATION ENABLED"
            sim.start_clock(time.monotonic())
            _until(lambda: node.sdo[0x606C].raw == 6000)
            assert node.state == "OPERATION ENABLED" and node.statusword & (1 << 10)
            node.op_mode = "PROFILED POSITION"
            here = node.sdo[0x6064].raw
            node.sdo[0x607A].raw = here + 5 * 4096 + 1024  # 5 revolutions and 90 deg on
            node.controlword = 0x3F
            node.controlword = 0x0F
            _until(lambda: node.statusword & (1 << 10) and node.sdo[0x606C].raw == 0)
            assert node.sdo[0x6064].raw == here + 5 * 4096 + 1024
            node.state = "QUICK STOP ACTIVE"
            node.state = "SWITCH ON DISABLED"
        finally:
            network.notifier.stop(1.0)
            b.shutdown()


def _ctx(bus: Any) -> DriveContext:
    return DriveContext(0.5, ROOT, "test.toml", bus, MOTOR)


def test_our_client_refuses_a_drive_that_may_not_start() -> None:
    sim = SimServo(MOTOR, TABLE, 0.0, DriveFaults(guard_open=True))
    with sim.serve(TABLE, None) as (table, bus):
        drive = drive_family_of("cia402").connect(table, _ctx(bus))
        try:
            st = drive.read()
            assert not st.guard_closed and st.fault_code == 0
            with pytest.raises(DriveError, match="never reached Operation enabled"):
                drive.run(50.0)
        finally:
            drive.close()
    sim = SimServo(MOTOR, TABLE, 0.0, DriveFaults(fault_code=0x7305))
    with sim.serve(TABLE, None) as (table, bus):
        drive = drive_family_of("cia402").connect(table, _ctx(bus))
        assert drive.read().fault_code == 0x7305
        drive.close()


def test_a_silent_node_is_one_line() -> None:
    sim = SimServo(MOTOR, TABLE, 0.0, DriveFaults(silent=True))
    with sim.serve(TABLE, None) as (table, bus), pytest.raises(
        DriveError, match=r"^drive cia402 node 10 on stand-servo-.*: its set-up: no answer|"
                          r"statusword 0x6041: no answer"):  # fmt: skip
        drive_family_of("cia402").connect(table, _ctx(bus))


def _config(cia402: dict[str, Any]) -> dict[str, Any]:
    import tomllib

    data = tomllib.loads((ROOT / "examples" / "drive-cia402.toml").read_text(encoding="utf-8"))
    data["drive"]["cia402"] = {**data["drive"]["cia402"], **cia402}
    return data


@pytest.mark.parametrize(("change", "named"), [
    ({"node_id": 0}, "drive.cia402.node_id"), ({"node_id": 128}, "drive.cia402.node_id"),
    ({"eds": ""}, "drive.cia402.eds"), ({"counts_per_rev": 2}, "drive.cia402.counts_per_rev"),
    ({"velocity_per_rpm": -1.0}, "drive.cia402.velocity_per_rpm"), ({"pdo": 1}, "drive.cia402.pdo"),
])  # fmt: skip
def test_hostile_cia402_tables(change: dict[str, Any], named: str) -> None:
    with pytest.raises(ConfigError, match=named.replace(".", r"\.")):
        config_from_dict(_config(change), "ex.toml")


@pytest.mark.parametrize("what", ["missing", "fifo", "not-402", "garbage"])
def test_a_wrong_eds_is_named_before_anything_turns(tmp_path: Path, what: str) -> None:
    eds = tmp_path / "servo.eds"
    text = eds_path().read_text(encoding="utf-8")
    if what == "fifo":
        os.mkfifo(eds)
    elif what == "not-402":
        eds.write_text(text.replace("[6041]", "[6F41]").replace("=0x6041", "=0x6F41"))
    elif what == "garbage":
        eds.write_text("[FileInfo\nthis is = no EDS")
    table = TABLE.model_copy(update={"eds": str(eds)})
    ctx = DriveContext(0.5, tmp_path, "cfg.toml", {"interface": "virtual", "channel": "x"}, MOTOR)
    with pytest.raises(ConfigError) as err:
        drive_family_of("cia402").connect(table, ctx)
    assert "cfg.toml" in str(err.value) and "\n" not in str(err.value)
    if what == "not-402":
        assert "0x6041" in str(err.value)
