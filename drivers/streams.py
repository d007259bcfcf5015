"""Per-support sample streams, whatever family of hardware sent them: :class:`NodeStream`
(one support's samples and reference edges) and :class:`RunStreams` (a run's).  Each
family's decoder builds them from frames (:mod:`stand.drivers.family`); the measuring path
reads nothing else of the hardware."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from stand.core import Diagnostic
from stand.drivers.frame_index import FrameIndex
from stand.drivers.frames import BadFrame

SUPPORT_NODES = (1, 2)
"""The streams a measurement needs: support 1's and support 2's (a v1 node's id is its
support's number)."""
LATE_SHARE = 0.2
"""More than this share of a node's frames in backlogs (left out: which sample each holds
is not known) and no sample's time of that node is trusted: its stream is flagged
:data:`LATE_FLAG` and not measured (a conforming CANopen module never answers past CiA
301's synchronous window; a host too busy to keep the SYNC's pace makes such runs)."""
LATE_FLAG = "late_backlog"
"""The flag of a stream whose samples' times are not known (:data:`LATE_SHARE`)."""
OFF_BEAT_FLAG = "sync_off_beat"
"""The flag of a stream whose SYNCs came off the clock's beat for more than
:data:`LATE_SHARE` of its samples: a host that did not keep the SYNC's pace, whose gaps
and bursts leave too few whole revolutions to count the reference mark's edges by."""


@dataclass(frozen=True)
class NodeStream:
    """One node's samples and reference edges.

    Attributes
    ----------
    node : int
        Node id (1 = support 1, 2 = support 2).
    rate_hz : float or None
        Nominal sample rate from STATUS [Hz] (None: no STATUS seen).
    scale_um_s2 : float or None
        Scale from STATUS [µm/s² per count] (the latest one if it changed).
    index : ndarray of int64, or FrameIndex
        Sample index of every valid sample, within its segment; a node whose
        samples are all valid, in one segment, keeps it as its frames' numbers
        (:class:`~stand.drivers.frame_index.FrameIndex`, which reads as the array).
    counts : ndarray of int16
        The count of every valid sample.
    segment_start : ndarray of int64
        Where each segment (node restart) begins in ``index``: segment ``k``
        is ``index[segment_start[k]:segment_start[k + 1]]`` (samples arrive in
        segment order).  ``segment`` gives it per sample.
    scale_start, scale_m_s2 : ndarray or None
        The scale in force, as runs: from ``counts[scale_start[j]]`` on, one
        count is ``scale_m_s2[j]`` [m/s²].  None without STATUS.
        ``accel_m_s2`` and :meth:`accel` apply it; nothing else stores the
        accelerations, so a long run costs 2 bytes a sample and its index (8/3 or 8).
    mark_position : ndarray of float64
        Reference edges, as sample positions (sub-sample) within their segment.
    mark_segment : ndarray of int32
        Segment of every edge.
    mark_rev : ndarray of int64
        Unwrapped revolution counter of every edge.
    frames, samples, invalid_samples, lost_frames, duplicate_frames,
    status_frames, lost_marks : int
        Counts: SAMPLES frames kept, samples received (3 per frame, invalid
        included), invalid samples, frames missing from ``seq`` gaps,
        repeated frames dropped, STATUS frames, edges missing from ``rev``.
    flags : tuple of str
        STATUS flag names seen (``overrange``, ``sensor_fault``, ``no_reference``).
    first_t_s, last_t_s : float
        Host time of the node's first and last frame [s].
    """

    node: int
    rate_hz: float | None
    scale_um_s2: float | None
    index: NDArray[np.int64] | FrameIndex
    counts: NDArray[np.int16]
    segment_start: NDArray[np.int64]
    scale_start: NDArray[np.int64] | None
    scale_m_s2: NDArray[np.float64] | None
    mark_position: NDArray[np.float64]
    mark_segment: NDArray[np.int32]
    mark_rev: NDArray[np.int64]
    frames: int
    samples: int
    invalid_samples: int
    lost_frames: int
    duplicate_frames: int
    status_frames: int
    lost_marks: int
    segments: int
    flags: tuple[str, ...]
    first_t_s: float
    last_t_s: float
    off_beat_samples: int = 0
    """CANopen: samples taken on a SYNC that came off the clock's beat (placed at their own
    time or left out); more than :data:`LATE_SHARE` of them flags :data:`OFF_BEAT_FLAG`."""

    @property
    def marks(self) -> int:
        """Number of reference edges received."""
        return len(self.mark_position)

    @property
    def segment(self) -> NDArray[np.int32]:
        """Segment (node restart count) of every valid sample."""
        sizes = np.diff(np.append(self.segment_start, len(self.index)))
        return np.repeat(np.arange(len(sizes), dtype=np.int32), sizes)

    def segment_bounds(self, k: int) -> tuple[int, int]:
        """``(lo, hi)``: segment ``k``'s samples are ``index[lo:hi]``."""
        lo = int(self.segment_start[k])
        hi = int(self.segment_start[k + 1]) if k + 1 < len(self.segment_start) else len(self.index)
        return lo, hi

    @property
    def accel_m_s2(self) -> NDArray[np.float64] | None:
        """Acceleration of every valid sample [m/s²]; None without STATUS."""
        return None if self.scale_m_s2 is None else self.accel(0, len(self.counts))

    def accel(self, lo: int, hi: int) -> NDArray[np.float64]:
        """Acceleration of the valid samples ``lo:hi`` [m/s²] (scaled as they came)."""
        assert self.scale_start is not None and self.scale_m_s2 is not None, "no STATUS"
        starts = np.clip(self.scale_start, lo, hi) - lo
        sizes = np.diff(np.append(starts, hi - lo))
        if np.count_nonzero(sizes) == 1:  # one scale over the samples: the common case
            one: NDArray[np.float64] = self.counts[lo:hi] * self.scale_m_s2[int(np.argmax(sizes))]
            return one
        scale = np.repeat(self.scale_m_s2, sizes)
        return self.counts[lo:hi] * scale

    def take(self, keep: NDArray[np.bool_]) -> NodeStream:
        """The same node with only the samples where ``keep`` is true (edges unchanged)."""
        pos = np.concatenate(([0], np.cumsum(keep)))
        return replace(
            self,
            index=self.index[keep],
            counts=self.counts[keep],
            segment_start=pos[self.segment_start],
            scale_start=None if self.scale_start is None else pos[self.scale_start],
        )

    def rpm(self) -> float | None:
        """Mean shaft speed from the reference edges [rpm] (None: < 2 edges or no rate).

        Counts revolutions with the ``rev`` counter, so lost MARK frames do
        not bias it; each segment is timed on its own clock.
        """
        if self.rate_hz is None or self.rate_hz <= 0:
            return None
        revs = 0
        samples = 0.0
        for s in np.unique(self.mark_segment).tolist():
            sel = self.mark_segment == s
            if np.count_nonzero(sel) < 2:
                continue
            p, r = self.mark_position[sel], self.mark_rev[sel]
            revs += int(r[-1] - r[0])
            samples += float(p[-1] - p[0])
        if revs == 0 or samples <= 0:
            return None
        return 60.0 * revs * self.rate_hz / samples


@dataclass(frozen=True)
class RunStreams:
    """All nodes of a run, and what did not fit the protocol."""

    nodes: dict[int, NodeStream]
    frames: int
    unknown_frames: int
    error_frames: int
    bad: tuple[BadFrame, ...]
    duration_s: float
    warnings: tuple[Diagnostic, ...] = field(default=())

    @property
    def bad_frames(self) -> int:
        return len(self.bad)
