"""The edge towards the hardware.  At the root, what every family shares: a block of
frames (:mod:`~stand.drivers.frames`), the per-support streams
(:mod:`~stand.drivers.streams`), the one-clock mark and sample code
(:mod:`~stand.drivers.one_clock`, its checks :mod:`~stand.drivers.checks`), the live bus
through python-can (:mod:`~stand.drivers.bus`) and the one seam for acquisition hardware
(:mod:`~stand.drivers.family`: a Protocol and the registry of families).  One wing a
family: the sensor nodes' protocol v1 (:mod:`stand.drivers.v1`), a scan-stream module
(:mod:`stand.drivers.scan`), CANopen modules on SYNC (:mod:`stand.drivers.canopen`); and
the run files' own (:mod:`stand.drivers.runs`).  Bad bytes are refused in one line naming
the file and the place.  The numerical core never imports this package; decoding loads
neither python-can nor h5py (they load where a bus or a file is opened).
"""

from stand.drivers.family import FAMILIES, Acquisition, family_of
from stand.drivers.frames import Frames
from stand.drivers.runs.recording import Recording, read_recording, read_streams, write_recording
from stand.drivers.streams import NodeStream, RunStreams

__all__ = [
    "FAMILIES",
    "Acquisition",
    "Frames",
    "NodeStream",
    "Recording",
    "RunStreams",
    "family_of",
    "read_recording",
    "read_streams",
    "write_recording",
]
