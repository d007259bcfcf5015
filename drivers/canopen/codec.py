"""CANopen analog input modules sampling on SYNC (CiA 301 + CiA 401/404): the recorded
SYNC frames are the sample clock.

Each support's module answers every SYNC with its TPDO1 (transmission type 1), mapping
its accelerometer's and the reference sensor's analog inputs.  The TPDO's layout comes
from the module's EDS (read with the ``canopen`` library: its TPDO1 mapping 0x1A00, the
COB-ID 0x1800 sub 1, the mapped objects' types); the frames are decoded here with numpy.
A TPDO's sample index is the number of SYNCs before it, less one (the SYNC it answers);
a TPDO missing between two SYNCs is a lost sample with its index kept; one delayed past
the next SYNC is put back on its own SYNC when that SYNC has none, else dropped and
counted.  Mark edges are the mark input's interpolated threshold crossings (as
:mod:`stand.drivers.scan`), moved into the accelerometer's time by the channels' known
delays.  The module's own word becomes the streams' flags: an input's AI status (CiA 404
0x6150, when mapped) drops a sample marked not valid (``sensor_fault``) and flags an
overload (``overrange``); an EMCY (0x80 + node id) flags ``emcy`` and a boot-up (0x700 +
node id: the module restarted, its TPDOs stop until it is started again) ``restart``,
each also a warning with its time.  The decoder is chosen per bus (``[bus] protocol =
"canopen"``), so TPDO ids that protocol v1 also uses (0x181, 0x182) are read as TPDOs,
never as v1's MARKs.
"""

from __future__ import annotations

from dataclasses import replace

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
from stand.drivers.one_clock import mark_edges, one_clock_stream
from stand.drivers.streams import RunStreams


def _indices(k: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.bool_], int, int]:
    """Each TPDO's SYNC (``k``: SYNCs before it, less one), a TPDO that came after the next
    SYNC put back where its own SYNC has none; which are kept; how many were put back; how
    many dropped (a second TPDO on one SYNC)."""
    k = k.copy()
    moved = 0
    for j in np.flatnonzero(np.diff(k) == 0):  # two on one SYNC: the first came late?
        if k[j] - 1 >= 0 and (j == 0 or k[j - 1] < k[j] - 1):
            k[j] -= 1
            moved += 1
    keep = np.concatenate(([True], np.diff(k) > 0)) if len(k) else np.zeros(0, bool)
    keep &= k >= 0
    return k, keep, moved, int(np.count_nonzero(~keep))


def _module_says(frames: Frames, std: NDArray[np.bool_], t0: float, n: PdoNode,
                 warn: list[Diagnostic]) -> tuple[list[str], NDArray[np.bool_]]:  # fmt: skip
    """The module's EMCY and boot-up frames: flags, warnings, which frames they are."""
    flags: list[str] = []
    emcy = std & (frames.can_id == 0x80 + n.node_id) & (frames.dlc >= 3)
    boot = std & (frames.can_id == 0x700 + n.node_id) & (frames.dlc >= 1)
    boot &= frames.data[:, 0] == 0
    t = np.where(emcy | boot, frames.t_s - t0, 0.0) if emcy.any() or boot.any() else frames.t_s
    if emcy.any():
        codes = frames.data[emcy, 0].astype(np.int64) | (frames.data[emcy, 1].astype(np.int64) << 8)
        said = ", ".join(
            f"0x{c:04X} at {s:.3f} s" for c, s in zip(codes[:5], t[emcy][:5], strict=True)
        )
        more = f" and {len(codes) - 5} more" if len(codes) > 5 else ""
        warn.append(Diagnostic("emcy", f"node {n.node_id}: EMCY {said}{more} (CiA 301 error "
                               "codes; 0x0000: the error is gone)", float(len(codes))))  # fmt: skip
        flags.append("emcy")
    if boot.any():
        warn.append(Diagnostic("module_restart", f"node {n.node_id}: the module restarted "
                               f"(boot-up at {t[boot][0]:.3f} s): no TPDO after it until it is "
                               "started again", float(np.count_nonzero(boot))))  # fmt: skip
        flags.append("restart")
    return flags, emcy | boot


def _status(n: PdoNode, data: NDArray[np.uint8]) -> tuple[NDArray[np.bool_], NDArray[np.bool_],
                                                          list[str]]:  # fmt: skip
    """Per TPDO: the accelerometer's sample valid, the mark's sample valid; the flags (CiA
    404 AI status: bit 0 not valid, bit 1 positive and bit 2 negative overload)."""
    ok = [np.ones(len(data), bool), np.ones(len(data), bool)]
    flags = []
    for k, sig in enumerate(n.status):
        if sig is None:
            continue
        st = sig.raw(data)
        ok[k] = (st & 1) == 0
        if not ok[k].all():
            flags.append("sensor_fault")
        if ((st & 6) != 0).any():
            flags.append("overrange")
    return ok[0], ok[1], flags


def pdo_streams(frames: Frames, layout: PdoLayout) -> RunStreams:
    """The two supports' streams of a CANopen recording (frames in arrival order)."""
    std = (frames.flags & FLAG_EXTENDED) == 0
    is_sync = std & (frames.can_id == layout.sync_id)
    syncs_before = np.cumsum(is_sync, dtype=np.int32)  # SYNCs up to each frame (int32:
    syncs_before -= is_sync  # 2^31 SYNCs are 12 days at 2 kHz): those before it
    nodes, known = {}, is_sync.copy()
    warn: list[Diagnostic] = []
    t0 = float(frames.t_s[0]) if len(frames) else 0.0
    for n in layout.nodes:
        said, theirs = _module_says(frames, std, t0, n, warn)
        known |= theirs
        rows = std & (frames.can_id == n.cob_id) & (frames.dlc >= 1)
        known |= rows
        data, t = frames.data[rows], frames.t_s[rows]
        k, keep, moved, dropped = _indices(syncs_before[rows].astype(np.int64) - 1)
        data, t, index = data[keep], t[keep], k[keep]
        if moved or dropped:
            warn.append(Diagnostic("tpdo_late", f"node {n.node_id}: {moved} TPDO(s) came after "
                                   f"the next SYNC (put back on their own), {dropped} a second "
                                   "on one SYNC (dropped)", float(moved + dropped)))  # fmt: skip
        if not len(index):
            continue  # nothing from this module: the measuring path says so
        check_clock(layout.rate_hz, recorded_rate(index, t), layout.source,
                    "bus.canopen.rate_hz")  # fmt: skip
        accel_ok, mark_ok, flags = _status(n, data)
        v = (n.mark.raw(data[mark_ok]) * n.mark_scale).astype(np.float64)
        check_mark(v, f"node {n.node_id} {n.mark.name.split(':', 1)[1]}", layout.source)
        check_accel(n.accel.raw(data[accel_ok]), f"node {n.node_id} "
                    f"{n.accel.name.split(':', 1)[1]}", n.support, layout.source)  # fmt: skip
        shift = (n.mark_delay_s - n.accel_delay_s) * layout.rate_hz
        lost = int(index[-1] - index[0] + 1) - len(index)
        stream = one_clock_stream(
            n.support, layout.rate_hz, index[accel_ok], n.accel.raw(data[accel_ok]),
            n.accel_scale, mark_edges(v, index[mark_ok], layout.mark_threshold), shift,
            t, lost, dropped,
        )  # fmt: skip
        invalid = len(index) - int(np.count_nonzero(accel_ok))
        if invalid:
            warn.append(Diagnostic("ai_status", f"node {n.node_id}: {invalid} sample(s) the "
                                   "module marked not valid (AI status), left out",
                                   float(invalid)))  # fmt: skip
        nodes[n.support] = replace(stream, samples=len(index), invalid_samples=invalid,
                                   flags=tuple(dict.fromkeys([*flags, *said])))  # fmt: skip
    span_s = float(frames.t_s[-1] - frames.t_s[0]) if len(frames) else 0.0
    warn.extend(Diagnostic("description_stored", note) for note in layout.notes)
    out = RunStreams(nodes, len(frames), int(np.count_nonzero(~known)), 0, (), span_s,
                     tuple(warn))  # fmt: skip
    check_distinct(out, layout.source)
    return out
