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
from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.core import Diagnostic
from stand.drivers.checks import check_accel, check_clock, check_mark, recorded_rate
from stand.drivers.frames import FLAG_EXTENDED, Frames
from stand.drivers.one_clock import mark_edges, one_clock_stream
from stand.drivers.scan.layout import ScanLayout
from stand.drivers.streams import RunStreams
from stand.errors import ConfigError

GAP_FACTOR = 1.5
"""Without a counter: receive times further apart than this many sample periods are a gap."""


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
    check_clock(layout.rate_hz, recorded_rate(index, t), layout.source, "bus.scan.rate_hz")
    mark = layout.mark
    v = (mark.signal.raw(data) * mark.signal.factor + mark.signal.offset).astype(np.float64)
    check_mark(v, mark.signal.name, layout.source)
    marks = mark_edges(v, index, layout.mark_threshold)
    nodes = {}
    for support in (1, 2):
        ch = layout.accel(support)
        counts = ch.signal.raw(data)
        check_accel(counts, ch.signal.name, support, layout.source)
        shift = (mark.delay_s - ch.delay_s) * layout.rate_hz
        nodes[support] = one_clock_stream(
            support, layout.rate_hz, index, counts, ch.signal.factor * ch.scale,
            marks, shift, t, lost, int(np.count_nonzero(~keep)),
        )  # fmt: skip
    warn.extend(Diagnostic("description_stored", note) for note in layout.notes)
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
