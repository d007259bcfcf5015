"""The simulator's sensor nodes (``[nodes] protocol = "v1"``): each node's counts (clipping,
quantisation, invalid samples), its STATUS flags, its protocol-v1 frames
(:func:`stand.drivers.v1.nodes.node_frames`) on its own clock, and the frames the bus
loses."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.core.model import FloatArray
from stand.drivers.frames import Frames
from stand.drivers.v1.nodes import STATUS_PERIOD_S, node_frames
from stand.sim.bus_side import lost, noisy, rng_of

FULL_SCALE = 32767
"""Largest count a node sends; -32768 is reserved for invalid samples."""
NO_REFERENCE_S = 2.0
"""STATUS flags "no reference edge" after this long without one [s]."""


def emit(scene: Any, accel: list[Any], times: list[FloatArray], edges: FloatArray,
         clocks: list[tuple[float, float]]) -> list[Frames]:  # fmt: skip
    """What the two nodes send for the accelerations their sensors read, each on its own
    clock (``clocks``: its ppm and offset)."""
    return [_node_frames(scene, i, accel[i], times[i], edges, clocks[i]) for i in range(2)]


def _node_frames(
    scene: Any,
    i: int,
    a: Any,
    times: Any,
    edges: Any,
    clock: tuple[float, float],
) -> Frames:
    """What node ``i + 1`` sends for the acceleration ``a`` its sensor reads [m/s^2]: noise,
    clipping, counts, invalid samples, its STATUS flags, its frames and the frames lost."""
    e, rate, node = scene.effects, scene.nodes.rate_hz, i + 1
    ppm, offset = clock
    a = noisy(scene, node, a)
    clipped = np.zeros(len(a), bool)
    if e.clipping:
        r = e.clipping.range_m_s2
        clipped = np.abs(a) > r
        a = np.clip(a, -r, r)
    counts = np.rint(a / (scene.nodes.scale_um_s2 * 1e-6))
    clipped |= np.abs(counts) > FULL_SCALE
    counts = np.clip(counts, -FULL_SCALE, FULL_SCALE).astype(np.int16)
    invalid = np.zeros(len(a), bool)
    if e.invalid:
        invalid = rng_of(scene, "invalid", node).random(len(a)) < e.invalid.probability
        counts[invalid] = -32768
    true_rate = rate * (1 + ppm * 1e-6)
    positions = (edges - times[0]) * true_rate if len(times) else edges[:0]
    flags = _status_flags(len(a), rate, clipped, invalid, positions)
    frames = node_frames(
        node,
        counts,
        rate_hz=rate,
        scale_um_s2=scene.nodes.scale_um_s2,
        edges=positions,
        first_seq=scene.nodes.first_seq,
        t0_s=offset,
        status_flags=flags,
        clock_ppm=ppm,
    )
    return lost(scene, node, frames)


def _status_flags(
    n: int,
    rate: int,
    clipped: NDArray[np.bool_],
    invalid: NDArray[np.bool_],
    edges: FloatArray,
) -> NDArray[np.uint8]:
    """Flags of each STATUS (start-up, then each second): what happened in the second before."""
    per_status = round(STATUS_PERIOD_S * rate)  # samples between two STATUS frames
    n_status = n // per_status + 1
    reported_by = np.arange(n) // per_status + 1  # STATUS k reports the second before it
    flags = np.zeros(n_status, np.uint8)
    for bit, happened in ((1, clipped), (2, invalid)):
        k_hit = np.unique(reported_by[happened])
        flags[k_hit[k_hit < n_status]] |= bit
    k = np.arange(n_status)
    t_status = k * per_status  # sample position of STATUS k
    last_edge = np.searchsorted(edges, t_status, side="right") - 1
    since = np.where(last_edge >= 0, t_status - edges[np.maximum(last_edge, 0)], t_status)
    flags[(k > 0) & (since > NO_REFERENCE_S * rate)] |= 4
    return flags
