"""Order tracking: a node's 1x phasor block by block of whole revolutions, with the speed
of each block, for runs whose speed changes (a run-up through a ball balancer's onset).

Each block of ``revs`` revolutions gets the least-squares fit of ``cos theta, sin theta,
1`` on its samples (the shaft angle from the reference edges, as the steady fit's:
:func:`stand.core.dsp.shaft_angle`), and its mean speed.  A block's phasor is the 1x
the support had while the shaft turned those revolutions; over a slow run-up it follows
the steady response at the block's speed.
"""

from __future__ import annotations

import math

import numpy as np

from stand.core.dsp import shaft_angle
from stand.core.fitsums import block_fits, block_sums
from stand.drivers.streams import NodeStream
from stand.measuring.gate import node_segment


def track_1x(
    s: NodeStream, gamma_rad: float, revs: int = 2
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per block of ``revs`` revolutions of the node's longest segment: its mean speed
    [rad/s], its 1x acceleration phasor [m/s^2] and that phasor's standard error per
    component [m/s^2].

    Raises
    ------
    MeasurementError
        The node cannot be measured (no samples, no edges: :func:`node_segment`).
    """
    lo, hi, pos, rev = node_segment(s)
    assert s.rate_hz is not None
    index = np.asarray(s.index[lo:hi], dtype=float)
    inside, theta, w = shaft_angle(index, pos, rev, gamma_rad)
    a = s.accel(lo, hi)[inside]
    turn = np.floor((theta - theta[0]) / (2 * math.pi * revs)).astype(np.int64) if len(theta) \
        else np.zeros(0, np.int64)  # fmt: skip
    n_blocks = int(turn[-1]) + 1 if len(turn) else 0
    starts = np.searchsorted(turn, np.arange(n_blocks))
    sums = block_sums(np.cos(theta), np.sin(theta), a, starts, n_blocks)
    A, n, var = block_fits(sums)
    speed = np.add.reduceat(w, starts) / np.maximum(np.diff(np.append(starts, len(w))), 1) \
        if n_blocks else np.zeros(0)  # fmt: skip
    whole = n >= 8
    whole[-1:] = False  # the last block may hold less than its revolutions
    return speed[whole] * s.rate_hz, A[whole], np.sqrt(2 * var[whole] / n[whole])
