"""The simulated drive of each drive family (:data:`stand.drivers.drive.DRIVES`): the
protocol a real one speaks, on the simulated shaft (:mod:`stand.sim.shaft`)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from stand.core.motor import Motor
from stand.errors import ConfigError
from stand.sim.drive import sim_drive
from stand.sim.servo import sim_servo
from stand.sim.shaft import SimShaft

SIMULATED: dict[str, Callable[[Any, Motor, Any], SimShaft]] = {
    "modbus": sim_drive, "cia402": sim_servo,
}  # fmt: skip
"""Family name -> the function that makes a scene's simulated drive of that family."""


def simulated_drive(family: str, scene: Any, motor: Motor, table: Any) -> SimShaft:
    """The simulated drive of ``family`` for ``scene`` (its motor, the config's table).

    Raises
    ------
    ConfigError
        No simulated drive of that family.
    """
    if family not in SIMULATED:
        raise ConfigError(f"{family!r}: no simulated drive of this family (simulated: "
                          f"{', '.join(SIMULATED)})", key="drive.family")  # fmt: skip
    made: SimShaft = SIMULATED[family](scene, motor, table)
    return made
