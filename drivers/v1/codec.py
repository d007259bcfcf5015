"""The sensor nodes' frames decoded and encoded, by the layout of the protocol.

:func:`decode` turns a block of frames into per-kind records (SAMPLES,
STATUS, MARK) in one numpy pass, naming every frame it cannot decode and why
(:class:`BadReason`); the encoders make frames (the simulated nodes, the
tests).  The layout, the constants and the record types are
:mod:`stand.drivers.v1.protocol`'s.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stand.drivers.frames import FLAG_ERROR, FLAG_EXTENDED, FLAG_FD, FLAG_REMOTE, FRAME_DLC, Frames
from stand.drivers.v1.protocol import (
    FRAC_SCALE,
    LAYOUT,
    MARK_BASE,
    MAX_NODE,
    PROTOCOL_VERSION,
    SAMPLES_BASE,
    SAMPLES_PER_FRAME,
    STATUS_BASE,
    BadFrame,
    Decoded,
    MarkRecords,
    SamplesRecords,
    StatusRecords,
)


class BadReason(enum.IntEnum):
    """Why a frame of a protocol id cannot be decoded (0: it can)."""

    FINE = 0
    REMOTE = 1
    CAN_FD = 2
    WRONG_LENGTH = 3
    SLOT = 4
    VERSION = 5

    def describe(self, dlc: int, d8: NDArray[np.uint8]) -> str:
        """The reason in words, with the figure from the frame (its DLC and 8 bytes)."""
        if self is BadReason.WRONG_LENGTH:
            return f"wrong length: DLC {dlc}, expected {FRAME_DLC}"
        if self is BadReason.SLOT:
            return f"MARK slot {_field(d8[None], None, 'MARK', 'slot')[0]}, expected 0..2"
        if self is BadReason.VERSION:
            got = _field(d8[None], None, "STATUS", "version")[0]
            return f"STATUS protocol version {got}, expected {PROTOCOL_VERSION}"
        return {
            BadReason.REMOTE: "remote frame on a protocol id",
            BadReason.CAN_FD: "CAN FD frame, expected classic CAN",
        }.get(self, "")


def _field(d8: NDArray[np.uint8], rows: NDArray[np.int64] | None, kind: str, name: str) -> NDArray:  # type: ignore[type-arg]
    """Field ``name`` of message ``kind`` in the frames ``rows`` of ``d8`` (None: all), by
    :data:`LAYOUT`: the decoder and the encoders read and write through it."""
    offset, dtype = LAYOUT[kind][name]
    size = np.dtype(dtype).itemsize
    cols = d8[:, offset : offset + size] if rows is None else d8[rows, offset : offset + size]
    return np.ascontiguousarray(cols).view(dtype).reshape(-1)


def _put(data: NDArray[np.uint8], kind: str, name: str, values: ArrayLike) -> None:
    """Write field ``name`` of message ``kind`` into every row of ``data`` (by :data:`LAYOUT`)."""
    offset, dtype = LAYOUT[kind][name]
    n = len(data)
    size = np.dtype(dtype).itemsize
    v = np.ascontiguousarray(np.broadcast_to(np.asarray(values), (n,)).astype(dtype))
    data[:, offset : offset + size] = v.view(np.uint8).reshape(n, size)


def _counts(b: NDArray[np.uint8]) -> NDArray[np.int16]:
    """The SAMPLES frames' counts ``s0, s1, s2`` (n, 3) int16, by :data:`LAYOUT`: one copy
    of their bytes when the layout keeps them side by side (it does), else field by field."""
    offsets = [LAYOUT["SAMPLES"][f"s{k}"] for k in range(SAMPLES_PER_FRAME)]
    first = offsets[0][0]
    if all(o == (first + 2 * k, "<i2") for k, o in enumerate(offsets)):
        cols = np.ascontiguousarray(b[:, first : first + 2 * SAMPLES_PER_FRAME])
        return cols.view("<i2").reshape(len(b), SAMPLES_PER_FRAME).astype(np.int16, copy=False)
    fields = [_field(b, None, "SAMPLES", f"s{k}") for k in range(SAMPLES_PER_FRAME)]
    return np.stack(fields, -1).astype(np.int16, copy=False)


def _rows(d8: NDArray[np.uint8], r: NDArray[np.int64]) -> NDArray[np.uint8]:
    """Rows ``r`` of the frames' 8 bytes: gathered as one 8-byte word each where the
    bytes lie row after row (a fifth of the time of a gather of 8-byte rows)."""
    if d8.flags.c_contiguous and d8.shape[1] == 8:
        words: NDArray[np.uint8] = d8.view(np.uint64)[:, 0].take(r).view(np.uint8)
        return words.reshape(len(r), 8)
    return d8[r]


def _records(
    d8: NDArray[np.uint8], node: NDArray[np.uint8], rows: dict[str, NDArray[np.int64]]
) -> tuple[SamplesRecords, StatusRecords, MarkRecords]:
    """The records of each kind from the good frames' 8 bytes, by :data:`LAYOUT` (each
    kind's rows gathered once, its fields then cut from them)."""
    r = rows["SAMPLES"]
    b = _rows(d8, r)
    samples = SamplesRecords(
        frame=r,
        node=node[r],
        seq=_field(b, None, "SAMPLES", "seq"),
        counts=_counts(b),
    )
    r = rows["STATUS"]
    b = _rows(d8, r)
    status = StatusRecords(
        frame=r,
        node=node[r],
        rate=_field(b, None, "STATUS", "rate"),
        scale=_field(b, None, "STATUS", "scale"),
        flags=_field(b, None, "STATUS", "flags"),
        version=_field(b, None, "STATUS", "version"),
    )
    r = rows["MARK"]
    b = _rows(d8, r)
    marks = MarkRecords(
        frame=r,
        node=node[r],
        seq=_field(b, None, "MARK", "seq"),
        slot=_field(b, None, "MARK", "slot"),
        frac=_field(b, None, "MARK", "frac"),
        rev=_field(b, None, "MARK", "rev"),
    )
    return samples, status, marks


def decode(frames: Frames) -> Decoded:
    """Sort and decode a block of frames, all at once.

    Parameters
    ----------
    frames
        Any frames, in arrival order.

    Returns
    -------
    Decoded
        Records of each kind carry ``frame``, their index in ``frames``.
    """
    cid = frames.can_id.astype(np.uint32, copy=False)  # ids are 29 bits: 4 bytes do
    error = (frames.flags & FLAG_ERROR) != 0
    standard = (frames.flags & (FLAG_EXTENDED | FLAG_ERROR)) == 0
    base = cid & np.uint32(~0x3F & 0xFFFFFFFF)
    node = (cid & np.uint32(0x3F)).astype(np.uint8)
    protocol = standard & ((base == SAMPLES_BASE) | (base == STATUS_BASE) | (base == MARK_BASE))
    protocol &= (node >= 1) & (node <= MAX_NODE)

    reason = np.zeros(len(frames), dtype=np.int8)  # BadReason.FINE
    remote = (frames.flags & FLAG_REMOTE) != 0
    fd = (frames.flags & FLAG_FD) != 0
    reason[protocol & (frames.dlc != FRAME_DLC)] = BadReason.WRONG_LENGTH
    reason[protocol & fd] = BadReason.CAN_FD
    reason[protocol & remote] = BadReason.REMOTE
    d8 = frames.data[:, :FRAME_DLC]
    # the fields that can spoil a MARK or a STATUS, read from those frames only
    is_mark = np.flatnonzero(protocol & (base == MARK_BASE) & (reason == 0))
    slot = _field(d8, is_mark, "MARK", "slot")
    reason[is_mark[slot > SAMPLES_PER_FRAME - 1]] = BadReason.SLOT
    is_status = np.flatnonzero(protocol & (base == STATUS_BASE) & (reason == 0))
    version = _field(d8, is_status, "STATUS", "version")
    reason[is_status[version != PROTOCOL_VERSION]] = BadReason.VERSION

    good = protocol & (reason == 0)
    rows = {
        k: np.flatnonzero(good & (base == b))
        for k, b in (("SAMPLES", SAMPLES_BASE), ("STATUS", STATUS_BASE), ("MARK", MARK_BASE))
    }

    samples, status, marks = _records(d8, node, rows)
    bad = [
        BadFrame(
            frame=i,
            can_id=int(cid[i]),
            reason=BadReason(int(reason[i])).describe(int(frames.dlc[i]), d8[i]),
        )
        for i in np.flatnonzero(reason).tolist()
    ]
    return Decoded(
        samples=samples,
        status=status,
        marks=marks,
        unknown_frames=int(np.count_nonzero(~protocol & ~error)),
        error_frames=int(np.count_nonzero(error)),
        bad=tuple(bad),
    )


# --- encoding: what a node sends (the simulator and the tests use it) ---


def encode_samples(node: int, seq: ArrayLike, counts: ArrayLike, t_s: ArrayLike) -> Frames:
    """SAMPLES frames of one node: ``seq`` (u16, wrapped here), ``counts`` (n, 3) int16."""
    seq_a = np.asarray(seq, dtype=np.int64).reshape(-1)
    c = np.asarray(counts, dtype=np.int16).reshape(len(seq_a), SAMPLES_PER_FRAME)
    data = np.zeros((len(seq_a), FRAME_DLC), dtype=np.uint8)
    _put(data, "SAMPLES", "seq", seq_a % 65536)
    for k in range(SAMPLES_PER_FRAME):
        _put(data, "SAMPLES", f"s{k}", c[:, k])
    return Frames.build(t_s, SAMPLES_BASE + node, data)


def encode_status(
    node: int,
    rate: ArrayLike,
    scale: ArrayLike,
    flags: ArrayLike,
    t_s: ArrayLike,
    version: int = PROTOCOL_VERSION,
) -> Frames:
    """STATUS frames of one node (``rate`` Hz, ``scale`` µm/s² per count, ``flags`` bits)."""
    t = np.asarray(t_s, dtype=np.float64).reshape(-1)
    data = np.zeros((len(t), FRAME_DLC), dtype=np.uint8)
    for name, values in (("rate", rate), ("scale", scale), ("flags", flags), ("version", version)):
        _put(data, "STATUS", name, values)
    return Frames.build(t, STATUS_BASE + node, data)


def encode_marks(
    node: int, seq: ArrayLike, slot: ArrayLike, frac: ArrayLike, rev: ArrayLike, t_s: ArrayLike
) -> Frames:
    """MARK frames of one node; ``seq`` and ``rev`` are wrapped to u16 here."""
    t = np.asarray(t_s, dtype=np.float64).reshape(-1)
    data = np.zeros((len(t), FRAME_DLC), dtype=np.uint8)
    _put(data, "MARK", "seq", np.asarray(seq, dtype=np.int64) % 65536)
    _put(data, "MARK", "slot", slot)
    _put(data, "MARK", "frac", frac)
    _put(data, "MARK", "rev", np.asarray(rev, dtype=np.int64) % 65536)
    return Frames.build(t, MARK_BASE + node, data)


def edge_fields(
    position: ArrayLike,
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """MARK ``(F, slot, frac)`` for edges at sample positions ``position`` (>= 0).

    ``frac`` is rounded to the nearest 1/65536 sample; a round-up to a whole
    sample moves the edge to the next sample, as a node would report it.
    """
    p = np.asarray(position, dtype=np.float64)
    ticks = np.rint(p * FRAC_SCALE).astype(np.int64)
    sample, frac = np.divmod(ticks, FRAC_SCALE)
    frame, slot = np.divmod(sample, SAMPLES_PER_FRAME)
    return frame, slot, frac


def concat_decoded(parts: Sequence[Decoded]) -> Decoded:
    """Decoded blocks one after the other (their ``frame`` indices already run on)."""

    def cat(records: Sequence[Any]) -> Any:
        kind = type(records[0])
        return kind(
            **{f.name: np.concatenate([getattr(r, f.name) for r in records]) for f in fields(kind)}
        )

    if not parts:
        return decode(Frames.empty())
    return Decoded(
        samples=cat([p.samples for p in parts]),
        status=cat([p.status for p in parts]),
        marks=cat([p.marks for p in parts]),
        unknown_frames=sum(p.unknown_frames for p in parts),
        error_frames=sum(p.error_frames for p in parts),
        bad=tuple(b for p in parts for b in p.bad),
    )
