"""The simulator's scan-stream module (``[nodes] protocol = "scan"``): one simultaneous-
sampling module, a frame per scan (``drivers/scan/scan_module.dbc``): a 16-bit counter, both
accelerometers (IEPE, 100 mV/g) and the once-per-revolution sensor (0..5 V) on three
+-10 V, 16-bit inputs.  One clock for all three channels, so no per-node clock effect.
``[nodes] counter = false`` leaves the counter's bits at 0 and the decoder is told there
is none (a module that sends none)."""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from stand.drivers.frames import Frames
from stand.drivers.scan.codec import mark_wave, scan_frames
from stand.drivers.scan.layout import load_layout
from stand.drivers.scan.table import ScanTable
from stand.sim.bus_side import lost, noisy

VOLTS_PER_COUNT = 10.0 / 32768
"""The module's inputs: +-10 V on 16 bits."""
SENSITIVITY_M_S2_PER_V = 9.80665 / 0.1
"""The accelerometers: 100 mV/g."""
MARK_HIGH_V = 5.0
"""The reference sensor's output when the mark is under it."""
RISE_SAMPLES = 4.0
"""The mark's edge: a ramp this many samples wide (the sensor behind its filter)."""
SCAN_ID = 0x300
"""The module's frame id (``SCAN`` in the DBC; clear of protocol v1's ids)."""


def dbc_path() -> str:
    """The simulated module's DBC, shipped with the drivers."""
    return str(resources.files("stand.drivers.scan") / "scan_module.dbc")


def bus_table(rate_hz: float, counter: bool, per_frame: int = 1) -> dict[str, Any]:
    """The ``[bus]`` table that decodes the simulated module (stored in its run files)."""
    channels = [
        {"message": "SCAN", "signal": "ai1", "role": "accel", "support": 1,
         "scale": SENSITIVITY_M_S2_PER_V},
        {"message": "SCAN", "signal": "ai2", "role": "accel", "support": 2,
         "scale": SENSITIVITY_M_S2_PER_V},
        {"message": "SCAN", "signal": "ai3", "role": "mark", "scale": 1.0},
    ]  # fmt: skip
    scan: dict[str, Any] = {"dbc": dbc_path(), "rate_hz": float(rate_hz),
                            "mark_threshold": MARK_HIGH_V / 2, "channels": channels}  # fmt: skip
    if counter:
        scan["counter"] = "counter"
    if per_frame > 1:
        scan["scans_per_frame"] = per_frame
    return {"protocol": "scan", "scan": scan}


def shaft_phase(t: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The shaft's angle past the mark at times ``t``: interpolated between the edges (the
    mark at 0, 2 pi, ...), extended by the first and last turns' speed."""
    if len(edges) < 2:
        return np.full(len(t), math.pi)  # no edge: the mark never passes
    k = 2 * math.pi * np.arange(len(edges))
    out = np.interp(t, edges, k)
    before, after = t < edges[0], t > edges[-1]
    w0 = 2 * math.pi / (edges[1] - edges[0])
    w1 = 2 * math.pi / (edges[-1] - edges[-2])
    out[before] = (t[before] - edges[0]) * w0
    out[after] = k[-1] + (t[after] - edges[-1]) * w1
    return np.asarray(out, dtype=np.float64)


def input_counts(t: np.ndarray, accel: list[np.ndarray], edges: np.ndarray, rate_hz: float
                 ) -> tuple[list[np.ndarray], np.ndarray]:  # fmt: skip
    """What the module's inputs read at the sample times ``t``, in counts: each
    accelerometer's (IEPE, 100 mV/g) and the reference sensor's (0..5 V, its edge a ramp
    :data:`RISE_SAMPLES` wide)."""
    counts = [np.clip(np.rint(a / SENSITIVITY_M_S2_PER_V / VOLTS_PER_COUNT), -32767, 32767)
              for a in accel]  # fmt: skip
    speed = 2 * math.pi / np.median(np.diff(edges)) if len(edges) > 1 else 0.0
    rise = max(RISE_SAMPLES * speed / rate_hz, 1e-9)
    mark = np.rint(MARK_HIGH_V * mark_wave(shaft_phase(t, edges), rise) / VOLTS_PER_COUNT)
    return counts, mark


def module_frames(t: np.ndarray, accel: list[np.ndarray], edges: np.ndarray, rate_hz: float,
                  counter: bool, per_frame: int = 1) -> Frames:  # fmt: skip
    """The module's frames, encoded by the layout its own DBC and ``[bus.scan]`` table give
    (:func:`stand.drivers.scan.codec.scan_frames`, the decoder's twin): each scan at its
    sample time ``t`` (host time = sample time); without a counter its bits stay 0; with
    ``per_frame`` > 1, CAN FD frames of that many scans, each sent at its last scan's
    time."""
    counts, mark = input_counts(t, accel, edges, rate_hz)
    table = ScanTable.model_validate(bus_table(rate_hz, counter, per_frame)["scan"])
    layout = load_layout(table, Path("."), "the simulated scan module")
    return scan_frames(layout, t - t[0] if len(t) else t, (counts[0], counts[1]), mark)


def emit(scene: Any, accel: list[Any], times: list[Any], edges: Any, clocks: Any
         ) -> list[Frames]:  # fmt: skip
    """:class:`stand.sim.hardware.SimHardware`'s ``emit``: one module, one clock (the first
    node's sample times)."""
    heard = [noisy(scene, i + 1, a) for i, a in enumerate(accel)]
    n = scene.nodes
    return [lost(scene, 1, module_frames(times[0], heard, edges, n.rate_hz, n.counter,
                                         n.scans_per_frame))]  # fmt: skip


def bus_keys(nodes: Any) -> dict[str, Any]:
    """The ``[bus]`` keys that decode the simulated module (``[nodes]``: its rate, counter
    and scans a frame)."""
    return bus_table(nodes.rate_hz, nodes.counter, nodes.scans_per_frame)
