"""The simulated CANopen modules' own side of the bus: each a ``canopen`` ``LocalNode``
built from ``drivers/canopen/canopen_ai.eds`` that answers NMT and SDO (the host's set-up,
:mod:`stand.drivers.canopen.setup`) from its object dictionary, as a real CiA 404 module
would, and can answer each SYNC with its TPDO1.

``[effects.canopen]`` makes one module show another identity (``vendor_id``) or refuse
to have TPDO1 mapped (``refuse_mapping``: SDO abort 0x06040041, "object cannot be mapped
to the PDO").  On the simulated stand the run's SYNC and TPDO frames are the scene's own
(:mod:`stand.sim.canopen_emit`), played in real time as the bus would carry them: a Python
thread cannot answer a 2 kHz SYNC within its 0.5 ms window, and a TPDO past the window
would be decoded one SYNC late.  :meth:`SimulatedModules.answer_syncs` answers the host's
own SYNC producer frame by frame; :meth:`SimulatedModules.serve` does so on a bus shared
with another process (``stand simulate SCENE --bus``), the scene's TPDOs in turn.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from stand.sim.canopen_emit import NODE_IDS, SYNC_ID, eds_path

TPDO_BASE = 0x180
"""CiA 301's TPDO1 COB-ID, less the node id (the simulated modules' EDS gives it)."""
HOST_WAIT_S = 60.0
"""``serve`` waits this long for a host to set the modules up and start its SYNC [s]."""
HOST_GONE_S = 3.0
"""``serve`` stops when the host's SYNCs stop for this long [s]."""
STAMP_AFTER_SYNC_S = 1e-6
"""A TPDO :meth:`SimulatedModules.serve` sends is stamped this long after its SYNC, per
node (the host's own SYNC stamps in a catch-up burst lie 5 us apart and more)."""
ABORT_NOT_MAPPABLE = 0x06040041
"""CiA 301's SDO abort code "object cannot be mapped to the PDO"."""


class SimulatedModules:
    """The modules of a CANopen scene, attached to a bus by :meth:`attach`.

    Parameters
    ----------
    faults
        The scene's ``[effects.canopen]`` (:class:`stand.sim.tables.CanopenFaults`), or None.
    """

    def __init__(self, faults: Any = None, eds: str | None = None,
                 node_ids: tuple[int, ...] = NODE_IDS):  # fmt: skip
        self.faults, self.eds, self.node_ids = faults, eds or eds_path(), node_ids
        self.network: Any = None
        self.nodes: dict[int, Any] = {}
        self.answered: dict[int, int] = {}
        """TPDOs sent per node by :meth:`answer_syncs`."""

    def _local(self, node_id: int) -> Any:
        import canopen
        from canopen.sdo.exceptions import SdoAbortedError

        node = canopen.LocalNode(node_id, self.eds)
        f = self.faults
        if f is None or f.node != node_id:
            return node
        if f.vendor_id is not None:
            node.data_store.setdefault(0x1018, {})[1] = int(f.vendor_id).to_bytes(4, "little")
        if f.refuse_mapping:

            def refuse(index: int, subindex: int, **_: Any) -> None:
                if index == 0x1A00 and subindex >= 1:
                    raise SdoAbortedError(ABORT_NOT_MAPPABLE)

            node.add_write_callback(refuse)  # type: ignore[no-untyped-call]
        return node

    def attach(self, bus: Any) -> SimulatedModules:
        """Answer NMT and SDO on ``bus`` (the modules' side of the simulated bus)."""
        import can
        import canopen

        self.network = canopen.Network(bus)
        for node_id in self.node_ids:
            self.nodes[node_id] = self._local(node_id)
            self.network.add_node(self.nodes[node_id])
        self.network.notifier = can.Notifier(bus, self.network.listeners, 0.05)
        return self

    def answer_syncs(self, sync_id: int, payloads: dict[int, list[bytes]]) -> None:
        """Answer each SYNC, once started (NMT operational), with the node's next payload
        from ``payloads`` on its TPDO1 (0x180 + node id), until they run out."""
        self.answered = {n: 0 for n in payloads}

        def on_sync(can_id: int, data: bytes, timestamp: float) -> None:
            for node_id, queue in payloads.items():
                k = self.answered[node_id]
                if self.nodes[node_id].nmt.state == "OPERATIONAL" and k < len(queue):
                    self.network.send_message(TPDO_BASE + node_id, queue[k])
                    self.answered[node_id] = k + 1

        self.network.subscribe(sync_id, on_sync)

    def serve(self, bus: Any, frames: Any, rate_hz: float,
              stamps: Callable[[], bool] | None = None) -> int:  # fmt: skip
        """On ``bus`` (another process's host, as a real stand's): answer the host's set-up
        over SDO; once every module is started (NMT operational), answer each SYNC with
        each module's TPDO of the scene's ``frames`` sampled when that SYNC came (its time
        from the host's first SYNC, at ``rate_hz``: a SYNC the host sent late gets the
        sample of its own time, as a module samples on SYNC), in a loop of its own (no
        dispatch: a 2 kHz SYNC leaves 0.5 ms), until the scene's samples run out and the
        host's SYNCs stop for :data:`HOST_GONE_S`, or none set the modules up within
        :data:`HOST_WAIT_S`.  ``stamps``, called once the set-up is done: have the bus
        send each frame's own time (True where it can): each TPDO then carries the time it
        answers, within its SYNC's window however late this process is: the SYNC's own
        plus :data:`STAMP_AFTER_SYNC_S` per node (a host catching up sends its SYNCs
        microseconds apart, and the answer must sit before the next one).
        Returns the TPDOs sent."""
        import can

        payloads = [
            (TPDO_BASE + n, [bytes(frames.data[j, : frames.dlc[j]])
                             for j in np.flatnonzero(frames.can_id == TPDO_BASE + n)])
            for n in self.node_ids
        ]  # fmt: skip
        self.attach(bus)
        start = time.monotonic()
        while not all(n.nmt.state == "OPERATIONAL" for n in self.nodes.values()):
            if time.monotonic() - start > HOST_WAIT_S:
                self.detach()
                return 0
            time.sleep(0.005)
        self.detach()  # the set-up is done: the SYNCs are answered below, straight
        wire = stamps() if stamps is not None else False
        sent, first, last = 0, None, time.monotonic()
        total = min(len(p) for _, p in payloads)
        while time.monotonic() - last < HOST_GONE_S:
            msg = bus.recv(0.1)
            if msg is None or msg.arbitration_id != SYNC_ID or msg.is_extended_id:
                continue
            last = time.monotonic()
            first = msg.timestamp if first is None else first
            k = round((msg.timestamp - first) * rate_hz)  # the sample of the SYNC's time
            if 0 <= k < total:
                for j, (cob, queue) in enumerate(payloads):
                    at = msg.timestamp + STAMP_AFTER_SYNC_S * (j + 1) if wire else 0.0
                    bus.send(can.Message(timestamp=at, arbitration_id=cob, data=queue[k],
                                         is_extended_id=False))  # fmt: skip
                    sent += 1
        return sent

    def detach(self) -> None:
        """Stop answering (idempotent); the bus stays its owner's."""
        network, self.network = self.network, None
        if network is not None and network.notifier is not None:
            network.notifier.stop(1.0)
