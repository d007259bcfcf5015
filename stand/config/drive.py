"""``[drive]``: the stand's drive (a family of :data:`stand.drivers.drive.DRIVES`, its
``[drive.<name>]`` table checked by the family's model), the shaft it turns and the
cycle's limits.

::

    [drive]
    family = "modbus"            # "none": the operator spins the rotor (as without [drive])
    speed_rpm = 900.0            # the measuring speed the drive is set to
    inertia_kg_m2 = 0.35         # rotor and drive about the spin axis
    torque_n_m = 25.0            # the drive's torque limit
    brake_torque_n_m = 40.0      # its braking torque
    friction_n_m = 0.5           # the drag of bearings and air (constant)
    index_mark_deg = 0.0         # the operator's mark, from the reference sensor, in the
                                 # direction of rotation: where the correction place stops
    max_speed_rpm = 1500.0       # never a set point above (default: [tolerance]'s)
    runup_limit_m_s2 = 50.0      # a support's 1x above this during run-up: quick stop
    speed_agree_pct = 1.0        # the drive's speed against the reference mark's
    timeout_s = 0.5              # one exchange with the drive

    [drive.modbus]
    host = "192.168.10.20"
    ...
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Any

from pydantic import BaseModel, Field, FiniteFloat, field_validator

from stand.config.tables import STRICT, Angle, Rpm
from stand.config.validation import validate
from stand.core.motor import Motor
from stand.drivers.drive import DRIVES, DriveFamily, drive_family_of
from stand.errors import ConfigError

Torque = Annotated[FiniteFloat, Field(gt=0.0, le=1e6)]
"""[N m]: at most a meganewton-metre."""


class DriveTable(BaseModel):
    """``[drive]``: the family, the shaft, the cycle's limits; a family's own table by name."""

    model_config = STRICT

    family: Annotated[str, Field(min_length=1, max_length=32)]
    """The drive's family: ``modbus`` (a frequency inverter on Modbus TCP) or ``none`` (the
    operator spins the rotor, as without ``[drive]``)."""
    speed_rpm: Rpm | None = None
    """The measuring speed the drive is set to [rpm] (``--rpm`` sets another)."""
    inertia_kg_m2: Annotated[FiniteFloat, Field(gt=0.0, le=1e6)] = 1.0
    """Rotor and drive about the spin axis [kg m^2]: with the torques, the run-up's and the
    braking's floors and the simulated drive's motion."""
    torque_n_m: Torque = 10.0
    """The drive's torque limit [N m]."""
    brake_torque_n_m: Torque = 10.0
    """The drive's braking torque [N m] (brake resistor, or a mechanical brake)."""
    friction_n_m: Annotated[FiniteFloat, Field(ge=0.0, le=1e6)] = 0.0
    """The constant drag of bearings and air [N m], below the torque limit."""
    index_mark_deg: Angle = 0.0
    """The operator's mark, from the reference sensor in the direction of rotation [deg]:
    where the drive stops a plane's correction place."""
    max_speed_rpm: Rpm | None = None
    """No set point above this [rpm] (default: ``[tolerance] max_speed_rpm``)."""
    runup_limit_m_s2: Annotated[FiniteFloat, Field(gt=0.0, le=1e5)] | None = None
    """A support's 1x over this during the run-up stops the rotor [m/s^2] (a loose or
    grossly unbalanced rotor); none: not watched."""
    speed_agree_pct: Annotated[FiniteFloat, Field(gt=0.0, le=20.0)] = 1.0
    """The drive's speed and the reference mark's may differ by this much [%]; more: the
    run is refused, both figures named (a register map's wrong scaling)."""
    timeout_s: Annotated[FiniteFloat, Field(ge=0.01, le=30.0)] = 0.5
    """One exchange with the drive [s]: longer, the drive does not answer."""
    modbus: dict[str, Any] | None = None
    """``[drive.modbus]``: the inverter's address and register map (docs/drive.md)."""
    cia402: dict[str, Any] | None = None
    """``[drive.cia402]``: the servo's node id, EDS and units (docs/drive.md)."""

    @field_validator("family")
    @classmethod
    def _known(cls, family: str) -> str:
        if family not in DRIVES:
            raise ValueError(f"expected one of {', '.join(DRIVES)}")
        return family

    def motor(self) -> Motor:
        """The shaft the drive turns (:class:`stand.core.motor.Motor`)."""
        return Motor(self.inertia_kg_m2, self.torque_n_m, self.brake_torque_n_m,
                     self.friction_n_m)  # fmt: skip


@dataclass(frozen=True)
class DriveChoice:
    """The family ``[drive]`` names, its checked ``[drive.<name>]`` table, the table."""

    family: DriveFamily
    table: Any
    drive: DriveTable


def drive_choice(drive: DriveTable, source: str) -> DriveChoice:
    """The ``[drive]`` table's family and its checked own table.

    Raises
    ------
    ConfigError
        Its table missing or wrong, a table of another family, a friction that stops the
        rotor turning.
    """
    fam = drive_family_of(drive.family, source)
    others = [n for n in DRIVES if n != fam.name and getattr(drive, n, None) is not None]
    if others:
        raise ConfigError(f"[drive.{others[0]}] is read by family = {others[0]!r}, but the "
                          f"config says family = {fam.name!r}", source=source)  # fmt: skip
    if drive.friction_n_m >= drive.torque_n_m:
        raise ConfigError(f"{drive.friction_n_m:g} N m, at least the torque limit "
                          f"{drive.torque_n_m:g} N m: the drive could never turn the rotor",
                          source=source, key="drive.friction_n_m")  # fmt: skip
    if fam.table is None:
        return DriveChoice(fam, None, drive)
    table = getattr(drive, fam.name, None)
    if table is None:
        raise ConfigError(f"[drive] family = {fam.name!r} needs a [drive.{fam.name}] table",
                          source=source)  # fmt: skip
    return DriveChoice(fam, validate(fam.table, table, source, prefix=f"drive.{fam.name}."),
                       drive)  # fmt: skip
