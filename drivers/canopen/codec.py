"""CANopen analog input modules sampling on SYNC (CiA 301 + CiA 401/404): the recorded
SYNC frames are the sample clock.

Each support's module answers every SYNC with its TPDO1 (transmission type 1), mapping
its accelerometer's and the reference sensor's analog inputs.  The TPDO's layout comes
from the module's EDS (read with the ``canopen`` library: its TPDO1 mapping 0x1A00, the
COB-ID 0x1800 sub 1, the mapped objects' types); the frames are decoded here with numpy.
A TPDO's sample index is the number of SYNCs before it, less one (the SYNC it answers);
a TPDO missing between two SYNCs is a lost sample with its index kept; one delayed past
the next SYNC is put back on its own SYNC when that SYNC has none; a backlog (three or more
on one SYNC, or two where the SYNC before is taken) is left out and counted, never placed
by guess.  Mark edges are the mark input's interpolated threshold crossings (as
:mod:`stand.drivers.scan`), moved into the accelerometer's time by the channels' known
delays.  The module's own word becomes the streams' flags: an input's AI status (CiA 404
0x6150, when mapped) drops a sample marked not valid (``sensor_fault``) and flags an
overload (``overrange``); an EMCY (0x80 + node id) flags ``emcy`` and a boot-up (0x700 +
node id: the module restarted, its TPDOs stop until it is started again) ``restart``,
each also a warning with its time.  The decoder is chosen per bus (``[bus] protocol =
"canopen"``), so TPDO ids that protocol v1 also uses (0x181, 0x182) are read as TPDOs,
never as v1's MARKs.

Frames are decoded block by block as they come (:class:`PdoBuilder`, a live session's and
a file read's): a block's TPDOs leave only their SYNC index, receive time and the mapped
inputs' raw values (about 30 bytes a TPDO); the streams are built from those on demand.
A run is never held whole as frames.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.core import Diagnostic
from stand.drivers.canopen.layout import PdoLayout, PdoNode
from stand.drivers.checks import (
    check_accel,
    check_clock,
    check_distinct,
    check_mark,
    clock_line,
)
from stand.drivers.frames import FLAG_EXTENDED, Frames
from stand.drivers.one_clock import BlockBuilder, Blocks, kept, mark_edges, one_clock_stream
from stand.drivers.streams import (
    LATE_FLAG,
    LATE_SHARE,
    OFF_BEAT_FLAG,
    NodeStream,
    RunStreams,
)

EMCY_BASE, BOOT_BASE = 0x80, 0x700
"""CiA 301's EMCY and NMT error control (boot-up) COB-IDs: the base plus the node id."""


ON_BEAT = 0.5
"""A SYNC within this many periods of its own beat (the SYNCs' line) came on time."""
NEAR_BEAT = 0.1
"""A SYNC that came late is placed on the beat nearest its time when it lies within this
many periods of it (its samples' time then as far off as an on-time SYNC's jitter lets
them be), else its samples are left out."""


def sync_clock(sync_t: NDArray[np.float64], rate_hz: float, source: str
               ) -> NDArray[np.int64] | None:  # fmt: skip
    """The recording is the clock: the SYNC frames' own times checked against the
    configured rate, and each SYNC's sample index, the beat of its own time (-1: left out;
    None: too short a run to judge, each SYNC its own beat).

    The modules sample when a SYNC comes, so the SYNCs' times are the samples' times: their
    line (:func:`~stand.drivers.checks.clock_line`, robust: a stall leaves it where it
    was) gives the rate and the beat, whatever the TPDOs' delivery did.  A SYNC on time
    is its own beat; one that came late (a host that stalled, then caught up in a burst)
    is placed on the beat nearest its time where it lies within :data:`NEAR_BEAT` of it,
    never on the beat it missed; of several SYNCs on one beat (a burst) the nearest is
    kept; the others are left out."""
    line = clock_line(np.arange(len(sync_t)), sync_t)
    if line is None:
        return None
    period, at0 = line
    check_clock(rate_hz, 1.0 / period, source, "bus.canopen.rate_hz")
    off = sync_t - at0
    off /= period
    off -= np.arange(len(sync_t), dtype=np.float64)  # each SYNC off its own beat [periods]
    on = np.abs(off) <= ON_BEAT
    late = np.flatnonzero(~on)
    if not len(late) or bool(np.any(np.diff(sync_t) < 0)):
        return None  # every SYNC on its own beat (the common case), or stamps out of order
    where = off[late] + late
    beat = np.rint(where).astype(np.int64)
    near = np.abs(where - beat)
    ok = (near <= NEAR_BEAT) & (beat >= 0)
    ok &= ~((beat < len(on)) & np.take(on, beat, mode="clip"))  # an on-time SYNC's beat
    order = np.lexsort((near, beat))  # by beat, the nearest first
    first = np.ones(len(order), bool)
    first[1:] = beat[order][1:] != beat[order][:-1]
    nearest = np.zeros(len(late), bool)
    nearest[order[first]] = True
    out = np.arange(len(sync_t), dtype=np.int64)
    out[late] = np.where(ok & nearest, beat, -1)
    return out


def _indices(k: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.bool_], int, int]:
    """Each TPDO's SYNC (``k``: SYNCs before it, less one): of exactly two on one SYNC whose
    SYNC before has none, the first came late and is put back on it (one TPDO late by
    less than two SYNCs); three or more on one SYNC (a backlog: which SYNC each answered
    is not known) are all left out, never placed by guess (a sample put on a later SYNC
    than its own would lag the 1x: a bias no interval holds).  Returns the indices, which
    are kept, how many were put back, how many left out."""
    if not len(k):
        return k, np.zeros(0, bool), 0, 0
    starts = np.flatnonzero(np.concatenate(([True], np.diff(k) != 0)))
    runs = np.diff(np.concatenate((starts, [len(k)])))
    k, keep, moved = k.copy(), np.ones(len(k), bool), 0
    for s, n in zip(starts.tolist(), runs.tolist(), strict=True):
        if n == 2 and k[s] >= 1 and (s == 0 or k[s - 1] < k[s] - 1):
            k[s] -= 1  # the first came late: its own SYNC has none
            moved += 1
        elif n >= 2:
            keep[s : s + n] = False
    keep &= k >= 0
    return k, keep, moved, int(np.count_nonzero(~keep))


MAX_LATE_SYNCS = 64
"""A TPDO's stamp places it at most this many SYNCs before its arrival (:func:`_by_stamp`);
further back, its stamp is not its wire time (a frame sent unstamped)."""


def _by_stamp(k: NDArray[np.int64], t: NDArray[np.float64],
              sync_t: NDArray[np.float64]) -> tuple[NDArray[np.int64], int]:  # fmt: skip
    """Each TPDO's SYNC: the last SYNC before its arrival (``k``), or an earlier one where
    its stamp ``t`` says it was sent before SYNCs that reached the host ahead of it (a
    stamp that is the frame's wire time: a bus stamping in hardware, a simulated module
    stamping the time it answered within its window while its process ran late), at most
    :data:`MAX_LATE_SYNCS` back.  On a recording whose stamps follow the arrival, as a
    host's receive stamps do, this is the arrival's SYNC, always.  Returns the SYNCs and
    how many TPDOs their stamps put back."""
    if not len(k) or len(sync_t) < 2:
        return k, 0
    early = t < np.take(sync_t, k, mode="clip")  # stamped before the SYNC it came after
    early &= (k >= 0) & (k < len(sync_t))
    if not early.any() or bool(np.any(np.diff(sync_t) < 0)):
        return k, 0  # the stamps follow the arrival (the common case), or tell nothing
    at = np.flatnonzero(early)
    by_t = np.searchsorted(sync_t, t[at], side="right") - 1
    use = (by_t >= 0) & (k[at] - by_t <= MAX_LATE_SYNCS)
    out = k.copy()
    out[at[use]] = by_t[use]
    return out, int(np.count_nonzero(use))


def _placed(k: NDArray[np.int64], beats: NDArray[np.int64] | None
            ) -> tuple[NDArray[np.int64], NDArray[np.bool_], int, int, int, int]:  # fmt: skip
    """Each TPDO on its SYNC (:func:`_indices`), then at its SYNC's beat (``beats``:
    :func:`sync_clock`).  Returns the sample indices, which are kept, how many TPDOs were
    put back on their SYNC, how many left out in backlogs, how many placed at a beat
    other than their SYNC's count (off the beat), how many left out with their SYNC."""
    k, keep, moved, dropped = _indices(k)
    if beats is None:
        return k, keep, moved, dropped, 0, 0
    inside = keep & (k < len(beats))
    index = np.where(inside, np.take(beats, k, mode="clip"), -1)
    off = int(np.count_nonzero(inside & (index >= 0) & (index != k)))
    gone = int(np.count_nonzero(inside & (index < 0)))
    return index, keep & (index >= 0), moved, dropped, off, gone


@dataclass
class _Parts(Blocks):
    """What one module's frames left, block by block: per TPDO its SYNC index (less one),
    place in its block (``base`` + ``at``: its arrival number), receive time and the mapped
    inputs' raw values, about 22 bytes; its EMCY and boot-up frames' times and codes."""

    k: list[NDArray[Any]] = field(default_factory=list)
    t: list[NDArray[Any]] = field(default_factory=list)
    accel: list[NDArray[Any]] = field(default_factory=list)
    mark: list[NDArray[Any]] = field(default_factory=list)
    status: tuple[list[NDArray[Any]], list[NDArray[Any]]] = field(default_factory=lambda: ([], []))
    emcy: list[tuple[float, int]] = field(default_factory=list)
    boot: list[float] = field(default_factory=list)


def _said(n: PdoNode, parts: _Parts, t0: float, warn: list[Diagnostic]) -> list[str]:
    """The module's EMCY and boot-up frames as flags and warnings (times from the run's
    first frame)."""
    flags = []
    if parts.emcy:
        said = ", ".join(f"0x{c:04X} at {t - t0:.3f} s" for t, c in parts.emcy[:5])
        more = f" and {len(parts.emcy) - 5} more" if len(parts.emcy) > 5 else ""
        warn.append(Diagnostic("emcy", f"node {n.node_id}: EMCY {said}{more} (CiA 301 error "
                               "codes; 0x0000: the error is gone)",
                               float(len(parts.emcy))))  # fmt: skip
        flags.append("emcy")
    if parts.boot:
        warn.append(Diagnostic("module_restart", f"node {n.node_id}: the module restarted "
                               f"(boot-up at {parts.boot[0] - t0:.3f} s): no TPDO after it "
                               "until it is started again", float(len(parts.boot))))  # fmt: skip
        flags.append("restart")
    return flags


def _status(n: PdoNode, status: list[NDArray[Any] | None], count: int
            ) -> tuple[NDArray[np.bool_], NDArray[np.bool_], list[str]]:  # fmt: skip
    """Per TPDO: the accelerometer's sample valid, the mark's sample valid; the flags (CiA
    404 AI status: bit 0 not valid, bit 1 positive and bit 2 negative overload)."""
    ok = [np.ones(count, bool), np.ones(count, bool)]
    flags = []
    for k, st in enumerate(status):
        if st is None:
            continue
        ok[k] = (st & 1) == 0
        if not ok[k].all():
            flags.append("sensor_fault")
        if ((st & 6) != 0).any():
            flags.append("overrange")
    return ok[0], ok[1], flags


class PdoBuilder(BlockBuilder):
    """CANopen frames decoded as they come (:class:`stand.drivers.family.FrameBuilder`):
    SYNCs counted across blocks, each module's TPDOs reduced to their index and inputs.
    ``streams`` and ``tail`` build the supports' streams from what was kept."""

    layout: PdoLayout

    def _reset(self) -> None:
        self._syncs, self._unknown = 0, 0
        self._sync_t: list[NDArray[np.float64]] = []
        self._t0: float | None = None
        self._t1 = 0.0
        self._parts = {n.node_id: _Parts() for n in self.layout.nodes}

    def add(self, frames: Frames) -> None:
        """Decode a block of frames (in arrival order, after those added before)."""
        if not len(frames):
            return
        std = (frames.flags & FLAG_EXTENDED) == 0
        is_sync = std & (frames.can_id == self.layout.sync_id)
        before = np.cumsum(is_sync, dtype=np.int32)  # SYNCs up to each frame, of the run
        before += self._syncs - 1  # less one, less itself: the SYNC each TPDO answers
        known = is_sync
        for n in self.layout.nodes:
            known = known | self._take(n, frames, std, before)
        self._syncs += int(np.count_nonzero(is_sync))
        self._sync_t.append(frames.t_s[is_sync])
        self._unknown += int(np.count_nonzero(~known))
        self._t0 = float(frames.t_s[0]) if self._t0 is None else self._t0
        self._t1 = float(frames.t_s[-1])
        self.frames += len(frames)
        self.last_block = frames

    def _take(self, n: PdoNode, frames: Frames, std: NDArray[np.bool_],
              before: NDArray[np.int32]) -> NDArray[np.bool_]:  # fmt: skip
        """One module's frames of a block kept; which frames were its."""
        parts = self._parts[n.node_id]
        emcy = std & (frames.can_id == EMCY_BASE + n.node_id) & (frames.dlc >= 3)
        boot = std & (frames.can_id == BOOT_BASE + n.node_id) & (frames.dlc >= 1)
        boot &= frames.data[:, 0] == 0
        for j in np.flatnonzero(emcy):
            parts.emcy.append((float(frames.t_s[j]),
                               int(frames.data[j, 0]) | int(frames.data[j, 1]) << 8))  # fmt: skip
        parts.boot.extend(float(x) for x in frames.t_s[boot])
        rows = std & (frames.can_id == n.cob_id) & (frames.dlc >= 1)
        at = np.flatnonzero(rows)
        data = frames.data[at]
        parts.k.append(before[at])  # int32: 2^31 SYNCs are 12 days at 2 kHz
        parts.base.append(self.frames)
        parts.at.append(at.astype(np.int32))
        parts.t.append(frames.t_s[at])
        parts.accel.append(n.accel.raw(data))
        parts.mark.append(n.mark.raw(data))
        for k, sig in enumerate(n.status):
            if sig is not None:
                parts.status[k].append(sig.raw(data))
        theirs: NDArray[np.bool_] = rows | emcy | boot
        return theirs

    def _build(self, first: int, consume: bool) -> RunStreams:
        warn: list[Diagnostic] = []
        t0 = self._t0 if self._t0 is not None else 0.0
        sync_t = (np.concatenate(self._sync_t) if self._sync_t
                  else np.zeros(0))  # fmt: skip
        if consume:
            self._sync_t.clear()
        clock = (sync_t, sync_clock(sync_t, self.layout.rate_hz, self.layout.source))
        nodes = {}
        for n in self.layout.nodes:
            built = self._node(n, self._parts[n.node_id], first, consume, t0, warn, clock)
            if built is not None:
                nodes[n.support] = built
        warn.extend(Diagnostic("description_stored", note) for note in self.layout.notes)
        out = RunStreams(nodes, self.frames, self._unknown, 0, (), self._t1 - t0, tuple(warn))
        check_distinct(out, self.layout.source)
        return out

    def _node(self, n: PdoNode, parts: _Parts, first: int, consume: bool, t0: float,
              warn: list[Diagnostic], clock: tuple[NDArray[np.float64],
                                                   NDArray[np.int64] | None]
              ) -> NodeStream | None:  # fmt: skip
        """One support's stream from its module's kept TPDOs (``consume``: let go as
        used; ``clock``: the SYNCs' times and each one's beat, :func:`sync_clock`)."""
        said = _said(n, parts, t0, warn)
        t_rx = parts.joined(parts.t, first, consume)
        k_rx = parts.joined(parts.k, first, consume).astype(np.int64)
        k_st, stamped = _by_stamp(k_rx, t_rx, clock[0])
        k, keep, moved, dropped, off, gone = _placed(k_st, clock[1])
        moved += stamped
        if off or gone:
            warn.append(Diagnostic(
                "sync_late", f"node {n.node_id}: {off + gone} sample(s) taken on a SYNC off "
                "the beat (the host's SYNC stalled, then caught up): each placed at its own "
                f"time, {gone} left out (SYNCs a burst put nearest one beat); the clock is "
                "the SYNCs' own", float(off + gone)))  # fmt: skip
        if moved or dropped:
            warn.append(Diagnostic("tpdo_late", f"node {n.node_id}: {moved} TPDO(s) came after "
                                   f"the next SYNC (put back on their own, by their stamps or "
                                   f"as the only one late), {dropped} in a "
                                   "backlog on one SYNC (left out: which SYNC each answered is "
                                   "not known)", float(moved + dropped)))  # fmt: skip
        index, t = kept(k, keep), kept(t_rx, keep)
        if not len(index):
            return None  # nothing from this module: the measuring path says so
        layout, name = self.layout, f"node {n.node_id}"
        status = [kept(parts.joined(st, first, consume), keep) if st else None
                  for st in parts.status]  # fmt: skip
        accel_ok, mark_ok, flags = _status(n, status, len(index))
        accel = kept(kept(parts.joined(parts.accel, first, consume), keep), accel_ok)
        v = kept(kept(parts.joined(parts.mark, first, consume), keep), mark_ok) * n.mark_scale
        check_mark(v, f"{name} {n.mark.name.split(':', 1)[1]}", layout.source)
        check_accel(accel, f"{name} {n.accel.name.split(':', 1)[1]}", n.support, layout.source)
        shift = (n.mark_delay_s - n.accel_delay_s) * layout.rate_hz
        lost = int(index[-1] - index[0] + 1) - len(index)
        stream = one_clock_stream(
            n.support, layout.rate_hz, kept(index, accel_ok), accel, n.accel_scale,
            mark_edges(v, kept(index, mark_ok), layout.mark_threshold), shift, t, lost, dropped,
        )  # fmt: skip
        invalid = len(index) - int(np.count_nonzero(accel_ok))
        if invalid:
            warn.append(Diagnostic("ai_status", f"{name}: {invalid} sample(s) the module "
                                   "marked not valid (AI status), left out",
                                   float(invalid)))  # fmt: skip
        late = [LATE_FLAG] if dropped > LATE_SHARE * (len(index) + dropped) else []
        if off + gone > LATE_SHARE * len(k_rx):
            late.append(OFF_BEAT_FLAG)
        return replace(stream, samples=len(index), invalid_samples=invalid,
                       off_beat_samples=off + gone,
                       flags=tuple(dict.fromkeys([*flags, *said, *late])))  # fmt: skip


def pdo_streams(frames: Frames, layout: PdoLayout) -> RunStreams:
    """The two supports' streams of a CANopen recording (frames in arrival order)."""
    builder = PdoBuilder(layout)
    builder.add(frames)
    return builder.streams(release=True)


def sync_frames(layout: PdoLayout, t_s: NDArray[np.float64]) -> Frames:
    """The SYNC frames at times ``t_s`` (no data: CiA 301's SYNC without a counter)."""
    return Frames.build(t_s, layout.sync_id, np.zeros((len(t_s), 8), np.uint8), dlc=0)


def tpdo_frames(node: PdoNode, t_s: NDArray[np.float64], accel: NDArray[Any],
                mark: NDArray[Any], status: tuple[NDArray[Any] | None, NDArray[Any] | None]
                = (None, None)) -> Frames:  # fmt: skip
    """A module's TPDO1 frames by its layout (the encoder :class:`PdoBuilder` decodes):
    the inputs' raw counts and, where mapped and given, their AI status, at ``t_s``."""
    words = node.accel.encode(accel) | node.mark.encode(mark)
    for sig, st in zip(node.status, status, strict=True):
        if sig is not None and st is not None:
            words |= sig.encode(st)
    data = words.view(np.uint8).reshape(-1, 8)
    return Frames.build(t_s, node.cob_id, data, dlc=sum(e & 0xFF for e in node.mapping) // 8)
