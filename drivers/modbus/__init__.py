"""A frequency inverter over Modbus TCP or RTU (``[drive] family = "modbus"``): its register map
(:mod:`~stand.drivers.modbus.table`) and the client that commands it
(:mod:`~stand.drivers.modbus.client`, on pymodbus)."""

from __future__ import annotations

from typing import Any

from stand.drivers.modbus.table import ModbusTable


class Modbus:
    """The family of inverters on Modbus TCP or RTU as a
    :class:`~stand.drivers.drive.DriveFamily`."""

    name = "modbus"
    table = ModbusTable
    commanded = True

    def connect(self, table: Any, ctx: Any) -> Any:
        from stand.drivers.modbus.client import ModbusDrive

        return ModbusDrive(table, timeout_s=ctx.timeout_s)


FAMILY = Modbus()
