"""The simulator's CANopen modules (``[nodes] protocol = "canopen"``): a SYNC producer at
the sample rate (CiA 301, COB-ID 0x80, its jitter ``[nodes] sync_jitter_s``), and per
support an analog input module (``drivers/canopen_ai.eds``, node ids 1 and 2) that samples
its accelerometer and the reference sensor when the SYNC arrives and answers with TPDO1
(0x180 + node id: two INTEGER16, 0x6401 sub 1 and 2) 100 us per node later.  The inputs
are the scan module's (+-10 V on 16 bits, 100 mV/g, the mark 0..5 V:
:mod:`stand.sim.scan_emit`)."""

from __future__ import annotations

from importlib import resources
from typing import Any

import numpy as np

from stand.drivers.protocol import Frames
from stand.sim.scan_emit import (
    MARK_HIGH_V,
    SENSITIVITY_M_S2_PER_V,
    VOLTS_PER_COUNT,
    input_counts,
)

SYNC_ID = 0x80
"""CiA 301's default COB-ID of SYNC."""
NODE_IDS = (1, 2)
"""The modules' node ids (support 1, support 2)."""
ANSWER_S = 100e-6
"""A module's TPDO follows the SYNC by this much per node id."""


def eds_path() -> str:
    """The simulated module's EDS, shipped with the drivers."""
    return str(resources.files("stand.drivers") / "canopen_ai.eds")


def bus_table(rate_hz: float) -> dict[str, Any]:
    """The ``[bus]`` table that decodes the simulated modules (stored in their run files)."""
    nodes = [
        {"support": s, "node_id": n, "eds": eds_path(), "accel": "0x6401:1",
         "mark": "0x6401:2", "scale": VOLTS_PER_COUNT * SENSITIVITY_M_S2_PER_V,
         "mark_scale": VOLTS_PER_COUNT}
        for s, n in zip((1, 2), NODE_IDS, strict=True)
    ]  # fmt: skip
    table = {"rate_hz": float(rate_hz), "sync_id": SYNC_ID, "mark_threshold": MARK_HIGH_V / 2,
             "nodes": nodes}  # fmt: skip
    return {"protocol": "canopen", "canopen": table}


def module_frames(t: np.ndarray, accel: list[np.ndarray], edges: np.ndarray, rate_hz: float,
                  lost: Any) -> Frames:  # fmt: skip
    """The SYNCs at the sample times ``t`` and each module's TPDO after each; ``lost(node,
    frames)`` takes out the frames the bus loses."""
    t0 = t[0] if len(t) else 0.0
    inputs, mark = input_counts(t, accel, edges, rate_hz)
    blocks = [Frames.build(t - t0, SYNC_ID, np.zeros((len(t), 8), np.uint8), dlc=0)]
    for k, (node, counts) in enumerate(zip(NODE_IDS, inputs, strict=True)):
        data = np.zeros((len(t), 8), np.uint8)
        word = (counts.astype(np.int64) & 0xFFFF) | ((mark.astype(np.int64) & 0xFFFF) << 16)
        data[:, :4] = word.astype("<u4").view(np.uint8).reshape(-1, 4)
        tpdo = Frames.build(t - t0 + ANSWER_S * (k + 1), 0x180 + node, data, dlc=4)
        blocks.append(lost(k + 1, tpdo))
    every = Frames.concat(blocks)
    return every.take(np.argsort(every.t_s, kind="stable"))
