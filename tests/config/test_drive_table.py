"""``[drive]`` and ``[drive.modbus]``: every key bounded, every fault one ConfigError naming
the key; a config without ``[drive]`` or with ``family = "none"`` commands nothing."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

import pytest

from stand.config import config_from_dict
from stand.errors import ConfigError
from stand.live.source import drive_link

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = tomllib.loads((ROOT / "examples" / "drive-modbus.toml").read_text(encoding="utf-8"))


def _with(drive: dict[str, Any] | None = None, modbus: dict[str, Any] | None = None,
          drop: str | None = None) -> dict[str, Any]:  # fmt: skip
    data = {**EXAMPLE, "drive": {**EXAMPLE["drive"], **(drive or {})}}
    data["drive"]["modbus"] = {**EXAMPLE["drive"]["modbus"], **(modbus or {})}
    data["drive"]["modbus"] = {k: v for k, v in data["drive"]["modbus"].items() if v is not None}
    if drop:
        del data["drive"][drop]
    return data


def test_the_example_loads_and_commands_its_drive() -> None:
    cfg, _ = config_from_dict(_with(), "ex.toml")
    link = drive_link(cfg, "ex.toml")
    assert link is not None and link.choice.family.name == "modbus"
    assert link.choice.table.counts_per_rev == 3600


@pytest.mark.parametrize("data", [
    {k: v for k, v in EXAMPLE.items() if k != "drive"},
    {**{k: v for k, v in EXAMPLE.items() if k != "drive"}, "drive": {"family": "none"}},
])  # fmt: skip
def test_no_drive_commands_nothing(data: dict[str, Any]) -> None:
    cfg, _ = config_from_dict(data, "ex.toml")
    assert drive_link(cfg, "ex.toml") is None


HOSTILE = [
    ({"family": "servo9000"}, None, None, "drive.family"),
    ({"family": 3}, None, None, "drive.family"),
    ({"speed_rpm": -900.0}, None, None, "drive.speed_rpm"),
    ({"speed_rpm": "900"}, None, None, "drive.speed_rpm"),
    ({"inertia_kg_m2": 0.0}, None, None, "drive.inertia_kg_m2"),
    ({"torque_n_m": float("inf")}, None, None, "drive.torque_n_m"),
    ({"brake_torque_n_m": float("nan")}, None, None, "drive.brake_torque_n_m"),
    ({"friction_n_m": 30.0}, None, None, "drive.friction_n_m"),
    ({"index_mark_deg": 1e9}, None, None, "drive.index_mark_deg"),
    ({"timeout_s": 0.0}, None, None, "drive.timeout_s"),
    ({"timeout_s": 1e6}, None, None, "drive.timeout_s"),
    ({"speed_agree_pct": 0.0}, None, None, "drive.speed_agree_pct"),
    ({"turbo": True}, None, None, "drive.turbo"),
    (None, {"host": ""}, None, "drive.modbus.host"),
    (None, {"host": "a b;rm"}, None, "drive.modbus.host"),
    (None, {"port": 70000}, None, "drive.modbus.port"),
    (None, {"unit": 300}, None, "drive.modbus.unit"),
    (None, {"control": -1}, None, "drive.modbus.control"),
    (None, {"status": 0x10000}, None, "drive.modbus.status"),
    (None, {"speed": 10}, None, "drive.modbus"),  # the status register twice
    (None, {"fault": 200}, None, "drive.modbus"),  # read registers spread over 32
    (None, {"speed_per_rpm": 0.0}, None, "drive.modbus.speed_per_rpm"),
    (None, {"counts_per_rev": 4}, None, "drive.modbus.counts_per_rev"),
    (None, {"counts_per_rev": 3600.5}, None, "drive.modbus.counts_per_rev"),
    (None, {"coils": 5}, None, "drive.modbus.coils"),
    (None, {"transport": "udp"}, None, "drive.modbus.transport"),
    (None, {"transport": "rtu"}, None, "transport 'rtu' takes device"),  # host, no device
    (None, {"device": "/dev/ttyUSB0"}, None, "transport 'tcp' takes host"),
    (
        None,
        {"transport": "rtu", "host": None, "device": "/dev/tty USB0;x"},
        None,
        "drive.modbus.device",
    ),
    (
        None,
        {"transport": "rtu", "host": None, "device": "../../etc/passwd"},
        None,
        "drive.modbus.device",
    ),
    (None, {"baudrate": 12345}, None, "drive.modbus.baudrate"),
    (None, {"parity": "X"}, None, "drive.modbus.parity"),
    (None, {"stopbits": 3}, None, "drive.modbus.stopbits"),
    (None, None, "modbus", "[drive] family = 'modbus' needs a [drive.modbus] table"),
]


@pytest.mark.parametrize(("drive", "modbus", "drop", "named"), HOSTILE)
def test_hostile_drive_tables_are_one_line_naming_the_key(
    drive: dict[str, Any] | None, modbus: dict[str, Any] | None, drop: str | None, named: str
) -> None:
    with pytest.raises(ConfigError) as err:
        config_from_dict(_with(drive, modbus, drop), "ex.toml")
    text = str(err.value)
    assert named in text.replace('"', "'"), text
    assert "\n" not in text and text.startswith("ex.toml")
