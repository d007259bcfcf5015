"""Per-node sample streams rebuilt from decoded frames.

For every node: the sample index and acceleration of every valid sample,
the reference edges as sub-sample positions, the node's rate and scale, its
flags, and the bookkeeping (lost frames, invalid samples, restarts).  The
rules (``spec/can-protocol.md``):

* ``seq`` is unwrapped; a forward jump is lost frames, whose samples are
  missing: later samples keep their true index (a gap is never closed by
  concatenation).  A repeated ``seq`` is a duplicate and is dropped.
* A node restart starts a new *segment*, with its own sample clock: ``seq``
  jumps back, or a STATUS arrives after the node was silent for
  :data:`~stand.drivers.v1.node_build.SILENCE_S` and ``seq`` does not run on as the time that passed
  predicts (if it does, the silence was a bus dropout: lost frames).
  Segment ``k``'s indices only compare with segment ``k``'s.
* The count -32768 is an invalid sample: counted, never a value.
* A MARK is matched to SAMPLES by ``seq``, whichever arrived first: its
  ``seq`` is unwrapped against the nearest SAMPLES frame of the same node.
* Samples are scaled by the node's latest STATUS (the first one for frames
  that came before it).  No STATUS within the node's first
  :data:`~stand.drivers.v1.node_build.STATUS_WITHIN_S` of frames is an error in strict
  mode, a warning otherwise.
* STATUS flags become warnings, with the time they were seen.

Everything is vectorised per node; nodes are few (1..15).  This module holds
the streams' rebuilding from protocol-v1 frames, whole or as they come
(:class:`StreamBuilder`); one node's stream is built by
:mod:`stand.drivers.v1.node_build`, where the rules above are carried out step by step.
"""

from __future__ import annotations

from dataclasses import fields
from itertools import pairwise
from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.core import Diagnostic
from stand.drivers.frames import READ_ROWS, Frames
from stand.drivers.streams import NodeStream, RunStreams
from stand.drivers.v1.codec import concat_decoded, decode
from stand.drivers.v1.node_build import rebuild_node
from stand.drivers.v1.protocol import Decoded, node_records, shift_decoded
from stand.i18n.words import said


def rebuild(frames: Frames, *, strict_status: bool = True) -> RunStreams:
    """Rebuild every node's stream from a run's frames (arrival order).

    Parameters
    ----------
    frames
        All frames of the run, in the order they arrived.
    strict_status
        If True, a node without STATUS in its first
        :data:`~stand.drivers.v1.node_build.STATUS_WITHIN_S`
        raises :class:`~stand.errors.NoStatusError`; if False it is a warning
        (and a node with no STATUS at all has ``accel_m_s2 = None``).

    Returns
    -------
    RunStreams
        Nodes by id, counts of unknown and bad frames, duration, warnings.
    """
    return rebuild_decoded(decode(frames), frames.t_s, strict_status=strict_status)


def rebuild_decoded(
    dec: Decoded | list[Decoded],
    t_s: NDArray[np.float64],
    *,
    strict_status: bool = True,
    release: bool = False,
) -> RunStreams:
    """:func:`rebuild` from frames already decoded (``t_s``: every frame's host time [s]).

    ``dec`` may be the decoded blocks one after the other: each node's records
    are gathered from them on their own, so the blocks are never joined whole.
    ``release``: the list of blocks is this function's to empty once every
    node's records are gathered (a long run's blocks are let go before the
    nodes are rebuilt: 140 MiB less at the peak of a one-hour run).
    """
    parts = [dec] if isinstance(dec, Decoded) else dec
    t0 = float(t_s[0]) if len(t_s) else 0.0
    seen = np.zeros(256, np.int64)  # node ids are u8: a count per id, in one pass each
    for p in parts:
        for records in (p.samples, p.status, p.marks):
            seen += np.bincount(records.node, minlength=256)
    present = [int(n) for n in np.flatnonzero(seen)]

    bad = tuple(b for p in parts for b in p.bad)
    errors = sum(p.error_frames for p in parts)
    unknown = sum(p.unknown_frames for p in parts)
    if len(parts) == 1:
        mine = dict.fromkeys(present, parts[0])
    else:
        mine = {node: node_records(parts, node) for node in present}
    if release and isinstance(dec, list):
        dec.clear()
    del parts
    nodes: dict[int, NodeStream] = {}
    warnings: list[Diagnostic] = []
    for node in present:
        stream, w = rebuild_node(node, mine.pop(node), t_s, t0, strict_status)
        nodes[node] = stream
        warnings.extend(w)
    if bad:
        b = bad[0]
        warnings.append(
            Diagnostic(
                "bad_frames",
                said(
                    "{n} malformed protocol frame(s) ignored; the first: frame {frame} (id "
                    "{id}): {reason}",
                    n=len(bad),
                    frame=b.frame,
                    id=f"0x{b.can_id:03X}",
                    reason=b.reason,
                ),
                float(len(bad)),
            )
        )
    if errors:
        warnings.append(
            Diagnostic(
                "error_frames", said("{n} CAN error frame(s) on the bus", n=errors), float(errors)
            )
        )
    duration = float(t_s[-1] - t_s[0]) if len(t_s) else 0.0
    return RunStreams(
        nodes=nodes,
        frames=len(t_s),
        unknown_frames=unknown,
        error_frames=errors,
        bad=bad,
        duration_s=duration,
        warnings=tuple(warnings),
    )


class StreamBuilder:
    """Frames decoded once, as they arrive; the node streams rebuilt from them on demand.

    A live session :meth:`add` s each block as it comes (decoding it, and
    nothing else); :meth:`streams` rebuilds the nodes from everything
    decoded so far without decoding again.  ``rebuild(frames)`` and a
    builder fed the same frames in any blocks give the same streams.
    ``merge=False`` keeps every block's records apart: a file read once in
    a few large blocks needs no merging (each merge copies the records).
    """

    def __init__(self, *, merge: bool = True) -> None:
        self._merge = merge
        self._parts: list[Decoded] = []
        self._times: list[NDArray[np.float64]] = []
        self._sizes: list[int] = []
        self.frames = 0
        self.last_block = Frames.empty()
        """The block added last (for a display of what just came)."""
        self.read_rows: int | None = READ_ROWS
        """A file is read in blocks of this many frames (decoded one by one)."""
        self.keeps_times = True

    def add(self, frames: Frames) -> None:
        """Decode a block of frames (in arrival order, after those added before)."""
        if not len(frames):
            return
        self.last_block = frames
        self._parts.append(shift_decoded(decode(frames), self.frames))
        self._sizes.append(len(frames))
        self._times.append(frames.t_s)
        self.frames += len(frames)
        # merge the newest blocks while they are as large as the one before them: like a
        # binary counter, a run of n frames is held in about log2(n) parts, and each frame
        # is copied about log2(n) times in all
        while self._merge and len(self._sizes) > 1 and self._sizes[-1] >= self._sizes[-2]:
            self._parts[-2:] = [concat_decoded(self._parts[-2:])]
            self._times[-2:] = [np.concatenate(self._times[-2:])]
            self._sizes[-2:] = [self._sizes[-2] + self._sizes[-1]]

    def streams(self, *, strict_status: bool = True, release: bool = False) -> RunStreams:
        """The node streams of every frame added so far (the blocks are not joined whole).

        ``release``: the builder is done with: its decoded blocks are let go as
        soon as every node's records are gathered from them.
        """
        t_s = _joined(self._times)
        if not release:
            return rebuild_decoded(list(self._parts), t_s, strict_status=strict_status)
        parts, self._parts, self._times, self._sizes = self._parts, [], [], []
        self.frames, self.last_block = 0, Frames.empty()
        return rebuild_decoded(parts, t_s, strict_status=strict_status, release=True)

    def tail(self, from_frame: int) -> RunStreams:
        """The node streams of the frames from ``from_frame`` (arrival order) on.

        Costs what the tail holds, not the run: each part is cut by a binary
        search.  A tail is its own run: its sample indices count from its first
        frame's ``seq``, and a node whose STATUS is older than the tail has no
        scale in it (never an error here).
        """
        from_frame = max(int(from_frame), 0)
        parts, times, at = [], [], 0
        for part, t in zip(self._parts, self._times, strict=True):
            if at + len(t) > from_frame:
                parts.append(shift_decoded(_records_from(part, from_frame), -from_frame))
                times.append(t[max(from_frame - at, 0) :])
            at += len(t)
        t_s = np.concatenate(times) if times else np.zeros(0)
        return rebuild_decoded(parts, t_s, strict_status=False)


def _joined(parts: list[NDArray[np.float64]]) -> NDArray[np.float64]:
    """The arrays one after the other: the very array they are consecutive views of (a run
    file's times, read whole), else a copy."""
    if not parts:
        return np.zeros(0)
    base = parts[0].base
    if (
        isinstance(base, np.ndarray)
        and base.ndim == 1
        and base.dtype == parts[0].dtype
        and base.flags.c_contiguous
        and all(p.base is base and p.flags.c_contiguous for p in parts)
        and all(a.ctypes.data + a.nbytes == b.ctypes.data for a, b in pairwise(parts))
    ):
        start = (parts[0].ctypes.data - base.ctypes.data) // base.itemsize
        joined: NDArray[np.float64] = base[start : start + sum(len(p) for p in parts)]
        return joined
    return np.concatenate(parts)


def _records_from(dec: Decoded, frame: int) -> Decoded:
    """The records of ``dec`` from arrival ``frame`` on (``frame`` indices ascend in a part)."""

    def cut(records: Any) -> Any:
        k = int(np.searchsorted(records.frame, frame))
        if k == 0:
            return records
        return type(records)(**{f.name: getattr(records, f.name)[k:] for f in fields(records)})

    bad = tuple(b for b in dec.bad if b.frame >= frame)
    return Decoded(cut(dec.samples), cut(dec.status), cut(dec.marks), 0, 0, bad)
