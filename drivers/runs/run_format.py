"""A run file's names: its format's name and version, its attributes, the frames' fields,
and the :class:`Recording` read from it (:mod:`stand.drivers.runs.recording` reads and writes
run files, :mod:`stand.drivers.runs.run_writer` writes one as it is recorded)."""

from __future__ import annotations

import datetime as _dt
import hashlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from stand.core import Diagnostic
from stand.drivers.frames import Frames

RUN_FORMAT = "rotor-stand-run"
RUN_FORMAT_VERSION = 1
RUN_SUFFIXES = (".h5", ".hdf5")
JOB_ATTR = "job_json"
"""Run file attribute: the job the run was made for (JSON: serial, order, operator, note)."""
MATRIX_ATTR = "influence_matrix_json"
"""Run file attribute: the stored influence matrix the run was measured with (its JSON)."""
STAND_ATTR = "stand_id"
"""Run file attribute: the id of the stand that recorded the run (``[stand] id``, else its
host name), so a plant's shared archive knows where each run was made."""
CANOPEN_SETUP_ATTR = "canopen_setup"
"""Run file attribute: how the CANopen modules were set up over SDO before the run (JSON: a
list of steps, :mod:`stand.drivers.canopen.setup`)."""
TEST_UNBALANCE_ATTR = "test_unbalance_json"
"""Run file attribute: the test unbalance a simulated start of a ball balancer's test
carried (JSON: ``[[re, im], [re, im]]`` per plane, kg m, ``U = q R e^{-i phi}``)."""
DESCRIPTIONS_ATTR = "descriptions_json"
"""Run file attribute: the description files (DBC, EDS) the run was recorded through
(JSON: ``{file name: text}``), so that it decodes as recorded even after a file changed
(:func:`stand.drivers.family.read_description`)."""
CARRIED_ATTRS = (JOB_ATTR, MATRIX_ATTR, STAND_ATTR, CANOPEN_SETUP_ATTR, TEST_UNBALANCE_ATTR,
                 DESCRIPTIONS_ATTR)  # fmt: skip
"""Text attributes a converted or rewritten run keeps."""
FRAME_FIELDS = {
    "t_s": np.float64,
    "can_id": np.uint32,
    "dlc": np.uint8,
    "flags": np.uint8,
}


@dataclass(frozen=True)
class Recording:
    """The frames of a run and what is known about it.

    ``meta`` holds the run file's attributes (``software``, ``start_time``,
    ``source``, ``config_toml``, ``complete`` ...); it is empty for a plain
    CAN log.  ``warnings`` are those recorded during the run.
    """

    path: str
    frames: Frames
    meta: dict[str, Any] = field(default_factory=dict)
    warnings: tuple[Diagnostic, ...] = ()


def h5py_module() -> Any:
    """h5py, imported where a run file is opened (decoding never needs it)."""
    import h5py

    return h5py


def config_digest(text: str) -> str:
    """SHA-256 of a configuration's text (hex): stored beside it, checked on every read."""

    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def utc_now() -> str:
    """Now, as ISO 8601 in UTC to the millisecond (a run file's times)."""
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="milliseconds")
