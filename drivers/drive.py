"""The one seam for the stand's drive: a family of drives (none, a frequency inverter over
Modbus TCP ...), what a connected drive shall do (:class:`Drive`), and the one registry
of family names to the modules that implement them (:data:`DRIVES`), each imported only
when chosen.

A family lives in its own wing of ``drivers/`` (``drivers/<name>/``) whose face holds
``FAMILY``, an object that satisfies :class:`DriveFamily`.  Adding one: write the wing,
add its name and module here, document it in ``docs/drive.md``.  The config checks
``[drive] family`` and ``[drive.<name>]`` through :func:`drive_family_of`; the cycle
(:mod:`stand.live.cycle`) is the one place that commands a drive.

The product supervises the stand's safety hardware; it is not that hardware.  The guard
interlock and the emergency stop act on the drive's power by themselves; a drive reports
their state (:class:`DriveState`) so that the cycle never commands what they forbid.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from stand.core.motor import Motor
from stand.errors import ConfigError, DriveError

DRIVES: dict[str, str] = {
    "none": "stand.drivers.nodrive",
    "modbus": "stand.drivers.modbus",
    "cia402": "stand.drivers.cia402",
}
"""``[drive] family`` names -> the module whose ``FAMILY`` implements it."""


@dataclass(frozen=True)
class DriveState:
    """What a drive reports, in SI: read once per supervision tick."""

    speed_rad_s: float
    """The actual speed [rad/s] (negative: turning backwards)."""
    angle_rad: float | None
    """The shaft angle from the reference mark, in the direction of rotation [rad], or
    None for a drive without an encoder referenced to the mark."""
    ready: bool
    """Powered, enabled, no fault: it follows a set point."""
    at_speed: bool
    """The speed is at the set point (the drive's own window)."""
    standstill: bool
    in_position: bool
    """A stop at an angle is finished."""
    guard_closed: bool
    """The guard's interlock input says closed."""
    estop_clear: bool
    """The emergency stop is not pressed."""
    fault_code: int
    """0: no fault; else the drive's own code."""


class Drive(Protocol):
    """A connected drive.  An implementation shall:

    - read its state in one exchange (:meth:`read`), every figure in SI and checked for
      what the map says it can hold (a register reading nonsense is one
      :class:`~stand.errors.DriveError` naming the register), and raise
      :class:`~stand.errors.DriveError` naming the drive (``where``) when it does not
      answer within the configured time;
    - take a speed set point (:meth:`run`) only below the limit the cycle gave it, a stop
      at an angle (:meth:`stop_at`: brake to rest with the shaft at that angle, the
      drive's own positioning doing the last degree), a quick stop (:meth:`quick_stop`:
      full braking, then disabled) and a disable (:meth:`disable`);
    - never leave the shaft turning on :meth:`close` after a fault of the host: close
      quick-stops a drive still running.
    """

    where: str
    """The drive named for a person: family, address."""

    def read(self) -> DriveState:
        """The drive's state now."""

    def run(self, omega_rad_s: float) -> None:
        """Enable and run at this speed [rad/s], within the drive's torque."""

    def stop_at(self, angle_rad: float) -> None:
        """Brake (or turn, from rest) to rest with the shaft at ``angle_rad`` from the mark."""

    def quick_stop(self) -> None:
        """Full braking to rest, then disabled."""

    def disable(self) -> None:
        """Power off the motor (at rest)."""

    def close(self) -> None:
        """Let the connection go (quick-stops a drive still turning)."""


@dataclass(frozen=True)
class DriveContext:
    """What a family connects with besides its table: each exchange's time limit [s], the
    config's folder and name (description files are relative to it), the stand's CAN bus
    (``can.Bus`` options; a drive on the bus uses it) and the shaft it turns."""

    timeout_s: float
    base: Path
    source: str
    bus: dict[str, Any] | None
    motor: Motor


class DriveFamily(Protocol):
    """A family of drives.  An implementation shall name itself (``name``, its ``[drive]
    family`` value), give the pydantic model of its ``[drive.<name>]`` table (``table``;
    None: it takes none; every key bounded), say whether the product commands it
    (``commanded``: False for ``none``, where the operator spins the rotor) and connect to
    one drive from a checked table (:meth:`connect`), raising
    :class:`~stand.errors.DriveError` when it does not answer and
    :class:`~stand.errors.ConfigError` for a description file that is wrong (read bounded,
    :func:`stand.drivers.family.read_description`)."""

    name: str
    table: type[Any] | None
    commanded: bool

    def connect(self, table: Any, ctx: DriveContext) -> Drive:
        """A connected drive."""


def close_link(quick_stop: Callable[[], None], running: bool, release: Callable[[], None]
               ) -> None:  # fmt: skip
    """A drive's :meth:`Drive.close`: quick-stop it first while it still runs, then let the
    link go (a link gone already: the drive's own watchdog stops it)."""
    try:
        if running:
            quick_stop()
    except DriveError:
        pass
    finally:
        release()


def drive_family_of(name: str, source: str = "the config") -> DriveFamily:
    """The family registered under ``name`` (its module imported now).

    Raises
    ------
    ConfigError
        No family of that name.
    """
    if name not in DRIVES:
        raise ConfigError(f"{name!r}, expected one of {', '.join(DRIVES)}",
                          source=source, key="drive.family")  # fmt: skip
    found: DriveFamily = importlib.import_module(DRIVES[name]).FAMILY
    return found
