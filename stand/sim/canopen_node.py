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
own SYNC producer frame by frame, at rates a thread can follow (the tests use it).
"""

from __future__ import annotations

from typing import Any

from stand.sim.canopen_emit import NODE_IDS, eds_path

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
                    self.network.send_message(0x180 + node_id, queue[k])
                    self.answered[node_id] = k + 1

        self.network.subscribe(sync_id, on_sync)

    def detach(self) -> None:
        """Stop answering (idempotent); the bus stays its owner's."""
        network, self.network = self.network, None
        if network is not None and network.notifier is not None:
            network.notifier.stop(1.0)
