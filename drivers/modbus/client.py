"""A frequency inverter over Modbus TCP or RTU as a :class:`~stand.drivers.drive.Drive`: its
state read in one request, commands written as the register map says
(:mod:`stand.drivers.modbus.table`), every fault of the link one
:class:`~stand.errors.DriveError` naming the inverter and the register."""

from __future__ import annotations

import math
import os
import stat
from typing import Any

from stand.drivers.drive import DriveState, close_link
from stand.drivers.modbus.table import (
    CONTROL_INDEX,
    CONTROL_QUICK_STOP,
    CONTROL_RUN,
    ModbusTable,
    status_flags,
)
from stand.errors import DriveError

RPM = math.pi / 30.0
"""rad/s per rpm (the register map's unit)."""


def signed(word: int) -> int:
    """A 16-bit register as a signed number (two's complement)."""
    return word - 0x10000 if word & 0x8000 else word


def serial_line(device: str, where: str) -> None:
    """Refuse a ``device`` that is not a serial line before it is opened (a regular file or
    a FIFO would be read as one, or hang): a character device, or a ``socket://`` URL."""
    if device.startswith("socket://"):
        return
    try:
        mode = os.stat(device).st_mode
    except OSError as exc:
        raise DriveError(f"the serial line: {exc.strerror}", where=where) from exc
    if not stat.S_ISCHR(mode):
        raise DriveError("the serial line is not a character device (a file, a folder or a "
                         "FIFO given as device?)", where=where)  # fmt: skip


def _client(table: ModbusTable, timeout_s: float) -> Any:
    """pymodbus's client for the table's transport (its framing: MBAP or RTU with CRC)."""
    from pymodbus.client import ModbusSerialClient, ModbusTcpClient

    if table.transport == "tcp":
        assert table.host is not None  # the table's validator
        return ModbusTcpClient(table.host, port=table.port, timeout=timeout_s, retries=0)
    assert table.device is not None
    serial_line(table.device, table.where)
    return ModbusSerialClient(table.device, baudrate=table.baudrate, parity=table.parity,
                              stopbits=table.stopbits, bytesize=8, timeout=timeout_s,
                              retries=0)  # fmt: skip


class ModbusDrive:
    """One inverter on Modbus TCP or RTU (pymodbus's client: its framing, transaction ids
    and CRC)."""

    def __init__(self, table: ModbusTable, *, timeout_s: float) -> None:
        self.map = table
        self.where = table.where
        self._client: Any = _client(table, timeout_s)
        self._running = False
        connect: Any = self._client.connect  # (pymodbus's connect is untyped)
        if not connect():
            raise DriveError("does not answer (no connection)", where=self.where)

    def _call(self, what: str, register: int, fn: Any, *args: Any, **kwargs: Any) -> Any:
        from pymodbus.exceptions import ModbusException

        try:
            reply = fn(*args, device_id=self.map.unit, **kwargs)
        except (ModbusException, OSError) as exc:
            raise DriveError(f"{what} register {register}: no answer ({exc})",
                             where=self.where) from exc  # fmt: skip
        if reply.isError():
            raise DriveError(f"{what} register {register}: refused ({reply})", where=self.where)
        return reply

    def read(self) -> DriveState:
        m = self.map
        reply = self._call("reading", m.first_read, self._client.read_holding_registers,
                           m.first_read, count=m.read_count)  # fmt: skip
        regs = list(reply.registers)
        if len(regs) != m.read_count:
            raise DriveError(f"reading register {m.first_read}: {len(regs)} registers "
                             f"answered, {m.read_count} asked", where=self.where)  # fmt: skip

        def at(register: int) -> int:
            return int(regs[register - m.first_read])

        flags, counts = status_flags(at(m.status)), at(m.angle)
        if counts >= m.counts_per_rev:
            raise DriveError(f"angle register {m.angle}: {counts} counts, the map says "
                             f"{m.counts_per_rev} a revolution", where=self.where)  # fmt: skip
        return DriveState(
            speed_rad_s=signed(at(m.speed)) / m.speed_per_rpm * RPM,
            angle_rad=2 * math.pi * counts / m.counts_per_rev,
            ready=flags["ready"],
            at_speed=flags["at_speed"],
            standstill=flags["standstill"],
            in_position=flags["in_position"],
            guard_closed=flags["guard_closed"],
            estop_clear=flags["estop_clear"],
            fault_code=at(m.fault) or (1 if flags["fault"] else 0),
        )

    def _write(self, what: str, register: int, value: int) -> None:
        self._call(f"writing {what} to", register, self._client.write_register, register, value)

    def run(self, omega_rad_s: float) -> None:
        m = self.map
        counts = round(omega_rad_s / RPM * m.speed_per_rpm)
        if not 0 <= counts <= 0x7FFF:
            raise DriveError(f"set point register {m.set_point}: {omega_rad_s / RPM:.1f} rpm "
                             f"does not fit at {m.speed_per_rpm:g} counts a rpm",
                             where=self.where)  # fmt: skip
        self._write("the set point", m.set_point, counts)
        self._write("run", m.control, CONTROL_RUN)
        self._running = True

    def stop_at(self, angle_rad: float) -> None:
        m = self.map
        counts = round((angle_rad % (2 * math.pi)) / (2 * math.pi) * m.counts_per_rev)
        self._write("the stop angle", m.target, counts % m.counts_per_rev)
        self._write("index", m.control, CONTROL_INDEX)

    def quick_stop(self) -> None:
        self._write("quick stop", self.map.control, CONTROL_QUICK_STOP)
        self._running = False

    def disable(self) -> None:
        self._write("disable", self.map.control, 0)
        self._running = False

    def close(self) -> None:
        close_link(self.quick_stop, self._running, self._client.close)
