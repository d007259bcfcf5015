"""A scan-stream DAQ module described by a DBC: one simultaneous-sampling module carries
both accelerometers and the once-per-revolution sensor as a third analog channel; every
frame is one scan of the module's clock.

The DBC (read with cantools) gives each signal's place in the frame; the frames are
decoded here with numpy, all at once.  The sample index comes from the counter signal
(wrapping at its width; a gap is lost samples, which keep their place, as in protocol
v1); without a counter, from frame order, and a gap the receive times show flags the run
(the samples after it sit early: never a silent shift; as the mark shares their clock,
only the turns that hold a gap are timed wrong).  Mark
edges are the mark channel's rising crossings of its threshold, interpolated linearly
between two consecutive samples, in the same sample units.  Each channel's known constant
delay moves the edges into its own accelerometer's time, so the result is the two
per-node streams the measuring path takes, on one clock.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.core import Diagnostic
from stand.drivers.node_stream import NodeStream
from stand.drivers.protocol import FLAG_EXTENDED, Frames
from stand.drivers.streams import RunStreams
from stand.errors import ConfigError

GAP_FACTOR = 1.5
"""Without a counter: receive times further apart than this many sample periods are a gap."""
MAX_BITS = 16
"""The widest acceleration signal taken (its raw value is the stream's count)."""


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

    def raw(self, data: NDArray[np.uint8]) -> NDArray[np.int64]:
        """The signal's raw integers in frames' payloads ``data`` (n, >= 8 bytes)."""
        word = np.ascontiguousarray(data[:, :8]).view("<u8").reshape(-1)
        mask = np.uint64((1 << self.length) - 1)
        v = ((word >> np.uint64(self.start)) & mask).astype(np.int64)
        if self.signed:
            v = np.where(v >= 1 << (self.length - 1), v - (1 << self.length), v)
        return v


@dataclass(frozen=True)
class Channel:
    """One mapped channel: an acceleration of a support, or the mark."""

    signal: Signal
    role: str
    support: int | None
    scale: float
    delay_s: float


@dataclass(frozen=True)
class ScanLayout:
    """The module: its rate, its counter (if any), its channels."""

    rate_hz: float
    counter: Signal | None
    channels: tuple[Channel, ...]
    mark_threshold: float | None = None
    per_frame: int = 1
    """Scans a frame carries (a CAN FD frame of k scans), ``scan_bytes`` each."""
    scan_bytes: int = 8

    def accel(self, support: int) -> Channel:
        return next(c for c in self.channels if c.role == "accel" and c.support == support)

    @property
    def mark(self) -> Channel:
        return next(c for c in self.channels if c.role == "mark")


def _signal(db: Any, message: str, name: str, source: str) -> Signal:
    try:
        msg = db.get_message_by_name(message)
    except KeyError:
        raise ConfigError(f"the DBC has no message {message!r}", source=source) from None
    sig = next((s for s in msg.signals if s.name == name), None)
    if sig is None:
        raise ConfigError(f"the DBC's message {message} has no signal {name!r}", source=source)
    if sig.byte_order != "little_endian" or sig.start + sig.length > 64:
        raise ConfigError(f"signal {message}.{name}: only little-endian signals within the "
                          "first 8 bytes are read", source=source)  # fmt: skip
    return Signal(f"{message}.{name}", int(msg.frame_id), bool(msg.is_extended_frame),
                  int(sig.start), int(sig.length), bool(sig.is_signed), float(sig.scale),
                  float(sig.offset))  # fmt: skip


def load_layout(table: Any, base: Path, source: str) -> ScanLayout:
    """The layout of a ``[bus.scan]`` table (:class:`stand.config.scan.ScanTable`), its DBC
    read relative to ``base``; a DBC without a named message or signal, or channels in more
    than one message, is one :class:`ConfigError`."""
    import cantools

    path = Path(table.dbc) if Path(table.dbc).is_absolute() else base / table.dbc
    try:
        db = cantools.database.load_file(str(path), database_format="dbc", strict=True)
    except (OSError, ValueError, cantools.database.errors.Error) as exc:
        raise ConfigError(f"[bus.scan] dbc: cannot read {path} as a DBC ({exc})",
                          source=source) from None  # fmt: skip
    channels = []
    for ch in table.channels:
        sig = _signal(db, ch.message, ch.signal, f"{source}, {path.name}")
        if ch.role == "accel" and sig.length > MAX_BITS:
            raise ConfigError(f"{sig.name}: {sig.length} bits; acceleration signals of up to "
                              f"{MAX_BITS} bits are read", source=source)  # fmt: skip
        channels.append(Channel(sig, ch.role, ch.support, ch.scale, ch.delay_s))
    counter = None
    if table.counter is not None:
        counter = _signal(db, channels[0].signal.name.split(".")[0], table.counter, source)
    ids = {c.signal.frame_id for c in channels} | ({counter.frame_id} if counter else set())
    if len(ids) != 1:
        raise ConfigError("[bus.scan] channels: every channel (and the counter) must be in one "
                          "message: one frame is one scan", source=source)  # fmt: skip
    bits = 8 * table.scan_bytes
    for s in (*(c.signal for c in channels), *([counter] if counter else [])):
        if s.start + s.length > bits:
            last = s.start + s.length - 1
            raise ConfigError(f"signal {s.name}: bits {s.start}..{last} lie beyond a scan's "
                              f"{table.scan_bytes} bytes", source=source)  # fmt: skip
    return ScanLayout(float(table.rate_hz), counter, tuple(channels), table.mark_threshold,
                      table.scans_per_frame, table.scan_bytes)  # fmt: skip


def _index(layout: ScanLayout, raw_counter: NDArray[np.int64] | None, t: NDArray[np.float64]
           ) -> tuple[NDArray[np.int64], NDArray[np.bool_], int, list[Diagnostic]]:  # fmt: skip
    """Each kept frame's sample index, which frames are kept (duplicates dropped), the
    samples lost, and the warnings."""
    n = len(t)
    if raw_counter is None:
        gaps = np.flatnonzero(np.diff(t) > GAP_FACTOR / layout.rate_hz)
        warn = []
        if len(gaps):
            warn.append(Diagnostic(
                "scan_gap_without_counter",
                f"{len(gaps)} gap(s) in the receive times of a module without a counter: "
                "frames were lost and the samples after each gap sit early; the turns that "
                "hold a gap are timed wrong (map the module's counter in [bus.scan] counter)",
                float(len(gaps)),
            ))  # fmt: skip
        return np.arange(n, dtype=np.int64), np.ones(n, bool), 0, warn
    assert layout.counter is not None
    period = 1 << layout.counter.length
    step = np.diff(raw_counter) % period
    index = np.concatenate(([0], np.cumsum(step))).astype(np.int64) + int(raw_counter[0])
    keep = np.concatenate(([True], step != 0))  # a repeated counter: a duplicate frame
    lost = int(np.sum(np.maximum(step[step != 0] - 1, 0)))
    return index[keep], keep, lost, []


def revolutions(edges: NDArray[np.float64]) -> tuple[NDArray[np.int64], int]:
    """Each edge's revolution number, counting the turns an edge was lost in (a gap in the
    samples can hide one): the steps between edges in whole median periods; and how many
    edges are missing."""
    if len(edges) < 2:
        return np.arange(len(edges), dtype=np.int64), 0
    d = np.diff(edges)
    steps = np.maximum(1, np.rint(d / np.median(d))).astype(np.int64)
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


def _scans(data: NDArray[np.uint8], t: NDArray[np.float64], layout: ScanLayout
           ) -> tuple[NDArray[np.uint8], NDArray[np.float64]]:  # fmt: skip
    """One row (8 bytes) a scan, from frames of ``per_frame`` scans, each scan timed a
    sample period after the one before it in its frame."""
    k, b = layout.per_frame, layout.scan_bytes
    if k == 1 and b == 8:
        return data, t
    rows = np.zeros((len(data) * k, 8), np.uint8)
    rows[:, :b] = data[:, : k * b].reshape(len(data) * k, b)
    times = (t[:, None] + np.arange(k) / layout.rate_hz).reshape(-1)
    return rows, times


def scan_streams(frames: Frames, layout: ScanLayout) -> RunStreams:
    """The two supports' streams of a scan-stream recording (frames in arrival order)."""
    sig0 = layout.channels[0].signal
    ext = (frames.flags & FLAG_EXTENDED) != 0
    need = layout.per_frame * layout.scan_bytes  # a frame's bytes
    mine = (frames.can_id == sig0.frame_id) & (ext == sig0.extended) & (frames.dlc >= need)
    mine &= need <= frames.data.shape[1]
    if mine.any() and int(frames.dlc[mine].min()) >= 2 * need:
        raise ConfigError(f"the module's frames carry {int(frames.dlc[mine].min())} bytes or "
                          f"more, [bus.scan] reads {layout.per_frame} scan(s) of "
                          f"{layout.scan_bytes} bytes a frame: set scans_per_frame (CAN FD)",
                          key="bus.scan.scans_per_frame")  # fmt: skip
    data, t = _scans(frames.data[mine], frames.t_s[mine], layout)
    span = float(frames.t_s[-1] - frames.t_s[0]) if len(frames) else 0.0
    if not len(t):  # none of the module's frames: no node (the measuring path says so)
        return RunStreams({}, len(frames), len(frames), 0, (), span)
    raw_counter = layout.counter.raw(data) if layout.counter is not None else None
    index, keep, lost, warn = _index(layout, raw_counter, t)
    data, t = data[keep], t[keep]
    mark = layout.mark
    v = (mark.signal.raw(data) * mark.signal.factor + mark.signal.offset).astype(np.float64)
    marks = mark_edges(v, index, layout.mark_threshold)
    nodes = {}
    for support in (1, 2):
        ch = layout.accel(support)
        shift = (mark.delay_s - ch.delay_s) * layout.rate_hz
        nodes[support] = one_clock_stream(
            support, layout.rate_hz, index, ch.signal.raw(data), ch.signal.factor * ch.scale,
            marks, shift, t, lost, int(np.count_nonzero(~keep)),
        )  # fmt: skip
    return RunStreams(nodes, len(frames), int(np.count_nonzero(~mine)), 0, (), span,
                      tuple(warn))  # fmt: skip


def scan_frames(
    t_s: NDArray[np.float64], accel_counts: tuple[NDArray[Any], NDArray[Any]],
    mark_counts: NDArray[Any], *, frame_id: int = 0x300, first_counter: int = 0,
) -> Frames:  # fmt: skip
    """The frames of the simulator's scan module (``scan_module.dbc``): per scan, a u16
    counter, the two accelerations and the mark channel as i16 counts."""
    n = len(t_s)
    data = np.zeros((n, 8), np.uint8)
    words = np.zeros(n, np.uint64)
    counter = (np.arange(n) + first_counter) % 65536
    for k, values in enumerate((counter, *accel_counts, mark_counts)):
        words |= (np.asarray(values).astype(np.int64) & 0xFFFF).astype(np.uint64) << np.uint64(
            16 * k
        )
    data[:] = words.view(np.uint8).reshape(n, 8)
    return Frames.build(t_s, frame_id, data)


def mark_wave(phase_rad: NDArray[np.float64], rise_rad: float) -> NDArray[np.float64]:
    """The once-per-revolution sensor's analog output, 0..1: high for half a turn from the
    mark on, each edge a linear ramp ``rise_rad`` wide centred on it (an optical sensor
    behind its anti-alias filter), so a threshold of 1/2 crosses at the mark exactly."""
    x = np.mod(phase_rad, 2 * math.pi)
    up = np.clip((x + rise_rad / 2) / rise_rad, 0.0, 1.0)
    down = np.clip((math.pi - x + rise_rad / 2) / rise_rad, 0.0, 1.0)
    wrap = np.clip((x - 2 * math.pi + rise_rad / 2) / rise_rad, 0.0, 1.0)
    return np.maximum(np.minimum(up, down), wrap)


class WholeBuilder:
    """A live session's frames, kept as they come and decoded all at once on demand by
    ``decode`` (a scan module's :func:`scan_streams`, or CANopen's): the face of
    :class:`stand.drivers.streams.StreamBuilder` (``add``, ``streams``, ``tail``,
    ``frames``, ``last_block``).  Vectorised, a full pass costs a few milliseconds for a
    minute at 2 kHz."""

    def __init__(self, decode: Callable[[Frames], RunStreams]) -> None:
        self.decode = decode
        self._blocks: list[Frames] = []
        self.frames = 0
        self.last_block = Frames.empty()

    def add(self, frames: Frames) -> None:
        """Keep a block of frames (in arrival order, after those added before)."""
        if len(frames):
            self._blocks.append(frames)
            self.frames += len(frames)
            self.last_block = frames

    def _all(self) -> Frames:
        if len(self._blocks) > 1:
            self._blocks = [Frames.concat(self._blocks)]
        return self._blocks[0] if self._blocks else Frames.empty()

    def streams(self, *, strict_status: bool = True, release: bool = False) -> RunStreams:
        """The two supports' streams of every frame so far (``strict_status`` is v1's: these
        modules send no STATUS)."""
        out = self.decode(self._all())
        if release:
            self._blocks, self.frames, self.last_block = [], 0, Frames.empty()
        return out

    def tail(self, from_frame: int) -> RunStreams:
        """The streams of the frames from ``from_frame`` on, a run of their own."""
        every = self._all()
        return self.decode(every.take(np.arange(max(int(from_frame), 0), len(every))))
