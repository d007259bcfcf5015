"""The edge towards the hardware: the sensor nodes' CAN protocol and its codec
(:mod:`~stand.drivers.protocol`, :mod:`~stand.drivers.codec`), per-node streams rebuilt
from frames (:mod:`~stand.drivers.streams`), the live bus through python-can
(:mod:`~stand.drivers.bus`), python-can and candump logs (:mod:`~stand.drivers.logs`) and
the run files (:mod:`~stand.drivers.recording`, HDF5).  Bad bytes are refused in one line
naming the file and the place.  The numerical core never imports this package; decoding
loads neither python-can nor h5py (they load where a bus or a file is opened).
"""

from stand.drivers.protocol import Frames
from stand.drivers.recording import Recording, read_recording, read_streams, write_recording
from stand.drivers.streams import NodeStream, RunStreams, rebuild

__all__ = [
    "Frames",
    "NodeStream",
    "Recording",
    "RunStreams",
    "read_recording",
    "read_streams",
    "rebuild",
    "write_recording",
]
