"""Setting CANopen analog input modules up over SDO before a recording, and the SYNC that
clocks them (CiA 301 + CiA 404; the decoder is :mod:`stand.drivers.canopen.codec`).

Per module, in this order, each step kept in the dialogue stored with the run:

1. NMT enter pre-operational (its PDOs stop; SDO answers).
2. Identity: 0x1018 sub 1 (vendor id) and sub 2 (product code) read and checked against
   the config (default: the EDS's); another module is refused.
3. The SYNC's COB-ID (0x1005), the communication cycle period (0x1006, the SYNC period
   in us) and the synchronous window (0x1007, us).
4. Where the EDS has them, each mapped input's sample rate (CiA 404 0x6114, the SYNC
   period in us) and its two-point scaling (0x6120..0x6123 set to 0 -> 0, 1 -> 1: the
   input's PV is the converter's count, so the config's ``scale`` is the only scale).
5. TPDO1: disabled (0x1800 sub 1 bit 31), its mapping (0x1A00) cleared, written entry
   by entry as the EDS gives it, its count set, transmission type 1 (0x1800 sub 2: on
   every SYNC), enabled; then the mapping and both communication entries read back and
   compared.

Then :class:`SyncProducer` starts the modules (NMT start) and sends the SYNC with the
interface's cyclic transmit (python-can's ``send_periodic``: the kernel's broadcast
manager on SocketCAN, a thread elsewhere); it stops it at the end of the run and puts the
modules back in pre-operational.  ``canopen`` does the SDO transfers only: the frames of
the run are read by the product's one receive thread.  A refusal (SDO abort), a silent
module or a wrong identity is a :class:`~stand.errors.BusError` in one line.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

from stand.drivers.canopen.layout import PdoLayout, PdoNode
from stand.drivers.runs.run_format import CANOPEN_SETUP_ATTR
from stand.errors import BusError

SDO_TIMEOUT_S = 0.3
"""A module that has not answered an SDO request within this long is asked once more,
then taken as silent [s]."""
NMT_PRE_OPERATIONAL = 0x80
NMT_START = 0x01
SCALING = ((0x6120, 0.0), (0x6121, 0.0), (0x6122, 1.0), (0x6123, 1.0))
"""CiA 404's two-point scaling of an input (FV1, PV1, FV2, PV2): the identity."""


@dataclass
class Step:
    """One exchange with a module: ``what`` is ``nmt``, ``read`` or ``write``."""

    node_id: int
    what: str
    obj: str
    value: int | float | None = None
    answer: str = "ok"

    def to_dict(self) -> dict[str, Any]:
        return {"node_id": self.node_id, "what": self.what, "object": self.obj,
                "value": self.value, "answer": self.answer}  # fmt: skip


class _Module:
    """One module's SDO client on the network, its steps appended to ``steps``."""

    def __init__(self, network: Any, node: PdoNode, channel: str, steps: list[Step]):
        import canopen

        self.n, self.channel, self.steps = node, channel, steps
        self.remote = canopen.RemoteNode(node.node_id, node.eds)
        self.remote.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT_S
        network.add_node(self.remote)
        self.od = self.remote.object_dictionary

    def var(self, index: int, sub: int) -> Any:
        """The EDS's entry ``index:sub`` (a plain variable is its own sub 0)."""
        from canopen.objectdictionary import ODVariable

        entry = self.od[index]
        return entry if isinstance(entry, ODVariable) else entry[sub]

    def has(self, index: int, sub: int) -> bool:
        try:
            self.var(index, sub)
        except KeyError:
            return False
        return True

    def _fail(self, verb: str, obj: str, exc: Exception) -> BusError:
        from canopen.sdo.exceptions import SdoAbortedError

        if isinstance(exc, SdoAbortedError):
            why = f"refused {verb} {obj} (SDO abort 0x{exc.code:08X}: {exc})"
        else:
            cob = 0x600 + self.n.node_id
            why = f"does not answer SDO ({verb} {obj}, COB-ID 0x{cob:03X}): "
            why += "is it powered, its node id right?"
        self.steps.append(Step(self.n.node_id, verb, obj, None, why))
        return BusError(f"CANopen node {self.n.node_id} {why}", channel=self.channel)

    def read(self, index: int, sub: int) -> int | float:
        from canopen.sdo.exceptions import SdoError

        obj = f"0x{index:04X}:{sub}"
        try:
            raw = self.remote.sdo.upload(index, sub)
            value = self.var(index, sub).decode_raw(raw)
        except (SdoError, ValueError) as exc:  # ValueError: an answer of the wrong size
            raise self._fail("read", obj, exc) from exc
        self.steps.append(Step(self.n.node_id, "read", obj, value))
        return value  # type: ignore[no-any-return]

    def write(self, index: int, sub: int, value: int | float) -> None:
        from canopen.sdo.exceptions import SdoError

        obj = f"0x{index:04X}:{sub}"
        try:
            self.remote.sdo.download(index, sub, self.var(index, sub).encode_raw(value))
        except SdoError as exc:
            raise self._fail("write", obj, exc) from exc
        self.steps.append(Step(self.n.node_id, "write", obj, value))


def _nmt(bus: Any, command: int, node_id: int) -> None:
    import can

    bus.send(can.Message(arbitration_id=0x000, data=[command, node_id], is_extended_id=False))


def _identity(m: _Module) -> None:
    got = (int(m.read(0x1018, 1)), int(m.read(0x1018, 2)))
    if got != m.n.identity:
        raise BusError(
            f"CANopen node {m.n.node_id} is another module: identity (0x1018) vendor "
            f"0x{got[0]:08X} product 0x{got[1]:08X}, the config expects vendor "
            f"0x{m.n.identity[0]:08X} product 0x{m.n.identity[1]:08X}",
            channel=m.channel,
        )


def _inputs(m: _Module, period_us: int) -> None:
    """Each mapped input's sample rate and scaling, where the EDS has the objects."""
    subs = {int(s.name.rpartition(":")[2], 0) for s in (m.n.accel, m.n.mark)}
    for sub in sorted(subs):
        if m.has(0x6114, sub):
            m.write(0x6114, sub, period_us)
        for index, value in SCALING:
            if m.has(index, sub):
                m.write(index, sub, value)


def _tpdo(m: _Module) -> None:
    """TPDO1 mapped as the EDS says, on every SYNC, and read back."""
    cob = m.n.cob_id
    m.write(0x1800, 1, cob | 0x80000000)
    m.write(0x1A00, 0, 0)
    for k, entry in enumerate(m.n.mapping, start=1):
        m.write(0x1A00, k, entry)
    m.write(0x1A00, 0, len(m.n.mapping))
    m.write(0x1800, 2, 1)
    m.write(0x1800, 1, cob)
    back = tuple(int(m.read(0x1A00, k)) for k in range(1, int(m.read(0x1A00, 0)) + 1))
    comm = (int(m.read(0x1800, 1)) & 0x800007FF, int(m.read(0x1800, 2)))
    if back != m.n.mapping or comm != (cob, 1):
        raise BusError(
            f"CANopen node {m.n.node_id}: TPDO1 reads back as COB-ID 0x{comm[0]:X}, "
            f"transmission type {comm[1]}, mapping {[f'0x{e:08X}' for e in back]}; written "
            f"0x{cob:X}, 1, {[f'0x{e:08X}' for e in m.n.mapping]}",
            channel=m.channel,
        )


def configure_modules(bus: Any, layout: PdoLayout, channel: str) -> list[dict[str, Any]]:
    """Set every module of ``layout`` up over SDO on the open ``bus``; the dialogue.

    Raises
    ------
    BusError
        A module refused a step, did not answer, or is another module (one line).
    """
    import can
    import canopen

    steps: list[Step] = []
    network = canopen.Network(bus)
    network.notifier = can.Notifier(bus, network.listeners, 0.05)
    period_us = round(1e6 / layout.rate_hz)
    window_us = round(1e6 * (layout.window_s or 0.5 / layout.rate_hz))
    try:
        for n in layout.nodes:
            _nmt(bus, NMT_PRE_OPERATIONAL, n.node_id)
            steps.append(Step(n.node_id, "nmt", "pre-operational"))
            m = _Module(network, n, channel, steps)
            _identity(m)
            m.write(0x1005, 0, layout.sync_id)
            m.write(0x1006, 0, period_us)
            m.write(0x1007, 0, window_us)
            _inputs(m, period_us)
            _tpdo(m)
    except can.CanError as exc:  # the interface refused to send: bus-off, unplugged
        raise BusError(f"cannot set the CANopen modules up: the interface refused to send "
                       f"({type(exc).__name__}: {exc})", channel=channel) from exc  # fmt: skip
    finally:
        network.notifier.stop(1.0)  # the bus stays open: it is the caller's
    return [s.to_dict() for s in steps]


class SyncProducer:
    """The modules started and the SYNC sent at the sample rate, until :meth:`stop`."""

    def __init__(self, bus: Any, layout: PdoLayout):
        self.bus, self.layout = bus, layout
        self._task: Any = None
        self._started = False

    def start(self, *, produce: bool = True, channel: str = "bus") -> None:
        """NMT start every module, then (``produce``) the SYNC at the sample rate.

        Raises
        ------
        BusError
            The interface refused to send (one line).
        """
        import can

        sync = can.Message(arbitration_id=self.layout.sync_id, data=b"", is_extended_id=False)
        if not math.isfinite(self.layout.rate_hz) or self.layout.rate_hz <= 0:
            raise ValueError(f"SYNC rate {self.layout.rate_hz} Hz")
        try:
            for n in self.layout.nodes:
                _nmt(self.bus, NMT_START, n.node_id)
            self._started = True
            if produce:
                self._task = self.bus.send_periodic(sync, 1.0 / self.layout.rate_hz)
        except (can.CanError, NotImplementedError) as exc:
            raise BusError(f"cannot start the CANopen modules and their SYNC "
                           f"({type(exc).__name__}: {exc})", channel=channel) from exc  # fmt: skip

    def stop(self) -> None:
        """Stop the SYNC and put the modules back in pre-operational (idempotent; a bus
        already gone is left alone)."""
        import can

        task, self._task = self._task, None
        started, self._started = self._started, False
        if not started:
            return
        try:
            if task is not None:
                task.stop()
            for n in self.layout.nodes:
                _nmt(self.bus, NMT_PRE_OPERATIONAL, n.node_id)
        except (can.CanError, OSError):
            pass


class CanopenSetup:
    """The family's :class:`~stand.drivers.family.BusSetup`: the modules set up over SDO
    (:func:`configure_modules`), started, and clocked by the host's SYNC
    (:class:`SyncProducer`) until :meth:`stop`."""

    attr = CANOPEN_SETUP_ATTR

    def __init__(self, layout: PdoLayout) -> None:
        self.layout = layout
        self.clock_ids = (layout.sync_id,)
        self._sync: SyncProducer | None = None

    def configure(self, bus: Any, channel: str) -> list[dict[str, Any]]:
        quiet_library_log()
        steps = configure_modules(bus, self.layout, channel)
        self._sync = SyncProducer(bus, self.layout)
        return steps

    def start(self, *, produce: bool, channel: str) -> None:
        if self._sync is not None:
            self._sync.start(produce=produce, channel=channel)

    def stop(self) -> None:
        if self._sync is not None:
            self._sync.stop()


def quiet_library_log() -> None:
    """The canopen library logs an aborted transfer ("Transfer aborted ...") before it
    raises; Python's last-resort handler would print that line to stderr before the
    product's own.  A NullHandler on the library's logger (what a library's user is
    meant to give it) keeps it quiet; an application that configured logging still
    gets the records."""
    log = logging.getLogger("canopen")
    if not log.handlers:
        log.addHandler(logging.NullHandler())
