"""A plain 1x (and 2x, 3x) least-squares fit from a node's stream, for checking the simulator.

Not the product's estimator (that is the DSP issue's): the shaft angle at each
sample is interpolated linearly between the node's reference edges, and the
samples between the first and last edge are fitted on cos/sin of k theta.
"""

from __future__ import annotations

import math

import numpy as np

from stand.drivers.streams import NodeStream


def theta_at(s: NodeStream, gamma_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(mask of samples between the edges, theta [rad] of those samples)."""
    seg = s.segment == 0
    m = s.mark_segment == 0
    pos, rev = s.mark_position[m], s.mark_rev[m]
    idx = s.index[seg].astype(float)
    inside = (idx >= pos[0]) & (idx <= pos[-1])
    theta = math.radians(gamma_deg) + 2 * math.pi * np.interp(idx[inside], pos, rev - rev[0])
    mask = np.zeros(len(s.index), bool)
    mask[np.flatnonzero(seg)[inside]] = True
    return mask, theta


def fit(
    s: NodeStream,
    gamma_deg: float = 0.0,
    orders: tuple[int, ...] = (1, 2, 3),
    extra_hz: float | None = None,
) -> dict[int, complex]:
    """Complex amplitude of each order k: ``a = sum Re(A_k e^{i k theta}) + c``."""
    mask, theta = theta_at(s, gamma_deg)
    assert s.accel_m_s2 is not None and s.rate_hz is not None
    a = s.accel_m_s2[mask]
    cols = [np.ones_like(theta)]
    for k in orders:
        cols += [np.cos(k * theta), np.sin(k * theta)]
    if extra_hz is not None:
        t = s.index[mask] / s.rate_hz
        cols += [np.cos(2 * math.pi * extra_hz * t), np.sin(2 * math.pi * extra_hz * t)]
    coef, *_ = np.linalg.lstsq(np.column_stack(cols), a, rcond=None)
    return {k: complex(coef[1 + 2 * j], -coef[2 + 2 * j]) for j, k in enumerate(orders)}
