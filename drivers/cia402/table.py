"""``[drive] family = "cia402"`` and the ``[drive.cia402]`` table: a servo drive on the
stand's CANopen bus (the config's ``[bus]``), driven through the CiA 402 state machine by
the ``canopen`` library's 402 profile (the client: :mod:`stand.drivers.cia402.client`).

::

    [drive.cia402]
    node_id = 10                   # the drive's CANopen node id
    eds = "servo.eds"              # its EDS, relative to this file's folder
    counts_per_rev = 4096          # position units a revolution (0x6064, 0x607A)
    velocity_per_rpm = 10.0        # velocity units a rpm (0x606C, 0x60FF)

The drive's position counts from the reference mark (its zero-pulse or touch-probe input
wired to the mark's sensor, as every node is); its digital inputs (0x60FD) carry the
guard's interlock (bit 3, CiA 402's "interlock": set while the guard is open) and the
emergency stop (bit :data:`ESTOP_BIT`, manufacturer-specific: set while it is pressed).
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, Field, FiniteFloat

from stand.drivers.family import STRICT

INTERLOCK_BIT = 3
"""0x60FD's bit set while the guard's interlock is active (CiA 402)."""
ESTOP_BIT = 16
"""0x60FD's bit set while the emergency stop is pressed (the first manufacturer bit)."""

SW_FAULT, SW_TARGET_REACHED = 1 << 3, 1 << 10
STATES = {  # CiA 402's statusword: (mask, value) -> state
    "NOT READY TO SWITCH ON": (0x4F, 0x00), "SWITCH ON DISABLED": (0x4F, 0x40),
    "READY TO SWITCH ON": (0x6F, 0x21), "SWITCHED ON": (0x6F, 0x23),
    "OPERATION ENABLED": (0x6F, 0x27), "QUICK STOP ACTIVE": (0x6F, 0x07),
    "FAULT REACTION ACTIVE": (0x4F, 0x0F), "FAULT": (0x4F, 0x08),
}  # fmt: skip
"""The drive's states by its statusword (0x6041), as CiA 402 defines them."""


def state_of(statusword: int) -> str:
    """The CiA 402 state a statusword says ("UNKNOWN": none)."""
    return next((s for s, (m, v) in STATES.items() if statusword & m == v), "UNKNOWN")


class Cia402Table(BaseModel):
    """``[drive.cia402]``: the servo's node, its EDS and its units."""

    model_config = STRICT

    node_id: Annotated[int, Field(ge=1, le=127)]
    eds: Annotated[str, Field(min_length=1, max_length=4000)]
    counts_per_rev: Annotated[int, Field(ge=36, le=1 << 24)] = 4096
    velocity_per_rpm: Annotated[FiniteFloat, Field(gt=0.0, le=1e6)] = 10.0
