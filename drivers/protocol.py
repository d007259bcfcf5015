"""Sensor-node protocol v1 in numpy: a block of raw frames, decoded all at once.

The wire contract is ``spec/can-protocol.md``; its machine-readable form is
``drivers/sensor_node_v1.dbc``, and ``tests/drivers/test_protocol.py`` shows that
:func:`stand.drivers.codec.decode` agrees with cantools' decoding of that DBC
for random frames and that :data:`LAYOUT` below is the DBC's signal layout.
This module holds the layout, the constants and the record types; the
decoder and the encoders are :mod:`stand.drivers.codec`.

Nothing here loops over frames in Python: a block of frames is a few numpy
arrays (:class:`Frames`), and the decoder sorts it into SAMPLES, STATUS and
MARK records with vectorised masks and byte views.  The live reader and the
offline readers share it.

Examples
--------
>>> from stand.drivers.codec import decode, encode_samples
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
from numpy.typing import ArrayLike, NDArray

DBC_PATH = Path(__file__).with_name("sensor_node_v1.dbc")
"""The protocol as a DBC file (nodes 1 and 2; more nodes repeat the three messages)."""

PROTOCOL_VERSION = 1
SAMPLES_BASE, STATUS_BASE, MARK_BASE = 0x100, 0x140, 0x180
MAX_NODE = 15
SUPPORT_NODES = (1, 2)
"""The nodes on the supports (support 1, support 2): the ones a measurement needs."""
FRAME_DLC = 8
MAX_PAYLOAD = 64
"""The most data bytes any CAN frame carries (CAN FD)."""
SAMPLES_PER_FRAME = 3
INVALID_COUNT = -32768
"""The count that marks an invalid sample (sensor fault, overrange): missing data."""
FRAC_SCALE = 65536
"""MARK ``frac`` is in 1/65536 of a sample period."""
WRAP = 65536
"""``seq`` and ``rev`` are u16 counters: they wrap here."""

# Frame flags (our own bit set, kept per frame in recordings).
FLAG_EXTENDED = 1
FLAG_REMOTE = 2
FLAG_ERROR = 4
FLAG_FD = 8

STATUS_FLAG_NAMES = {0: "overrange", 1: "sensor_fault", 2: "no_reference"}
"""STATUS ``flags`` bits."""

LAYOUT: dict[str, dict[str, tuple[int, str]]] = {
    "SAMPLES": {"seq": (0, "<u2"), "s0": (2, "<i2"), "s1": (4, "<i2"), "s2": (6, "<i2")},
    "STATUS": {"rate": (0, "<u2"), "scale": (2, "<u2"), "flags": (4, "u1"), "version": (5, "u1")},
    "MARK": {"seq": (0, "<u2"), "slot": (2, "u1"), "frac": (3, "<u2"), "rev": (5, "<u2")},
}
"""Byte offset and numpy type of each field (little-endian), per message kind."""


def _u8(a: ArrayLike, n: int) -> NDArray[np.uint8]:
    return np.broadcast_to(np.asarray(a, dtype=np.uint8), (n,)).copy()


@dataclass(frozen=True)
class Frames:
    """A block of raw CAN frames, in arrival order.

    Attributes
    ----------
    t_s : ndarray of float64, shape (n,)
        Host receive timestamps [s] (informational: timing comes from the
        nodes' sample indices).
    can_id : ndarray of uint32, shape (n,)
        Arbitration id (11 or 29 bits, see ``flags``).
    dlc : ndarray of uint8, shape (n,)
        Data length in bytes (0..8, up to 64 for CAN FD).
    data : ndarray of uint8, shape (n, w)
        Payload, zero-padded to the width ``w`` (8, or 64 once a CAN FD
        frame longer than 8 bytes is present): nothing is truncated.
    flags : ndarray of uint8, shape (n,)
        :data:`FLAG_EXTENDED`, :data:`FLAG_REMOTE`, :data:`FLAG_ERROR`,
        :data:`FLAG_FD` bits.
    """

    t_s: NDArray[np.float64]
    can_id: NDArray[np.uint32]
    dlc: NDArray[np.uint8]
    data: NDArray[np.uint8]
    flags: NDArray[np.uint8]

    def __post_init__(self) -> None:
        n = len(self.t_s)
        if not (len(self.can_id) == len(self.dlc) == len(self.flags) == len(self.data) == n):
            raise ValueError("Frames: arrays of different lengths")
        if self.data.ndim != 2 or self.data.shape[1] < FRAME_DLC:
            raise ValueError(f"Frames: data must be (n, >=8) bytes, got {self.data.shape}")

    @classmethod
    def build(
        cls,
        t_s: ArrayLike,
        can_id: ArrayLike,
        data: ArrayLike,
        dlc: ArrayLike | None = None,
        flags: ArrayLike = 0,
    ) -> Frames:
        """Frames from array-likes; ``data`` is (n, 8) bytes, ``dlc`` defaults to 8."""
        t = np.asarray(t_s, dtype=np.float64).reshape(-1)
        n = len(t)
        raw = np.asarray(data, dtype=np.uint8)
        raw = raw.reshape(n, raw.shape[-1] if raw.ndim == 2 else FRAME_DLC)
        if raw.shape[1] < FRAME_DLC:
            raw = np.pad(raw, ((0, 0), (0, FRAME_DLC - raw.shape[1])))
        return cls(
            t_s=t,
            can_id=np.broadcast_to(np.asarray(can_id, dtype=np.uint32), (n,)).copy(),
            dlc=_u8(FRAME_DLC if dlc is None else dlc, n),
            data=np.ascontiguousarray(raw),
            flags=_u8(flags, n),
        )

    @classmethod
    def empty(cls) -> Frames:
        """No frames."""
        return cls.build(np.empty(0), np.empty(0), np.empty((0, FRAME_DLC)))

    @classmethod
    def from_lists(
        cls,
        t_s: Sequence[float],
        can_id: Sequence[int],
        dlc: Sequence[int],
        flags: Sequence[int],
        payloads: Sequence[bytes],
    ) -> Frames:
        """Frames from per-frame Python lists (a block just received, a log just read)."""
        n = len(t_s)
        if n == 0:
            return cls.empty()
        lengths = np.fromiter(map(len, payloads), np.int64, count=n)
        if (lengths == FRAME_DLC).all():  # the protocol's case: one join, one view
            data = np.frombuffer(b"".join(payloads), np.uint8).reshape(n, FRAME_DLC).copy()
        else:
            data = np.zeros((n, max(FRAME_DLC, int(lengths.max()))), np.uint8)
            for i, p in enumerate(payloads):
                data[i, : len(p)] = np.frombuffer(p, np.uint8)
        return cls(
            np.asarray(t_s, np.float64),
            np.asarray(can_id, np.uint32),
            np.asarray(dlc, np.uint8),
            data,
            np.asarray(flags, np.uint8),
        )

    def __len__(self) -> int:
        return len(self.t_s)

    def take(self, index: ArrayLike) -> Frames:
        """The frames at ``index`` (an integer array, a boolean mask or a slice).

        A slice gives views of these arrays (numpy's rule); the others copy.
        """
        i = index if isinstance(index, slice) else np.asarray(index)
        return Frames(self.t_s[i], self.can_id[i], self.dlc[i], self.data[i], self.flags[i])

    @staticmethod
    def concat(blocks: Sequence[Frames]) -> Frames:
        """The blocks one after the other (data widened to the widest block)."""
        blocks = [b for b in blocks if len(b)]
        if not blocks:
            return Frames.empty()
        if len(blocks) == 1:
            return blocks[0]  # nothing to join: no copy
        width = max(b.data.shape[1] for b in blocks)
        data = [
            b.data
            if b.data.shape[1] == width
            else np.pad(b.data, ((0, 0), (0, width - b.data.shape[1])))
            for b in blocks
        ]
        return Frames(
            np.concatenate([b.t_s for b in blocks]),
            np.concatenate([b.can_id for b in blocks]),
            np.concatenate([b.dlc for b in blocks]),
            np.concatenate(data),
            np.concatenate([b.flags for b in blocks]),
        )

    def sorted_by_time(self) -> Frames:
        """The frames in timestamp order (stable: equal times keep their order)."""
        return self.take(np.argsort(self.t_s, kind="stable"))


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
class BadFrame:
    """A frame of a protocol id that cannot be decoded (counted, never fatal)."""

    frame: int
    can_id: int
    reason: str


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
