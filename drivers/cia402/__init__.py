"""A CiA 402 servo drive on the stand's CANopen bus (``[drive] family = "cia402"``): its
table (:mod:`~stand.drivers.cia402.table`) and the client that walks its state machine
through the ``canopen`` library's 402 profile (:mod:`~stand.drivers.cia402.client`)."""

from __future__ import annotations

from typing import Any

from stand.drivers.cia402.table import Cia402Table


class Cia402:
    """The family of CiA 402 drives as a :class:`~stand.drivers.drive.DriveFamily`."""

    name = "cia402"
    table = Cia402Table
    commanded = True

    def connect(self, table: Any, ctx: Any) -> Any:
        from stand.drivers.cia402.client import Cia402Drive

        return Cia402Drive(table, ctx)


FAMILY = Cia402()
