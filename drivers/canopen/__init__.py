"""CANopen analog input modules sampling on SYNC (``[bus] protocol = "canopen"``, CiA 301
+ CiA 404): one module per support answers every SYNC with its TPDO1, laid out by its
EDS.  Its ``[bus.canopen]`` table (:mod:`~stand.drivers.canopen.table`), the layout read
from the EDS files (:mod:`~stand.drivers.canopen.layout`), the frames decoded with the
recorded SYNCs as the clock (:mod:`~stand.drivers.canopen.codec`), and the set-up over
SDO before a live recording with the SYNC the host produces
(:mod:`~stand.drivers.canopen.setup`)."""

from __future__ import annotations

from typing import Any

from stand.drivers.canopen.codec import PdoBuilder
from stand.drivers.canopen.layout import load_pdo_layout
from stand.drivers.canopen.setup import CanopenSetup
from stand.drivers.canopen.table import CanopenTable
from stand.drivers.one_clock import OneClockFamily


class Canopen(OneClockFamily):
    """CANopen modules on SYNC as an :class:`~stand.drivers.family.Acquisition`."""

    def setup(self, layout: Any) -> CanopenSetup | None:
        """The modules set up over SDO and clocked by the host's SYNC, where the config says
        so (``configure``)."""
        return CanopenSetup(layout) if layout.configure else None


FAMILY = Canopen("canopen", CanopenTable, load_pdo_layout, PdoBuilder)
