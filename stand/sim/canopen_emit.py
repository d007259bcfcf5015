"""The simulator's CANopen modules (``[nodes] protocol = "canopen"``): a SYNC producer at
the sample rate (CiA 301, COB-ID 0x80, its jitter ``[nodes] sync_jitter_s``), and per
support an analog input module (``drivers/canopen/canopen_ai.eds``, node ids 1 and 2) that samples
its accelerometer and the reference sensor when the SYNC arrives and answers with TPDO1
(0x180 + node id: the two inputs' CiA 404 AI input PV, INTEGER16 0x7130 sub 1 and 2, and
their AI status, UNSIGNED8 0x6150 sub 1 and 2) 100 us per node later.  The inputs are the
scan module's (+-10 V on 16 bits, 100 mV/g, the mark 0..5 V: :mod:`stand.sim.scan_emit`).
``[effects.canopen]`` (:class:`stand.sim.tables.CanopenFaults`) makes one module answer
late, send an EMCY (and mark its input not valid for a moment) or restart; its identity
and mapping faults are the SDO side's (:mod:`stand.sim.canopen_node`)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from stand.drivers.canopen.codec import sync_frames, tpdo_frames
from stand.drivers.canopen.layout import PdoLayout, load_pdo_layout
from stand.drivers.canopen.table import CanopenTable
from stand.drivers.frames import Frames
from stand.sim.bus_side import lost, noisy, rng_of
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
EMCY_HARDWARE = 0x5000
"""CiA 301's EMCY error code "device hardware"."""


def eds_path() -> str:
    """The simulated module's EDS, shipped with the drivers."""
    return str(resources.files("stand.drivers.canopen") / "canopen_ai.eds")


def bus_table(rate_hz: float) -> dict[str, Any]:
    """The ``[bus]`` table that decodes the simulated modules (stored in their run files)."""
    nodes = [
        {"support": s, "node_id": n, "eds": eds_path(), "accel": "0x7130:1",
         "mark": "0x7130:2", "accel_status": "0x6150:1", "mark_status": "0x6150:2",
         "scale": VOLTS_PER_COUNT * SENSITIVITY_M_S2_PER_V, "mark_scale": VOLTS_PER_COUNT}
        for s, n in zip((1, 2), NODE_IDS, strict=True)
    ]  # fmt: skip
    table = {"rate_hz": float(rate_hz), "sync_id": SYNC_ID, "mark_threshold": MARK_HIGH_V / 2,
             "nodes": nodes}  # fmt: skip
    return {"protocol": "canopen", "canopen": table}


def _invalid(node: int, t_rel: np.ndarray, faults: Any) -> np.ndarray:
    """The accelerometer input's AI status per sample: bit 0 (not valid) while the scene's
    EMCY lasts on this module."""
    status = np.zeros(len(t_rel), np.uint8)
    if faults is not None and faults.node == node and faults.emcy_at_s is not None:
        status[(t_rel >= faults.emcy_at_s) & (t_rel < faults.emcy_at_s + faults.invalid_s)] |= 1
    return status


def _faulty(node: int, tpdo: Frames, t_rel: np.ndarray, period_s: float, faults: Any,
            rng: np.random.Generator) -> tuple[Frames, list[Frames]]:  # fmt: skip
    """One module's TPDOs with the scene's faults, and the EMCY and boot-up frames it sends."""
    if faults is None or faults.node != node:
        return tpdo, []
    said = []
    if faults.emcy_at_s is not None:
        data = np.zeros((1, 8), np.uint8)
        data[0, :3] = (EMCY_HARDWARE & 0xFF, EMCY_HARDWARE >> 8, 0x01)
        said.append(Frames.build(np.array([faults.emcy_at_s]), 0x80 + node, data, dlc=8))
    if faults.late_probability > 0:
        late = rng.random(len(tpdo)) < faults.late_probability
        tpdo.t_s[late] += period_s - ANSWER_S * node / 2  # after the next SYNC, before its TPDO
    if faults.restart_at_s is not None:
        tpdo = tpdo.take(t_rel < faults.restart_at_s)
        said.append(Frames.build(np.array([faults.restart_at_s]), 0x700 + node,
                                 np.zeros((1, 8), np.uint8), dlc=1))  # fmt: skip
    return tpdo, said


def layout_of(rate_hz: float) -> PdoLayout:
    """The simulated modules' layout, read from their own EDS and ``[bus.canopen]`` table."""
    table = CanopenTable.model_validate(bus_table(rate_hz)["canopen"])
    return load_pdo_layout(table, Path("."), "the simulated CANopen modules")


def module_frames(t: np.ndarray, accel: list[np.ndarray], edges: np.ndarray, rate_hz: float,
                  lose: Any, faults: Any = None, rng: Any = None) -> Frames:  # fmt: skip
    """The SYNCs at the sample times ``t`` and each module's TPDO after each, encoded by
    the modules' layout (:func:`stand.drivers.canopen.codec.tpdo_frames`); ``lose(node,
    frames)`` takes out the frames the bus loses; ``faults`` (``[effects.canopen]``, with
    its random generator ``rng``) what one module does wrong."""
    layout = layout_of(rate_hz)
    t0 = t[0] if len(t) else 0.0
    inputs, mark = input_counts(t, accel, edges, rate_hz)
    blocks = [sync_frames(layout, t - t0)]
    for k, (node, counts) in enumerate(zip(layout.nodes, inputs, strict=True)):
        status = (_invalid(node.node_id, t - t0, faults), None)
        tpdo = tpdo_frames(node, t - t0 + ANSWER_S * (k + 1), counts, mark, status)
        tpdo, said = _faulty(node.node_id, tpdo, t - t0, 1.0 / rate_hz, faults, rng)
        blocks += [lose(k + 1, tpdo), *said]
    every = Frames.concat(blocks)
    return every.take(np.argsort(every.t_s, kind="stable"))


def emit(scene: Any, accel: list[Any], times: list[Any], edges: Any, clocks: Any
         ) -> list[Frames]:  # fmt: skip
    """:class:`stand.sim.hardware.SimHardware`'s ``emit``: one SYNC for both modules, at
    the first module's sample times."""
    heard = [noisy(scene, i + 1, a) for i, a in enumerate(accel)]
    lose = lambda node, frames: lost(scene, node, frames)  # noqa: E731
    return [module_frames(times[0], heard, edges, scene.nodes.rate_hz, lose,
                          scene.effects.canopen, rng_of(scene, "canopen", 0))]  # fmt: skip


def bus_keys(nodes: Any) -> dict[str, Any]:
    """The ``[bus]`` keys that decode the simulated modules (``[nodes]``: their rate)."""
    return bus_table(nodes.rate_hz)
