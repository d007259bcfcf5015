"""CANopen modules' layout read from their EDS (with the ``canopen`` library): each
support's TPDO1 COB-ID, where its accelerometer, mark and AI status lie in it, the
identity its EDS names; the SYNC's id and rate."""

from __future__ import annotations

import configparser
import io
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stand.drivers.family import Description, Kept, read_description
from stand.drivers.one_clock import Signal
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
    descriptions: tuple[Description, ...] = ()
    """The EDS files read, with their texts (stored with each run recorded through them)."""
    notes: tuple[str, ...] = ()
    """What the reading says (a run's stored EDS used instead of a changed file)."""
    source: str = ""
    family: str = "canopen"


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
    offset = 0
    for e in _mapping(od, eds):
        index, sub, bits = e >> 16, (e >> 8) & 0xFF, e & 0xFF
        if (index, sub) == key:
            dtype = od[index][sub].data_type
            if dtype not in SIGNED and dtype not in UNSIGNED:
                raise ConfigError(f"{ref}: data type 0x{dtype:04X} is not an integer input",
                                  source=eds)  # fmt: skip
            if bits != (SIGNED.get(dtype) or UNSIGNED[dtype]):
                want = SIGNED.get(dtype) or UNSIGNED[dtype]
                raise ConfigError(f"[1A00] maps {ref} with {bits} bits, its type has {want}",
                                  source=eds)  # fmt: skip
            return offset, bits, dtype in SIGNED
        offset += bits
    raise ConfigError(f"{ref} is not mapped in TPDO1 (0x1A00)", source=eds)


def _mapping(od: Any, eds: str) -> tuple[int, ...]:
    """TPDO1's mapping entries (0x1A00), each with 1..64 bits, 8 bytes at most in all."""
    try:
        count = int(od[0x1A00][0].default)
        entries = tuple(int(od[0x1A00][k].default) for k in range(1, count + 1))
    except (KeyError, TypeError, ValueError):
        raise ConfigError("the EDS has no TPDO1 mapping [1A00] with its entries",
                          source=eds) from None  # fmt: skip
    for k, e in enumerate(entries, 1):
        if not 0 < e <= 0xFFFFFFFF or e & 0xFF == 0:
            raise ConfigError(f"[1A00sub{k}]: 0x{e & 0xFFFFFFFF:08X} maps no bits",
                              source=eds)  # fmt: skip
    if sum(e & 0xFF for e in entries) > 64:
        raise ConfigError(f"[1A00]: {sum(e & 0xFF for e in entries)} bits mapped, more than a "
                          "PDO's 8 bytes", source=eds)  # fmt: skip
    return entries


def object_dictionary(desc: Description, node_id: int, where: str) -> Any:
    """The object dictionary of an EDS text (the canopen library), every fault one line."""
    from canopen.objectdictionary import ObjectDictionaryError, import_od

    fp = io.StringIO(desc.text)
    fp.name = desc.name if desc.name.lower().endswith((".eds", ".dcf")) else desc.name + ".eds"
    try:
        return import_od(fp, node_id=node_id)
    except (ValueError, KeyError, TypeError, IndexError, OverflowError, AttributeError,
            configparser.Error, ObjectDictionaryError) as exc:  # fmt: skip
        detail = " ".join(str(exc).split())[:300] or type(exc).__name__
        raise ConfigError(f"cannot read the EDS ({type(exc).__name__}: {detail})",
                          source=where) from None  # fmt: skip


def _identity(od: Any, n: Any, where: str) -> tuple[tuple[int, int], int]:
    """The identity 0x1018 sub 1/2 (the config's where given) and TPDO1's COB-ID (11 bits)."""
    try:  # CiA 301 makes 0x1018 mandatory: an EDS without it is malformed, given ids or not
        named = (int(od[0x1018][1].default), int(od[0x1018][2].default))
        identity = (named[0] if n.vendor_id is None else n.vendor_id,
                    named[1] if n.product_code is None else n.product_code)  # fmt: skip
    except (KeyError, TypeError, ValueError):
        raise ConfigError("the EDS has no identity [1018] with sub 1 and 2 (vendor id, "
                          "product code)", source=where) from None  # fmt: skip
    try:
        cob = int(od[0x1800][1].default)
    except (KeyError, TypeError, ValueError):
        raise ConfigError("the EDS has no TPDO1 communication [1800] with its COB-ID "
                          "(sub 1)", source=where) from None  # fmt: skip
    if not 0 < cob & 0x7FF <= 0x7FF or cob < 0 or cob > 0xFFFFFFFF:
        raise ConfigError(f"[1800sub1]: COB-ID 0x{cob & 0xFFFFFFFF:X} is no 11-bit id",
                          source=where)  # fmt: skip
    return identity, cob & 0x7FF


def _node(n: Any, base: Path, source: str, stored: Kept | None
          ) -> tuple[PdoNode, Description, str | None]:  # fmt: skip
    eds = Path(n.eds) if Path(n.eds).is_absolute() else base / n.eds
    desc, note = read_description(eds, "bus.canopen", source, stored)
    where = f"{source}, {eds.name}"
    od = object_dictionary(desc, n.node_id, where)
    sig: list[Signal | None] = []
    for ref in (n.accel, n.mark, n.accel_status, n.mark_status):
        if ref is None:
            sig.append(None)
            continue
        key = _object(od, ref, where)
        off, bits, signed = _in_tpdo(od, key, where, ref)
        sig.append(Signal(f"{n.node_id}:{ref}", 0, False, off, bits, signed, 1.0, 0.0))
    identity, cob = _identity(od, n, where)
    mapping = _mapping(od, where)
    assert sig[0] is not None and sig[1] is not None
    node = PdoNode(n.support, n.node_id, cob, sig[0], sig[1], n.scale, n.mark_scale,
                   n.delay_s, n.mark_delay_s, identity, mapping, (sig[2], sig[3]),
                   str(eds))  # fmt: skip
    return node, desc, note


def load_pdo_layout(table: Any, base: Path, source: str,
                    stored: Kept | None = None) -> PdoLayout:  # fmt: skip
    """The layout of a ``[bus.canopen]`` table (:class:`stand.drivers.canopen.table.CanopenTable`),
    each EDS read relative to ``base`` (or the copy a run ``stored``) with the node's id.
    Two modules on one TPDO COB-ID, or a SYNC id that is a module's TPDO, EMCY or
    boot-up id, are refused."""
    read = [_node(n, base, source, stored) for n in table.nodes]
    nodes = tuple(r[0] for r in read)
    a, b = nodes
    if a.cob_id == b.cob_id:
        eds = Path(a.eds).name
        raise ConfigError(f"[bus.canopen] nodes {a.node_id} and {b.node_id} both send TPDO1 on "
                          f"0x{a.cob_id:03X} ({eds}'s [1800sub1] a fixed COB-ID, not "
                          "$NODEID+0x180?): one module's frames would feed both supports",
                          source=source)  # fmt: skip
    for n in nodes:
        if table.sync_id in (n.cob_id, 0x80 + n.node_id, 0x700 + n.node_id):
            raise ConfigError(f"[bus.canopen] sync_id 0x{table.sync_id:03X} is a frame id of "
                              f"node {n.node_id} (TPDO1 0x{n.cob_id:03X}, EMCY, boot-up)",
                              source=source, key="bus.canopen.sync_id")  # fmt: skip
    descs = tuple({r[1].name: r[1] for r in read}.values())
    notes = tuple(dict.fromkeys(r[2] for r in read if r[2] is not None))
    return PdoLayout(float(table.rate_hz), int(table.sync_id), nodes, table.mark_threshold,
                     table.configure, table.window_s, descs, notes, source)  # fmt: skip
