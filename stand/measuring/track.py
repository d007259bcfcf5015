"""Order tracking: a node's 1x (and 2x ...) phasor block by block of whole revolutions,
with the speed of each block, for runs whose speed changes (a run-up through a ball
balancer's onset, a run-up through the supports' resonances).

Each block of ``revs`` revolutions gets the least-squares fit of ``cos theta, sin theta,
1`` (and ``cos k theta, sin k theta`` for each order ``k`` asked) on its samples (the
shaft angle from the reference edges, as the steady fit's:
:func:`stand.core.dsp.shaft_angle`), and its mean speed.  A block's phasor is the 1x
the support had while the shaft turned those revolutions; over a slow run-up it follows
the steady response at the block's speed.
"""

from __future__ import annotations

import math

import numpy as np

from stand.core import vold_kalman as vk
from stand.core.dsp import shaft_angle
from stand.drivers.streams import NodeStream
from stand.errors import MeasurementError
from stand.measuring.gate import node_segment

MIN_SAMPLES = 16
"""A block with fewer samples is left out (more than the widest fit's seven columns and
five degrees of freedom; a whole revolution at 4 kHz and 6000 rpm holds 40)."""


def track_orders(
    s: NodeStream, gamma_rad: float, revs: int = 2, orders: tuple[int, ...] = (1,)
) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray]]]:
    """Per block of ``revs`` revolutions of the node's longest segment: its mean speed
    [rad/s], and for each order ``k`` of ``orders`` the block's ``k``x acceleration phasor
    [m/s^2] with that phasor's standard error per component [m/s^2]: one least-squares
    fit per block of ``1`` and ``cos k theta, sin k theta`` for every ``k`` at once (``a =
    Re(A e^{i k theta})``), so that no order's content is left in another's residual.

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
    speed = np.add.reduceat(w, starts) / np.maximum(np.diff(np.append(starts, len(w))), 1) \
        if n_blocks else np.zeros(0)  # fmt: skip
    # where more than the 1x is asked, the 1x's change across the block is fitted too (its
    # slope, u cos theta and u sin theta with u the block's fraction from its middle): in a
    # sweep through a resonance the 1x changes within one revolution, and a 1x that
    # changes is also a 0x and a 2x (sidebands a revolution's frequency apart) that would
    # read as the 2x
    u = (theta - theta[0]) / (2 * math.pi * revs) - turn - 0.5 if len(orders) > 1 else None
    A, n, _, se = _joint_fits(theta, a, starts, n_blocks, orders, u)
    whole = n >= MIN_SAMPLES  # the same blocks whatever the orders asked
    whole[-1:] = False  # the last block may hold less than its revolutions
    out = [(A[j][whole], se[j][whole]) for j in range(len(orders))]
    return speed[whole] * s.rate_hz, out


def _joint_fits(
    theta: np.ndarray, a: np.ndarray, starts: np.ndarray, n_blocks: int, orders: tuple[int, ...],
    u: np.ndarray | None = None,
) -> tuple[list[np.ndarray], np.ndarray, np.ndarray, list[np.ndarray]]:  # fmt: skip
    """Per block: each order's phasor, the sample count, the residual variance per sample
    and each order's standard error per component (the mean of its cos and sin
    coefficients' variances from the normal equations' inverse); with ``u`` (each sample's
    place in its block, -0.5 to 0.5) the first order's slope across the block fitted too,
    its phasor then the block's middle's.  The columns are made once, the normal
    equations summed one product at a time (a temporary of one row)."""
    # each column: (order, sine?, times u?); order 0 the constant
    cols = [(0, False, False)] + [(k, sn, False) for k in orders for sn in (False, True)]
    if u is not None:  # the first order's slope across the block (after the orders)
        cols += [(orders[0], False, True), (orders[0], True, True)]

    def column(i: int) -> np.ndarray:
        k, sine, slope = cols[i]
        x: np.ndarray = np.sin(k * theta) if sine else np.cos(k * theta)
        return x * u if slope and u is not None else x

    p = len(cols)
    sizes = np.diff(np.append(starts, len(a)))
    has = sizes > 0
    at = starts[has]
    G, b = np.zeros((n_blocks, p, p)), np.zeros((n_blocks, p))
    X = [column(i) for i in range(p)]  # p rows of the samples' length (7 at most)
    for i in range(p):
        b[has, i] = np.add.reduceat(X[i] * a, at) if len(at) else 0.0
        for j in range(i, p):
            G[has, i, j] = G[has, j, i] = np.add.reduceat(X[i] * X[j], at) if len(at) else 0
    aa = np.zeros(n_blocks)
    aa[has] = np.add.reduceat(a * a, at) if len(at) else 0.0
    n = np.where(has, sizes, 0)
    ok = n >= p + 5
    coef, inv = np.zeros((n_blocks, p)), np.zeros((n_blocks, p, p))
    if ok.any():
        inv[ok] = np.linalg.inv(G[ok])
        coef[ok] = np.einsum("bij,bj->bi", inv[ok], b[ok])
    resid = aa - np.einsum("bi,bi->b", coef, b)
    var = np.where(ok, np.maximum(resid, 0) / np.maximum(n - p, 1), np.inf)
    phasors, ses = [], []
    for j in range(len(orders)):
        c, s_ = 1 + 2 * j, 2 + 2 * j
        phasors.append(coef[:, c] - 1j * coef[:, s_])
        share = np.where(ok, 0.5 * (inv[:, c, c] + inv[:, s_, s_]), 1.0)
        ses.append(np.sqrt(var * share))  # infinite where the block is too short
    return phasors, n, var, ses


def track_1x_vk(
    s: NodeStream, gamma_rad: float, half_power_hz: float, revs: int = 1
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """As :func:`track_1x`, the 1x read by a Vold-Kalman filter of the half-power
    bandwidth ``half_power_hz`` [Hz] (:mod:`stand.core.vold_kalman`) on the node's longest
    segment, its samples on their uniform grid (a lost sample weighs nothing), then
    averaged over each block of ``revs`` revolutions; the blocks within the filter's
    settling at either end left out.  Each block's standard error is its residual's rms
    times the filter's noise gain (``sqrt(2 sum h^2)``, per component).

    Raises
    ------
    MeasurementError
        The node cannot be measured, or its segment is shorter than the filter settles.
    """
    lo, hi, pos, rev = node_segment(s)
    assert s.rate_hz is not None
    first, last = int(s.index[lo]), int(s.index[hi - 1])
    grid = np.arange(first, last + 1)
    inside, theta, w = shaft_angle(grid.astype(float), pos, rev, gamma_rad)
    grid = grid[inside]
    y = np.zeros(len(grid))
    weight = np.zeros(len(grid))
    at = np.asarray(s.index[lo:hi]) - first
    at_in = np.searchsorted(grid - first, at)
    ok = (at_in < len(grid)) & ((grid - first)[np.minimum(at_in, len(grid) - 1)] == at)
    y[at_in[ok]], weight[at_in[ok]] = s.accel(lo, hi)[ok], 1.0
    if half_power_hz < vk.narrowest_hz(s.rate_hz):
        raise MeasurementError(f"a Vold-Kalman filter of {half_power_hz:g} Hz is narrower than "
                               f"{vk.narrowest_hz(s.rate_hz):.2f} Hz, the narrowest solved to "
                               f"float precision at {s.rate_hz:g} Hz")  # fmt: skip
    settle = vk.settle_samples(half_power_hz, s.rate_hz)
    if len(grid) <= 2 * settle + 4:
        raise MeasurementError(f"{len(grid)} samples: too short for a Vold-Kalman filter of "
                               f"{half_power_hz:g} Hz (it settles in {settle} samples at "
                               "each end)")  # fmt: skip
    r = vk.weight_for(half_power_hz, s.rate_hz)
    A = vk.envelope(y, theta, weight, r)
    resid2 = np.where(weight > 0, (y - (A * np.exp(1j * theta)).real) ** 2, 0.0)
    turn = np.floor((theta - theta[0]) / (2 * math.pi * revs)).astype(np.int64)
    n_blocks = int(turn[-1]) + 1
    starts = np.searchsorted(turn, np.arange(n_blocks))
    count = np.diff(np.append(starts, len(turn)))
    present = np.add.reduceat(weight, starts)
    mean = np.add.reduceat(A, starts) / np.maximum(count, 1)
    speed = np.add.reduceat(w, starts) / np.maximum(count, 1)
    rms = np.sqrt(np.add.reduceat(resid2, starts) / np.maximum(present - 1, 1))
    se = rms * math.sqrt(2 * vk.noise_gain(r))
    ends = (starts >= settle) & (starts + count <= len(turn) - settle)
    whole = ends & (present >= MIN_SAMPLES)
    whole[-1:] = False  # the last block may hold less than its revolutions
    return speed[whole] * s.rate_hz, mean[whole], se[whole]


def track_1x(
    s: NodeStream, gamma_rad: float, revs: int = 2
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per block of ``revs`` revolutions of the node's longest segment: its mean speed
    [rad/s], its 1x acceleration phasor [m/s^2] and that phasor's standard error per
    component [m/s^2] (:func:`track_orders` of order 1).

    Raises
    ------
    MeasurementError
        The node cannot be measured (no samples, no edges: :func:`node_segment`).
    """
    w, ((A, se),) = track_orders(s, gamma_rad, revs, (1,))
    return w, A, se
