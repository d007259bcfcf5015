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
    recorded_rate,
)
from stand.drivers.frames import FLAG_EXTENDED, Frames
from stand.drivers.one_clock import BlockBuilder, Blocks, kept, mark_edges, one_clock_stream
from stand.drivers.streams import LATE_FLAG, LATE_SHARE, NodeStream, RunStreams

EMCY_BASE, BOOT_BASE = 0x80, 0x700
"""CiA 301's EMCY and NMT error control (boot-up) COB-IDs: the base plus the node id."""


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
        nodes = {}
        for n in self.layout.nodes:
            built = self._node(n, self._parts[n.node_id], first, consume, t0, warn)
            if built is not None:
                nodes[n.support] = built
        warn.extend(Diagnostic("description_stored", note) for note in self.layout.notes)
        out = RunStreams(nodes, self.frames, self._unknown, 0, (), self._t1 - t0, tuple(warn))
        check_distinct(out, self.layout.source)
        return out

    def _node(self, n: PdoNode, parts: _Parts, first: int, consume: bool, t0: float,
              warn: list[Diagnostic]) -> NodeStream | None:  # fmt: skip
        """One support's stream from its module's kept TPDOs (``consume``: let go as
        used)."""
        said = _said(n, parts, t0, warn)
        k, keep, moved, dropped = _indices(parts.joined(parts.k, first, consume).astype(np.int64))
        if moved or dropped:
            warn.append(Diagnostic("tpdo_late", f"node {n.node_id}: {moved} TPDO(s) came after "
                                   f"the next SYNC (put back on their own), {dropped} in a "
                                   "backlog on one SYNC (left out: which SYNC each answered is "
                                   "not known)", float(moved + dropped)))  # fmt: skip
        index, t = kept(k, keep), kept(parts.joined(parts.t, first, consume), keep)
        if not len(index):
            return None  # nothing from this module: the measuring path says so
        layout, name = self.layout, f"node {n.node_id}"
        check_clock(layout.rate_hz, recorded_rate(index, t), layout.source,
                    "bus.canopen.rate_hz")  # fmt: skip
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
        return replace(stream, samples=len(index), invalid_samples=invalid,
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
