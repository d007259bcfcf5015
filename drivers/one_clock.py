"""What the one-clock families share: a signal's place in a frame (:class:`Signal`), a
sampled mark channel's edges (:func:`mark_edges`), one support's stream when its samples
and the mark's share one clock and one index (:func:`one_clock_stream`), and a family made
of a layout reader and a block builder (:class:`OneClockFamily`); the checks the data
allow on a mapping and a clock are :mod:`stand.drivers.checks`.  A scan-stream module
(:mod:`stand.drivers.scan`) and CANopen modules on SYNC (:mod:`stand.drivers.canopen`)
are such families."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.drivers.family import FrameBuilder, Kept
from stand.drivers.frames import Frames
from stand.drivers.streams import NodeStream, RunStreams

BLOCK_ROWS = 1 << 18
"""Frames a one-clock builder reads a file in at a time: what it keeps of a frame is about
22 bytes, so a block smaller than protocol v1's lowers the peak (a 600 s CANopen run:
243 -> 221 MB) at no cost in time."""


def kept(a: NDArray[Any], mask: NDArray[np.bool_]) -> NDArray[Any]:
    """``a[mask]``, without the copy when every element is kept (the common case)."""
    return a if mask.all() else a[mask]


@dataclass
class Blocks:
    """What a block builder keeps, block by block: each block's first arrival number
    (``base``) and its kept frames' places in it (``at``), so that its lists of arrays
    (the subclass's fields) can be joined whole or from an arrival on."""

    base: list[int] = field(default_factory=list)
    at: list[NDArray[Any]] = field(default_factory=list)

    def joined(self, chunks: list[NDArray[Any]], first: int, consume: bool) -> NDArray[Any]:
        """One list's blocks joined, from arrival ``first`` on (``consume``: the list is
        emptied, its blocks let go as soon as they are joined)."""
        whole = (chunks[0] if len(chunks) == 1 else np.concatenate(chunks) if chunks
                 else np.zeros(0, np.int64))  # fmt: skip
        if consume:
            chunks.clear()
        if first <= 0:
            return whole
        arrival = [a.astype(np.int64) + b for a, b in zip(self.at, self.base, strict=True)]
        return whole[np.concatenate(arrival) >= first]


@dataclass(frozen=True)
class Signal:
    """Where one DBC signal lies: its frame, its bits (little-endian), its scaling."""

    name: str
    frame_id: int
    extended: bool
    start: int
    length: int
    signed: bool
    factor: float
    offset: float

    def raw(self, data: NDArray[np.uint8]) -> NDArray[np.integer[Any]]:
        """The signal's raw integers in frames' payloads ``data`` (n, >= 8 bytes): a
        byte-aligned 8, 16 or 32-bit signal as its own type read in place (no 8-byte word
        a frame), any other as int64."""
        if self.start % 8 == 0 and self.length in (8, 16, 32):
            b0, nb = self.start // 8, self.length // 8
            kind = f"<{'i' if self.signed else 'u'}{nb}"
            out: NDArray[np.integer[Any]] = np.ascontiguousarray(data[:, b0 : b0 + nb]).view(kind)
            return out.reshape(-1)
        word = np.ascontiguousarray(data[:, :8]).view("<u8").reshape(-1)
        mask = np.uint64((1 << self.length) - 1)
        v = ((word >> np.uint64(self.start)) & mask).astype(np.int64)
        if self.signed:
            v = np.where(v >= 1 << (self.length - 1), v - (1 << self.length), v)
        return v

    def encode(self, values: NDArray[Any]) -> NDArray[np.uint64]:
        """Raw integers ``values`` placed at the signal's bits of an 8-byte little-endian
        word a frame (the inverse of :meth:`raw`; a frame's signals' words OR-ed)."""
        mask = (1 << self.length) - 1
        return (values.astype(np.int64) & mask).astype(np.uint64) << np.uint64(self.start)


def revolutions(edges: NDArray[np.float64]) -> tuple[NDArray[np.int64], int]:
    """Each edge's revolution number, counting the turns an edge was lost in (a gap in the
    samples can hide one); and how many edges are missing.

    Each step between edges is counted in whole periods of the speed its neighbours turn
    at (the mean of the two beside it in revolutions per sample, at the ends the nearest
    two's line), twice, the second time with the first's counts: a run-up or a coast-down
    changes its period from one revolution to the next, so one period for the whole run
    (its median) would count a slow start's revolutions as many.  Fewer than four edges:
    their median period."""
    if len(edges) < 2:
        return np.arange(len(edges), dtype=np.int64), 0
    d = np.diff(edges)
    if len(d) < 3:
        steps = np.maximum(1, np.rint(d / np.median(d))).astype(np.int64)
    else:
        steps = np.ones(len(d), np.int64)
        for _ in range(2):
            v = steps / d  # revolutions per sample over each step
            near = np.empty_like(v)
            near[1:-1] = 0.5 * (v[:-2] + v[2:])
            near[0] = 2 * v[1] - v[2] if 2 * v[1] - v[2] > 0 else v[1]
            near[-1] = 2 * v[-2] - v[-3] if 2 * v[-2] - v[-3] > 0 else v[-2]
            steps = np.maximum(1, np.rint(d * near)).astype(np.int64)
    return np.concatenate(([0], np.cumsum(steps))), int(np.sum(steps - 1))


def edges_between(
    v: NDArray[np.float64], index: NDArray[np.int64], threshold: float
) -> NDArray[np.float64]:
    """Rising crossings of ``threshold`` between consecutive samples (``index`` one apart),
    as sample positions, linearly interpolated."""
    if len(v) < 2:
        return np.zeros(0)
    a, b = v[:-1], v[1:]
    hit = (a < threshold) & (b >= threshold) & (np.diff(index) == 1)
    k = np.flatnonzero(hit)
    return index[k] + (threshold - a[k]) / (b[k] - a[k])


@dataclass(frozen=True)
class Marks:
    """A mark channel's edges as sample positions, their revolution numbers, and how many
    edges the gaps hid."""

    position: NDArray[np.float64]
    rev: NDArray[np.int64]
    missed: int


def mark_edges(v: NDArray[np.float64], index: NDArray[np.int64], threshold: float | None) -> Marks:
    """The rising crossings of an analog mark channel ``v`` (``threshold`` None: its
    mid-range), counted in turns across gaps."""
    if threshold is None:
        threshold = (float(np.min(v)) + float(np.max(v))) / 2 if len(v) else 0.0
    edges = edges_between(v, index, threshold)
    rev, missed = revolutions(edges)
    return Marks(edges, rev, missed)


def one_clock_stream(
    support: int, rate_hz: float, index: NDArray[np.int64], counts: NDArray[np.int64],
    unit_m_s2: float, marks: Marks, shift: float, t: NDArray[np.float64], lost: int,
    duplicates: int,
) -> NodeStream:  # fmt: skip
    """One support's stream when its samples and the mark's share one clock and one index:
    a count is ``unit_m_s2``; the edges moved back by ``shift`` samples (the channels'
    delay difference)."""
    return NodeStream(
        node=support, rate_hz=rate_hz, scale_um_s2=unit_m_s2 * 1e6, index=index,
        counts=counts.astype(np.int16), segment_start=np.zeros(1, np.int64),
        scale_start=np.zeros(1, np.int64), scale_m_s2=np.array([unit_m_s2]),
        mark_position=marks.position - shift,
        mark_segment=np.zeros(len(marks.position), np.int32), mark_rev=marks.rev,
        frames=len(index), samples=len(index), invalid_samples=0, lost_frames=lost,
        duplicate_frames=duplicates, status_frames=0, lost_marks=marks.missed, segments=1,
        flags=(), first_t_s=float(t[0]) if len(t) else 0.0,
        last_t_s=float(t[-1]) if len(t) else 0.0,
    )  # fmt: skip


class BlockBuilder:
    """What a one-clock family's builder shares (:class:`stand.drivers.family.
    FrameBuilder`): its counters, the block size a file is read in, ``streams`` and
    ``tail`` from what it kept.  A subclass keeps a block's values in :meth:`add`, starts
    anew in :meth:`_reset` and builds the streams in :meth:`_build`."""

    def __init__(self, layout: Any) -> None:
        self.layout = layout
        self.frames = 0
        self.last_block = Frames.empty()
        self.read_rows: int | None = BLOCK_ROWS
        self.keeps_times = False
        self._reset()

    def _reset(self) -> None:
        raise NotImplementedError

    def _build(self, first: int, consume: bool) -> RunStreams:
        raise NotImplementedError

    def streams(self, *, strict_status: bool = True, release: bool = False) -> RunStreams:
        """The supports' streams of every frame so far (``strict_status`` is v1's: these
        devices send no STATUS); ``release``: the builder is done and starts anew."""
        out = self._build(0, consume=release)
        if release:
            self.frames, self.last_block = 0, Frames.empty()
            self._reset()
        return out

    def tail(self, from_frame: int) -> RunStreams:
        """The streams of the frames from ``from_frame`` on (their samples keep the run's
        indices: a tail's samples keep their place)."""
        return self._build(max(int(from_frame), 0), consume=False)


class OneClockFamily:
    """A family whose devices sample on one clock: its layout read by ``load(table, base,
    source, stored)``, its frames decoded block by block by the builder ``build(layout)``
    makes (a run decoded whole is one block); no set-up on the bus (a family with one
    overrides :meth:`setup`).  Satisfies :class:`stand.drivers.family.Acquisition`."""

    def __init__(self, name: str, table: type[Any], load: Callable[..., Any],
                 build: Callable[[Any], FrameBuilder]) -> None:  # fmt: skip
        self.name, self.table = name, table
        self._load, self._build = load, build

    def layout(self, table: Any, base: Path, source: str, stored: Kept | None = None) -> Any:
        return self._load(table, base, source, stored)

    def decode(self, layout: Any, frames: Frames) -> RunStreams:
        builder = self._build(layout)
        builder.add(frames)
        return builder.streams(release=True)

    def builder(self, layout: Any) -> FrameBuilder:
        return self._build(layout)

    def setup(self, layout: Any) -> Any:
        return None
