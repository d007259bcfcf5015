"""``[drive] family = "modbus"`` and the ``[drive.modbus]`` table: a frequency inverter
(or servo inverter) over Modbus TCP or Modbus RTU on a serial line, its register map
(the client: :mod:`stand.drivers.modbus.client`).

::

    [drive.modbus]
    host = "192.168.10.20"     # Modbus TCP: the inverter's address
    port = 502
    # transport = "rtu"        # Modbus RTU instead: the serial line, not host and port
    # device = "/dev/ttyUSB0"  #   an RS-485 adapter (a character device)
    # baudrate = 19200         #   and the line's settings (Modbus's default: 8 E 1)
    # parity = "E"
    # stopbits = 1
    unit = 1                   # the Modbus unit (device) id
    control = 0                # holding registers: the control word (bits: CONTROL_*)
    set_point = 1              #   the speed set point, signed, speed_per_rpm a rpm
    target = 2                 #   the stop angle, counts from the reference mark
    status = 10                #   the status word (bits: STATUS_*)
    speed = 11                 #   the actual speed, signed, speed_per_rpm a rpm
    angle = 12                 #   the actual angle, counts from the reference mark
    fault = 13                 #   the fault code, 0: none
    speed_per_rpm = 10.0       # register counts per rpm
    counts_per_rev = 3600      # angle counts per revolution

The four registers read (status, speed, angle, fault) lie within :data:`READ_SPAN`
registers of each other and are read in one request, so one state is one instant.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, Field, FiniteFloat, model_validator

from stand.drivers.family import STRICT

CONTROL_RUN = 1 << 0
"""Control word: enabled, following the speed set point."""
CONTROL_QUICK_STOP = 1 << 1
"""Control word: full braking to rest, then disabled (wins over every other bit)."""
CONTROL_INDEX = 1 << 2
"""Control word: brake (or turn, from rest) to rest at the target angle."""
CONTROL_RESET = 1 << 7
"""Control word: acknowledge a fault."""

STATUS_READY = 1 << 0
STATUS_AT_SPEED = 1 << 1
STATUS_STANDSTILL = 1 << 2
STATUS_IN_POSITION = 1 << 3
STATUS_GUARD_CLOSED = 1 << 4
STATUS_ESTOP_CLEAR = 1 << 5
STATUS_FAULT = 1 << 6

STATUS_BITS = {
    "ready": STATUS_READY, "at_speed": STATUS_AT_SPEED, "standstill": STATUS_STANDSTILL,
    "in_position": STATUS_IN_POSITION, "guard_closed": STATUS_GUARD_CLOSED,
    "estop_clear": STATUS_ESTOP_CLEAR, "fault": STATUS_FAULT,
}  # fmt: skip
"""The status word's bits by the name of what each says."""


def status_word(**flags: bool) -> int:
    """The status word of these flags (names of :data:`STATUS_BITS`)."""
    return sum(STATUS_BITS[name] for name, on in flags.items() if on)


def status_flags(word: int) -> dict[str, bool]:
    """The flags a status word says, by name."""
    return {name: bool(word & bit) for name, bit in STATUS_BITS.items()}


READ_SPAN = 32
"""The read registers' largest spread: one request of at most this many registers."""

Register = Annotated[int, Field(ge=0, le=0xFFFF)]
DEVICE = r"^(/dev/[A-Za-z0-9_.\-/]+|COM[0-9]{1,3}|socket://[A-Za-z0-9.\-]+:[0-9]{1,5})$"
"""A serial line: a device under /dev (COMn on Windows), or pyserial's ``socket://`` URL
(an RTU line carried over TCP: a serial device server, the simulated inverter)."""


class ModbusTable(BaseModel):
    """``[drive.modbus]``: where the inverter is and its register map."""

    model_config = STRICT

    transport: Literal["tcp", "rtu"] = "tcp"
    host: Annotated[str, Field(min_length=1, max_length=253,
                               pattern=r"^[A-Za-z0-9.:\-]+$")] | None = None  # fmt: skip
    port: Annotated[int, Field(ge=1, le=65535)] = 502
    device: Annotated[str, Field(max_length=200, pattern=DEVICE)] | None = None
    baudrate: Literal[1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200] = 19200
    parity: Literal["N", "E", "O"] = "E"
    stopbits: Literal[1, 2] = 1
    unit: Annotated[int, Field(ge=0, le=247)] = 1
    control: Register = 0
    set_point: Register = 1
    target: Register = 2
    status: Register = 10
    speed: Register = 11
    angle: Register = 12
    fault: Register = 13
    speed_per_rpm: Annotated[FiniteFloat, Field(gt=0.0, le=1000.0)] = 10.0
    counts_per_rev: Annotated[int, Field(ge=36, le=65536)] = 3600

    @model_validator(mode="after")
    def _map(self) -> ModbusTable:
        if self.transport == "tcp" and (self.host is None or self.device is not None):
            raise ValueError('transport "tcp" takes host (and port), not device')
        if self.transport == "rtu" and (self.device is None or self.host is not None):
            raise ValueError('transport "rtu" takes device (the serial line), not host')
        names = ("control", "set_point", "target", "status", "speed", "angle", "fault")
        seen: dict[int, str] = {}
        for name in names:
            if (other := seen.setdefault(getattr(self, name), name)) != name:
                raise ValueError(f"{name} and {other} are both register {getattr(self, name)}")
        read = [self.status, self.speed, self.angle, self.fault]
        if max(read) - min(read) >= READ_SPAN:
            raise ValueError(f"status, speed, angle and fault span {max(read) - min(read) + 1} "
                             f"registers: at most {READ_SPAN}, read in one request")  # fmt: skip
        return self

    @property
    def where(self) -> str:
        """The inverter in a message: ``modbus HOST:PORT unit U`` or ``modbus rtu DEVICE
        unit U``."""
        if self.transport == "rtu":
            return f"modbus rtu {self.device} unit {self.unit}"
        return f"modbus {self.host}:{self.port} unit {self.unit}"

    @property
    def first_read(self) -> int:
        return min(self.status, self.speed, self.angle, self.fault)

    @property
    def read_count(self) -> int:
        return max(self.status, self.speed, self.angle, self.fault) - self.first_read + 1
