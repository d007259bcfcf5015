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

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.core import Diagnostic
from stand.drivers.protocol import FLAG_EXTENDED, Frames
from stand.drivers.scan import Signal, mark_edges, one_clock_stream
from stand.drivers.streams import RunStreams
from stand.errors import ConfigError

SIGNED = {0x02: 8, 0x03: 16, 0x04: 32}
UNSIGNED = {0x05: 8, 0x06: 16, 0x07: 32}
"""CiA 301 data types a mapped analog input may have: INTEGER8/16/32, UNSIGNED8/16/32."""


@dataclass(frozen=True)
class PdoNode:
    """One support's module: its TPDO1 id, where the accelerometer and the mark lie in it,
    their scales and delays, and the identity its EDS names."""

    support: int
    node_id: int
    cob_id: int
    accel: Signal
    mark: Signal
    accel_scale: float
    mark_scale: float
    accel_delay_s: float
    mark_delay_s: float
    identity: tuple[int, int]
    mapping: tuple[int, ...]
    status: tuple[Signal | None, Signal | None] = (None, None)
    """The accelerometer's and the mark's AI status in TPDO1, where mapped."""
    eds: str = ""
    """The EDS the layout was read from (its objects encode the set-up's SDO values)."""


@dataclass(frozen=True)
class PdoLayout:
    """The bus: the SYNC's id and rate, the two modules, the mark's threshold."""

    rate_hz: float
    sync_id: int
    nodes: tuple[PdoNode, ...]
    mark_threshold: float | None = None
    configure: bool = True
    """Whether a live session sets the modules up and produces the SYNC."""
    window_s: float | None = None
    """The synchronous window [s] (None: half a period)."""


def _object(od: Any, ref: str, eds: str) -> tuple[int, int]:
    index, _, sub = ref.partition(":")
    key = (int(index, 0), int(sub or "0", 0))
    try:
        od[key[0]][key[1]]
    except KeyError:
        raise ConfigError(f"the EDS has no object {ref}", source=eds) from None
    return key


def _in_tpdo(od: Any, key: tuple[int, int], eds: str, ref: str) -> tuple[int, int, bool]:
    """Where a mapped object lies in TPDO1 (bit offset, bits, signed) by the EDS's 0x1A00."""
    try:
        count = int(od[0x1A00][0].default)
        entries = [int(od[0x1A00][k].default) for k in range(1, count + 1)]
    except (KeyError, TypeError, ValueError):
        raise ConfigError("the EDS has no TPDO1 mapping (0x1A00)", source=eds) from None
    offset = 0
    for e in entries:
        index, sub, bits = e >> 16, (e >> 8) & 0xFF, e & 0xFF
        if (index, sub) == key:
            dtype = od[index][sub].data_type
            if dtype not in SIGNED and dtype not in UNSIGNED:
                raise ConfigError(f"{ref}: data type 0x{dtype:04X} is not an integer input",
                                  source=eds)  # fmt: skip
            return offset, bits, dtype in SIGNED
        offset += bits
    raise ConfigError(f"{ref} is not mapped in TPDO1 (0x1A00)", source=eds)


def load_pdo_layout(table: Any, base: Path, source: str) -> PdoLayout:
    """The layout of a ``[bus.canopen]`` table (:class:`stand.config.canopen.CanopenTable`),
    each EDS read relative to ``base`` with the node's id."""
    from canopen.objectdictionary import import_od

    nodes = []
    for n in table.nodes:
        eds = Path(n.eds) if Path(n.eds).is_absolute() else base / n.eds
        try:
            od: Any = import_od(str(eds), node_id=n.node_id)
        except (OSError, ValueError, KeyError) as exc:
            raise ConfigError(f"[bus.canopen] eds: cannot read {eds} as an EDS ({exc})",
                              source=source) from None  # fmt: skip
        where = f"{source}, {eds.name}"
        sig: list[Signal | None] = []
        for ref in (n.accel, n.mark, n.accel_status, n.mark_status):
            if ref is None:
                sig.append(None)
                continue
            key = _object(od, ref, where)
            off, bits, signed = _in_tpdo(od, key, where, ref)
            sig.append(Signal(f"{n.node_id}:{ref}", 0, False, off, bits, signed, 1.0, 0.0))
        cob = int(od[0x1800][1].default) & 0x7FF
        identity = (
            int(od[0x1018][1].default) if n.vendor_id is None else n.vendor_id,
            int(od[0x1018][2].default) if n.product_code is None else n.product_code,
        )
        mapping = tuple(int(od[0x1A00][k].default)
                        for k in range(1, int(od[0x1A00][0].default) + 1))  # fmt: skip
        assert sig[0] is not None and sig[1] is not None
        nodes.append(PdoNode(n.support, n.node_id, cob, sig[0], sig[1], n.scale, n.mark_scale,
                             n.delay_s, n.mark_delay_s, identity, mapping, (sig[2], sig[3]),
                             str(eds)))  # fmt: skip
    return PdoLayout(float(table.rate_hz), int(table.sync_id), tuple(nodes),
                     table.mark_threshold, table.configure, table.window_s)  # fmt: skip


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
    flags, t = [], frames.t_s - t0
    emcy = std & (frames.can_id == 0x80 + n.node_id) & (frames.dlc >= 3)
    boot = std & (frames.can_id == 0x700 + n.node_id) & (frames.dlc >= 1)
    boot &= frames.data[:, 0] == 0
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
    syncs_before = np.cumsum(is_sync) - is_sync  # SYNCs received before each frame
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
        accel_ok, mark_ok, flags = _status(n, data)
        v = (n.mark.raw(data[mark_ok]) * n.mark_scale).astype(np.float64)
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
    return RunStreams(nodes, len(frames), int(np.count_nonzero(~known)), 0, (), span_s,
                      tuple(warn))  # fmt: skip
