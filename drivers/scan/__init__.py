"""A scan-stream DAQ module (``[bus] protocol = "scan"``): one simultaneous-sampling
module whose frames each carry one scan (or k scans in a CAN FD frame) of both
accelerometers and the reference sensor, laid out by a DBC.  Its ``[bus.scan]`` table
(:mod:`~stand.drivers.scan.table`), the layout read from the DBC
(:mod:`~stand.drivers.scan.layout`), and the frames decoded and encoded
(:mod:`~stand.drivers.scan.codec`)."""

from stand.drivers.one_clock import OneClockFamily
from stand.drivers.scan.codec import ScanBuilder
from stand.drivers.scan.layout import load_layout
from stand.drivers.scan.table import ScanTable

FAMILY = OneClockFamily("scan", ScanTable, load_layout, ScanBuilder)
"""The scan-stream module as an :class:`~stand.drivers.family.Acquisition`."""
