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
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.core import Diagnostic
from stand.drivers.checks import check_accel, check_clock, check_mark, recorded_rate
from stand.drivers.frames import FLAG_EXTENDED, FLAG_FD, Frames
from stand.drivers.one_clock import BlockBuilder, Blocks, kept, mark_edges, one_clock_stream
from stand.drivers.scan.layout import ScanLayout
from stand.drivers.streams import RunStreams
from stand.errors import ConfigError

GAP_FACTOR = 1.5
"""Without a counter: receive times further apart than this many sample periods are a gap."""


def _index(layout: ScanLayout, raw_counter: NDArray[Any] | None, t: NDArray[np.float64]
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
    counter: NDArray[np.int64] = raw_counter.astype(np.int64)
    step = np.diff(counter) % period
    index = np.concatenate(([0], np.cumsum(step))).astype(np.int64) + int(raw_counter[0])
    keep = np.concatenate(([True], step != 0))  # a repeated counter: a duplicate frame
    lost = int(np.sum(np.maximum(step[step != 0] - 1, 0)))
    return index[keep], keep, lost, []


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


@dataclass
class _Parts(Blocks):
    """What the module's frames left, block by block: per scan its counter's raw value
    (if mapped), its frame's place in its block (``base`` + ``at``: its arrival number),
    receive time, and the three inputs' raw values, about 20 bytes."""

    counter: list[NDArray[Any]] = field(default_factory=list)
    t: list[NDArray[Any]] = field(default_factory=list)
    accel: tuple[list[NDArray[Any]], list[NDArray[Any]]] = field(default_factory=lambda: ([], []))
    mark: list[NDArray[Any]] = field(default_factory=list)


class ScanBuilder(BlockBuilder):
    """A scan module's frames decoded as they come (:class:`stand.drivers.family.
    FrameBuilder`): each block's scans reduced to their counter, time and inputs (about
    30 bytes a scan); ``streams`` and ``tail`` build the supports' streams from them."""

    layout: ScanLayout

    def _reset(self) -> None:
        self._unknown = 0
        self._t0: float | None = None
        self._t1 = 0.0
        self._parts = _Parts()

    def add(self, frames: Frames) -> None:
        """Decode a block of frames (in arrival order, after those added before)."""
        if not len(frames):
            return
        layout, parts = self.layout, self._parts
        sig0 = layout.channels[0].signal
        ext = (frames.flags & FLAG_EXTENDED) != 0
        need = layout.per_frame * layout.scan_bytes  # a frame's bytes
        mine = (frames.can_id == sig0.frame_id) & (ext == sig0.extended) & (frames.dlc >= need)
        mine &= need <= frames.data.shape[1]
        if mine.any() and int(frames.dlc[mine].min()) >= 2 * need:
            raise ConfigError(f"the module's frames carry {int(frames.dlc[mine].min())} bytes "
                              f"or more, [bus.scan] reads {layout.per_frame} scan(s) of "
                              f"{layout.scan_bytes} bytes a frame: set scans_per_frame (CAN FD)",
                              key="bus.scan.scans_per_frame")  # fmt: skip
        at = np.flatnonzero(mine)
        data, t = _scans(frames.data[at], frames.t_s[at], layout)
        parts.base.append(self.frames)
        parts.at.append(np.repeat(at.astype(np.int32), layout.per_frame))
        parts.t.append(t)
        if layout.counter is not None:
            parts.counter.append(layout.counter.raw(data))
        for k in (0, 1):
            parts.accel[k].append(layout.accel(k + 1).signal.raw(data))
        parts.mark.append(layout.mark.signal.raw(data))
        self._unknown += len(frames) - len(at)
        self._t0 = float(frames.t_s[0]) if self._t0 is None else self._t0
        self._t1 = float(frames.t_s[-1])
        self.frames += len(frames)
        self.last_block = frames

    def _build(self, first: int, consume: bool) -> RunStreams:
        layout, parts = self.layout, self._parts
        span = self._t1 - (self._t0 if self._t0 is not None else 0.0)
        t = parts.joined(parts.t, first, consume)
        if not len(t):  # none of the module's frames: no node (the measuring path says so)
            return RunStreams({}, self.frames, self._unknown, 0, (), span)
        raw_counter = parts.joined(parts.counter, first, consume) if parts.counter else None
        index, keep, lost, warn = _index(layout, raw_counter, t)
        t = kept(t, keep)
        check_clock(layout.rate_hz, recorded_rate(index, t), layout.source, "bus.scan.rate_hz")
        mark = layout.mark
        v = kept(parts.joined(parts.mark, first, consume), keep) * mark.signal.factor
        v += mark.signal.offset
        check_mark(v, mark.signal.name, layout.source)
        marks = mark_edges(v, index, layout.mark_threshold)
        nodes = {}
        for support in (1, 2):
            ch = layout.accel(support)
            counts = kept(parts.joined(parts.accel[support - 1], first, consume), keep)
            check_accel(counts, ch.signal.name, support, layout.source)
            shift = (mark.delay_s - ch.delay_s) * layout.rate_hz
            nodes[support] = one_clock_stream(
                support, layout.rate_hz, index, counts, ch.signal.factor * ch.scale,
                marks, shift, t, lost, int(np.count_nonzero(~keep)),
            )  # fmt: skip
        warn.extend(Diagnostic("description_stored", note) for note in layout.notes)
        return RunStreams(nodes, self.frames, self._unknown, 0, (), span, tuple(warn))


def scan_streams(frames: Frames, layout: ScanLayout) -> RunStreams:
    """The two supports' streams of a scan-stream recording (frames in arrival order)."""
    builder = ScanBuilder(layout)
    builder.add(frames)
    return builder.streams(release=True)


def scan_frames(layout: ScanLayout, t_s: NDArray[np.float64],
                accel_counts: tuple[NDArray[Any], NDArray[Any]], mark_counts: NDArray[Any],
                *, first_counter: int = 0) -> Frames:  # fmt: skip
    """The module's frames by its layout (the encoder of :class:`ScanBuilder`'s decoding):
    each scan's counter (where the layout maps one), accelerations and mark as raw
    counts, at its sample time ``t_s``; with ``per_frame`` k > 1, CAN FD frames of k
    scans, each sent at its last scan's time (a partial frame at the end is not sent)."""
    n = len(t_s)
    words = np.zeros(n, np.uint64)
    signals = [(layout.accel(1).signal, accel_counts[0]), (layout.accel(2).signal,
               accel_counts[1]), (layout.mark.signal, mark_counts)]  # fmt: skip
    if layout.counter is not None:
        period = 1 << layout.counter.length
        signals.append((layout.counter, (np.arange(n) + first_counter) % period))
    for sig, values in signals:
        words |= sig.encode(np.asarray(values))
    b, k = layout.scan_bytes, layout.per_frame
    rows = words.view(np.uint8).reshape(n, 8)[:, :b]
    frame_id = layout.channels[0].signal.frame_id
    if k == 1:
        return Frames.build(t_s, frame_id, np.pad(rows, ((0, 0), (0, 8 - b))), dlc=b)
    m = n // k * k
    return Frames.build(t_s[k - 1 : m : k], frame_id, rows[:m].reshape(-1, k * b),
                        dlc=k * b, flags=FLAG_FD)  # fmt: skip


def mark_wave(phase_rad: NDArray[np.float64], rise_rad: float) -> NDArray[np.float64]:
    """The once-per-revolution sensor's analog output, 0..1: high for half a turn from the
    mark on, each edge a linear ramp ``rise_rad`` wide centred on it (an optical sensor
    behind its anti-alias filter), so a threshold of 1/2 crosses at the mark exactly."""
    x = np.mod(phase_rad, 2 * math.pi)
    up = np.clip((x + rise_rad / 2) / rise_rad, 0.0, 1.0)
    down = np.clip((math.pi - x + rise_rad / 2) / rise_rad, 0.0, 1.0)
    wrap = np.clip((x - 2 * math.pi + rise_rad / 2) / rise_rad, 0.0, 1.0)
    return np.maximum(np.minimum(up, down), wrap)
