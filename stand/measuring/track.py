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
    Where more than the 1x is asked, the 1x's change across the block is fitted too (its
    slope, ``u cos theta, u sin theta`` with ``u`` the block's fraction from its middle):
    in a sweep through a resonance the 1x changes within one revolution, and a 1x that
    changes is also a 0x and a 2x (side bands a revolution's frequency apart).

    The samples are taken :data:`CHUNK_SAMPLES` at a time and each block's normal
    equations summed across the chunks (sums add up), so that a long run never holds more
    than a chunk's columns.

    Raises
    ------
    MeasurementError
        The node cannot be measured (no samples, no edges: :func:`node_segment`).
    """
    lo, hi, pos, rev = node_segment(s)
    assert s.rate_hz is not None
    cols = [(0, False, False)] + [(k, sn, False) for k in orders for sn in (False, True)]
    if len(orders) > 1:  # the first order's slope across the block (after the orders)
        cols += [(orders[0], False, True), (orders[0], True, True)]
    sums = _BlockSums(len(cols))
    theta0 = None
    for c0 in range(lo, hi, CHUNK_SAMPLES):
        c1 = min(c0 + CHUNK_SAMPLES, hi)
        inside, theta, w = shaft_angle(np.asarray(s.index[c0:c1], dtype=float), pos, rev,
                                       gamma_rad)  # fmt: skip
        if not len(theta):
            continue
        theta0 = float(theta[0]) if theta0 is None else theta0
        place = (theta - theta0) / (2 * math.pi * revs)
        turn = np.floor(place).astype(np.int64)
        X = [_column(spec, theta, place - turn - 0.5) for spec in cols]
        sums.add(turn, X, s.accel(c0, c1)[inside], w)
    A, n, _, se, speed = sums.fits(len(orders))
    whole = n >= MIN_SAMPLES  # the same blocks whatever the orders asked
    whole[-1:] = False  # the last block may hold less than its revolutions
    out = [(A[j][whole], se[j][whole]) for j in range(len(orders))]
    return speed[whole] * s.rate_hz, out


CHUNK_SAMPLES = 32_768
"""Samples whose angles and fit columns are made at once (seven columns of them: 1.8 MB)."""


def _column(spec: tuple[int, bool, bool], theta: np.ndarray, u: np.ndarray) -> np.ndarray:
    """One fit column: ``cos`` or ``sin`` of ``k theta`` (``k = 0``: the constant), times
    ``u`` for a slope column."""
    k, sine, slope = spec
    x: np.ndarray = np.sin(k * theta) if sine else np.cos(k * theta)
    return x * u if slope else x


class _BlockSums:
    """Per block the normal equations ``X'X``, ``X'a``, ``a'a``, the sample count and the
    speed's sum, added chunk by chunk (a block may straddle two chunks)."""

    def __init__(self, p: int) -> None:
        self.p = p
        self.G, self.b = np.zeros((0, p, p)), np.zeros((0, p))
        self.aa, self.n, self.w = np.zeros(0), np.zeros(0), np.zeros(0)

    def _grow(self, blocks: int) -> None:
        have = len(self.n)
        if blocks <= have:
            return
        more = blocks - have
        self.G = np.concatenate((self.G, np.zeros((more, self.p, self.p))))
        self.b = np.concatenate((self.b, np.zeros((more, self.p))))
        self.aa, self.n, self.w = (np.concatenate((x, np.zeros(more)))
                                   for x in (self.aa, self.n, self.w))  # fmt: skip

    def add(self, turn: np.ndarray, X: list[np.ndarray], a: np.ndarray, w: np.ndarray) -> None:
        """Add a chunk's samples: their blocks ``turn`` (sorted), columns, values, speeds."""
        t0 = int(turn[0])
        self._grow(int(turn[-1]) + 1)
        rel = turn - t0
        m = int(rel[-1]) + 1

        def bins(v: np.ndarray) -> np.ndarray:
            return np.bincount(rel, weights=v, minlength=m)

        at = slice(t0, t0 + m)
        self.aa[at] += bins(a * a)
        self.n[at] += np.bincount(rel, minlength=m)
        self.w[at] += bins(w)
        for i in range(self.p):
            self.b[at, i] += bins(X[i] * a)
            for j in range(i, self.p):
                g = bins(X[i] * X[j])
                self.G[at, i, j] += g
                if j != i:
                    self.G[at, j, i] += g

    def fits(self, n_orders: int) -> tuple[list[np.ndarray], np.ndarray, np.ndarray,
                                           list[np.ndarray], np.ndarray]:  # fmt: skip
        """Each order's phasor, the count, the residual variance, each order's standard
        error per component (the mean of its cos and sin coefficients' variances from the
        inverse) and the blocks' mean speed [rad per sample]."""
        p, n = self.p, self.n
        ok = n >= p + 5
        coef, inv = np.zeros((len(n), p)), np.zeros((len(n), p, p))
        if ok.any():
            inv[ok] = np.linalg.inv(self.G[ok])
            coef[ok] = np.einsum("bij,bj->bi", inv[ok], self.b[ok])
        resid = self.aa - np.einsum("bi,bi->b", coef, self.b)
        var = np.where(ok, np.maximum(resid, 0) / np.maximum(n - p, 1), np.inf)
        phasors, ses = [], []
        for j in range(n_orders):
            c, s_ = 1 + 2 * j, 2 + 2 * j
            phasors.append(coef[:, c] - 1j * coef[:, s_])
            share = np.where(ok, 0.5 * (inv[:, c, c] + inv[:, s_, s_]), 1.0)
            ses.append(np.sqrt(var * share))  # infinite where the block is too short
        return phasors, n.astype(np.int64), var, ses, self.w / np.maximum(n, 1)


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
    if half_power_hz < vk.narrowest_hz(s.rate_hz):
        raise MeasurementError(f"a Vold-Kalman filter of {half_power_hz:g} Hz is narrower than "
                               f"{vk.narrowest_hz(s.rate_hz):.2f} Hz, the narrowest solved to "
                               f"float precision at {s.rate_hz:g} Hz")  # fmt: skip
    grid = np.arange(int(s.index[lo]), int(s.index[hi - 1]) + 1)
    inside, theta, w = shaft_angle(grid.astype(float), pos, rev, gamma_rad)
    grid = grid[inside]  # one stretch: the samples between the first and the last edge
    y, weight = np.zeros(len(grid)), np.zeros(len(grid))
    at = np.asarray(s.index[lo:hi]) - (int(grid[0]) if len(grid) else 0)
    ok = (at >= 0) & (at < len(grid))
    y[at[ok]], weight[at[ok]] = s.accel(lo, hi)[ok], 1.0
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
