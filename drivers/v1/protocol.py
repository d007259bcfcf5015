"""Sensor-node protocol v1 in numpy: a block of raw frames, decoded all at once.

The wire contract is ``spec/can-protocol.md``; its machine-readable form is
``drivers/v1/sensor_node_v1.dbc``, and ``tests/drivers/test_protocol.py`` shows that
:func:`stand.drivers.v1.codec.decode` agrees with cantools' decoding of that DBC
for random frames and that :data:`LAYOUT` below is the DBC's signal layout.
This module holds the layout, the constants and the record types; the
decoder and the encoders are :mod:`stand.drivers.v1.codec`.

Nothing here loops over frames in Python: a block of frames is a few numpy
arrays (:class:`Frames`), and the decoder sorts it into SAMPLES, STATUS and
MARK records with vectorised masks and byte views.  The live reader and the
offline readers share it.

Examples
--------
>>> from stand.drivers.v1.codec import decode, encode_samples
>>> f = encode_samples(node=1, seq=[7], counts=[[10, -32768, -1]], t_s=[0.5])
>>> d = decode(f)
>>> d.samples.node.tolist(), d.samples.seq.tolist(), d.samples.counts.tolist()
([1], [7], [[10, -32768, -1]])
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.drivers.frames import BadFrame as BadFrame  # the v1 decoder's, re-exported

DBC_PATH = Path(__file__).with_name("sensor_node_v1.dbc")
"""The protocol as a DBC file (nodes 1 and 2; more nodes repeat the three messages)."""

PROTOCOL_VERSION = 1
SAMPLES_BASE, STATUS_BASE, MARK_BASE = 0x100, 0x140, 0x180
MAX_NODE = 15
SUPPORT_NODES = (1, 2)
"""The nodes on the supports (support 1, support 2): the ones a measurement needs."""
SAMPLES_PER_FRAME = 3
INVALID_COUNT = -32768
"""The count that marks an invalid sample (sensor fault, overrange): missing data."""
FRAC_SCALE = 65536
"""MARK ``frac`` is in 1/65536 of a sample period."""
WRAP = 65536
"""``seq`` and ``rev`` are u16 counters: they wrap here."""

STATUS_FLAG_NAMES = {0: "overrange", 1: "sensor_fault", 2: "no_reference"}
"""STATUS ``flags`` bits."""

LAYOUT: dict[str, dict[str, tuple[int, str]]] = {
    "SAMPLES": {"seq": (0, "<u2"), "s0": (2, "<i2"), "s1": (4, "<i2"), "s2": (6, "<i2")},
    "STATUS": {"rate": (0, "<u2"), "scale": (2, "<u2"), "flags": (4, "u1"), "version": (5, "u1")},
    "MARK": {"seq": (0, "<u2"), "slot": (2, "u1"), "frac": (3, "<u2"), "rev": (5, "<u2")},
}
"""Byte offset and numpy type of each field (little-endian), per message kind."""


@dataclass(frozen=True)
class SamplesRecords:
    """Decoded SAMPLES frames: ``frame`` is the index into the decoded block."""

    frame: NDArray[np.int64]
    node: NDArray[np.uint8]
    seq: NDArray[np.uint16]
    counts: NDArray[np.int16]  # (n, 3): s0, s1, s2


@dataclass(frozen=True)
class StatusRecords:
    """Decoded STATUS frames."""

    frame: NDArray[np.int64]
    node: NDArray[np.uint8]
    rate: NDArray[np.uint16]
    scale: NDArray[np.uint16]
    flags: NDArray[np.uint8]
    version: NDArray[np.uint8]


@dataclass(frozen=True)
class MarkRecords:
    """Decoded MARK frames."""

    frame: NDArray[np.int64]
    node: NDArray[np.uint8]
    seq: NDArray[np.uint16]
    slot: NDArray[np.uint8]
    frac: NDArray[np.uint16]
    rev: NDArray[np.uint16]


@dataclass(frozen=True)
class Decoded:
    """A block of frames sorted into protocol records.

    Attributes
    ----------
    samples, status, marks
        The well-formed frames of each kind.
    unknown_frames : int
        Frames with other ids (or extended ids): ignored, counted.
    error_frames : int
        CAN error frames reported by the interface.
    bad : tuple of BadFrame
        Frames of a protocol id that are malformed (wrong length, remote
        frame, CAN FD, slot out of range, other protocol version).
    """

    samples: SamplesRecords
    status: StatusRecords
    marks: MarkRecords
    unknown_frames: int
    error_frames: int
    bad: tuple[BadFrame, ...] = field(default=())


def shift_decoded(dec: Decoded, offset: int) -> Decoded:
    """The same records with their ``frame`` indices moved by ``offset`` (a later block)."""
    if offset == 0:
        return dec
    return Decoded(
        samples=replace(dec.samples, frame=dec.samples.frame + offset),
        status=replace(dec.status, frame=dec.status.frame + offset),
        marks=replace(dec.marks, frame=dec.marks.frame + offset),
        unknown_frames=dec.unknown_frames,
        error_frames=dec.error_frames,
        bad=tuple(replace(b, frame=b.frame + offset) for b in dec.bad),
    )


def node_records(parts: Sequence[Decoded], node: int) -> Decoded:
    """Only the records of one node, from decoded blocks one after the other, in one
    array per field (counts and bad frames are left out).

    Each field is gathered straight into its place in one array of the node's
    length: no array per block, and no second copy to join them.
    """

    def gather(records: Sequence[Any]) -> Any:
        at = [np.flatnonzero(r.node == node) for r in records]  # once, then every field
        total = sum(len(a) for a in at)
        out = {}
        for f in fields(records[0]):
            first = getattr(records[0], f.name)
            field = np.empty((total, *first.shape[1:]), first.dtype)
            k = 0
            for r, a in zip(records, at, strict=True):
                np.take(getattr(r, f.name), a, axis=0, out=field[k : k + len(a)])
                k += len(a)
            out[f.name] = field
        return type(records[0])(**out)

    return Decoded(
        gather([p.samples for p in parts]),
        gather([p.status for p in parts]),
        gather([p.marks for p in parts]),
        0,
        0,
    )
