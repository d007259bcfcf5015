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
delays.  The decoder is chosen per bus (``[bus] protocol = "canopen"``), so TPDO ids
that protocol v1 also uses (0x181, 0x182) are read as TPDOs, never as v1's MARKs.
"""

from __future__ import annotations

from dataclasses import dataclass
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


@dataclass(frozen=True)
class PdoLayout:
    """The bus: the SYNC's id and rate, the two modules, the mark's threshold."""

    rate_hz: float
    sync_id: int
    nodes: tuple[PdoNode, ...]
    mark_threshold: float | None = None


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
        sig = []
        for ref in (n.accel, n.mark):
            key = _object(od, ref, where)
            off, bits, signed = _in_tpdo(od, key, where, ref)
            sig.append(Signal(f"{n.node_id}:{ref}", 0, False, off, bits, signed, 1.0, 0.0))
        cob = int(od[0x1800][1].default) & 0x7FF
        identity = (int(od[0x1018][1].default), int(od[0x1018][2].default))
        mapping = tuple(int(od[0x1A00][k].default)
                        for k in range(1, int(od[0x1A00][0].default) + 1))  # fmt: skip
        nodes.append(PdoNode(n.support, n.node_id, cob, sig[0], sig[1], n.scale, n.mark_scale,
                             n.delay_s, n.mark_delay_s, identity, mapping))  # fmt: skip
    return PdoLayout(float(table.rate_hz), int(table.sync_id), tuple(nodes), table.mark_threshold)


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


def pdo_streams(frames: Frames, layout: PdoLayout) -> RunStreams:
    """The two supports' streams of a CANopen recording (frames in arrival order)."""
    std = (frames.flags & FLAG_EXTENDED) == 0
    is_sync = std & (frames.can_id == layout.sync_id)
    syncs_before = np.cumsum(is_sync) - is_sync  # SYNCs received before each frame
    nodes, warn, known = {}, [], is_sync.copy()
    for n in layout.nodes:
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
        v = (n.mark.raw(data) * n.mark_scale).astype(np.float64)
        shift = (n.mark_delay_s - n.accel_delay_s) * layout.rate_hz
        lost = int(index[-1] - index[0] + 1) - len(index)
        nodes[n.support] = one_clock_stream(
            n.support, layout.rate_hz, index, n.accel.raw(data), n.accel_scale,
            mark_edges(v, index, layout.mark_threshold), shift, t, lost, dropped,
        )  # fmt: skip
    span_s = float(frames.t_s[-1] - frames.t_s[0]) if len(frames) else 0.0
    return RunStreams(nodes, len(frames), int(np.count_nonzero(~known)), 0, (), span_s,
                      tuple(warn))  # fmt: skip
