"""A synthetic two-node run for the driver tests: a pure 1x sine per node."""

from __future__ import annotations

import numpy as np

from stand.drivers import Frames
from stand.drivers.v1.nodes import merge, node_frames


def sine_run(
    seconds: float = 8.0,
    rpm: float = 900.0,
    rate_hz: float = 4000.0,
    scale_um_s2: int = 100,
    amplitudes_m_s2: tuple[float, ...] = (2.39, 1.64),
    phases_rad: tuple[float, ...] = (0.3, 2.0),
    first_seq: int = 0,
    first_rev: int = 0,
    edge_offset: float = 10.25,
    t0_s: float = 1000.0,
) -> Frames:
    """Frames of nodes 1.. (one per amplitude), each a 1x sine with edges at ``rpm``."""
    n = round(seconds * rate_hz)
    period = rate_hz * 60.0 / rpm  # samples per revolution
    edges = np.arange(edge_offset, n, period)
    k = np.arange(n)
    blocks = []
    for i, (amp, ph) in enumerate(zip(amplitudes_m_s2, phases_rad, strict=True)):
        theta = 2 * np.pi * (k - edge_offset) / period
        counts = np.rint(amp * np.cos(theta + ph) / (scale_um_s2 * 1e-6)).astype(np.int16)
        blocks.append(
            node_frames(
                i + 1,
                counts,
                rate_hz=rate_hz,
                scale_um_s2=scale_um_s2,
                edges=edges,
                first_seq=first_seq,
                first_rev=first_rev,
                t0_s=t0_s + 1e-4 * i,
            )
        )
    return merge(blocks)
