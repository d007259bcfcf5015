"""The Vold-Kalman order-tracking filter (second generation, one order): the complex
envelope of a shaft order at every sample, for a speed that changes too fast for whole
revolutions to be read as steady.

Pure numerics (arrays in, arrays out).  After Vold and Leuridan, *High resolution order
tracking at extreme slew rates using Kalman tracking filters*, SAE 931288 (1993), in the
form Tůma gives (*Setting the passband width in the Vold-Kalman order tracking filter*,
ICSV12, 2005): the envelope ``x`` of the samples ``y`` minimises

    sum_n w_n |e^{-i theta_n} y_n - x_n|^2 + r^2 sum_n |x_n - 2 x_{n+1} + x_{n+2}|^2

(the data equation and the structural equation: the envelope is locally linear), so
``(W + r^2 D'D) x = W e^{-i theta} y`` with ``D`` the second difference.  The order's
phasor is ``A = 2 x`` (``a = Re(A e^{i theta})``).  Here the data equation is taken on the
real samples with both components of ``A`` (:func:`envelope`): the order's mirror at
``-theta`` is fitted, not filtered, and a sample lost on the bus (``w_n = 0``) costs only
its own information, the structure carrying the envelope across it.  The system is
banded, solved in ``O(N)``.

The filter's response to an envelope changing at ``w`` [rad/sample] is
``H = 1 / (1 + r^2 (2 sin(w / 2))^4)``: half power at ``w_c`` for
``r = 1 / (2 sin(w_c / 2))^2`` (:func:`weight_for`).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


MAX_WEIGHT = 1.2e7
"""The largest structural weight ``r`` solved to float precision (the system's condition
grows as ``r^2``): at 4 kHz a half-power bandwidth of 0.19 Hz (:func:`narrowest_hz`);
0.2 Hz comes back within 2e-6 of a constant envelope, 0.14 Hz only within 1e-3."""


def narrowest_hz(rate_hz: float) -> float:
    """The narrowest half-power bandwidth [Hz] solved to float precision at ``rate_hz``.

    >>> round(narrowest_hz(4000.0), 3)
    0.184
    """
    return rate_hz / math.pi * 2 * math.asin(0.5 / math.sqrt(MAX_WEIGHT)) / 2


def weight_for(half_power_hz: float, rate_hz: float) -> float:
    """The structural weight ``r`` whose filter passes an envelope changing at
    ``half_power_hz`` with half its power, at the sample rate ``rate_hz``.

    >>> round(weight_for(1.0, 4000.0))
    405285
    """
    wc = 2 * math.pi * half_power_hz / rate_hz
    return 1.0 / (2 * math.sin(wc / 2)) ** 2


def noise_gain(r: float) -> float:
    """``sum h_k^2`` of the filter's impulse response (far from the record's ends): the
    share of white noise's variance the envelope keeps, ``(1 / 2 pi) int |H|^2``.

    >>> g = noise_gain(weight_for(1.0, 4000.0))
    >>> round(g / (3 * (2 * math.pi / 4000) / (8 * math.sqrt(2))), 4)  # its small-band limit
    1.0
    """
    from scipy.integrate import quad

    wc = 2 * math.asin(0.5 / math.sqrt(r))
    h2 = lambda w: 1.0 / (1.0 + r * r * (2 * math.sin(w / 2)) ** 4) ** 2  # noqa: E731
    near, _ = quad(h2, 0.0, 20 * wc, limit=200)
    far, _ = quad(h2, 20 * wc, math.pi, limit=200)
    return float(near + far) / math.pi


def settle_samples(half_power_hz: float, rate_hz: float) -> int:
    """Samples at each end of a record where the envelope still leans on the missing
    outside (six of the filter's time constants ``1 / (2 pi half_power_hz)``: the end's
    pull decays below 0.3 % of the record's first envelope)."""
    return math.ceil(6 * rate_hz / (2 * math.pi * half_power_hz))


def envelope(y: FloatArray, theta: FloatArray, weight: FloatArray, r: float) -> ComplexArray:
    """The order's phasor ``A`` at every sample (``a ~ Re(A e^{i theta})``).

    The data equation is taken on the real samples, ``y = Re(A e^{i theta})``, its two
    components solved together (the order's mirror at ``-theta`` then needs no filtering:
    a lost sample costs its own information only), with the structural weight ``r^2 / 2``
    on each component: on average a sample weighs ``1 / 2`` per component (``cos^2``), so
    the passband is the one-sided filter's, ``H`` above.  The unknowns interleaved
    (``Re A_0, Im A_0, Re A_1, ...``), the system is banded (four above the diagonal).

    Parameters
    ----------
    y
        The samples on a uniform grid [any unit; ``A`` has it].
    theta
        The order's angle at each sample [rad] (``k theta`` for the ``k``-th order).
    weight
        Each sample's weight: 1 measured, 0 missing (its ``y`` is not read).
    r
        The structural weight (:func:`weight_for`).
    """
    from scipy.linalg import cho_solve_banded, cholesky_banded

    n = len(y)
    if n < 4:
        raise ValueError(f"a Vold-Kalman filter needs 4 samples at least, got {n}")
    half = 0.5 * r * r
    main = np.full(n, 6.0)  # D'D for the second difference D
    main[[0, -1]], main[[1, -2]] = 1.0, 5.0
    first = np.full(n - 1, -4.0)
    first[[0, -1]] = -2.0
    w = np.asarray(weight, dtype=float)
    c, s = np.cos(theta), np.sin(theta)
    yw = w * np.where(w > 0, y, 0.0)
    ab = np.zeros((5, 2 * n))  # upper form: ab[4] the diagonal, ab[4 - k] k above it
    ab[4, 0::2], ab[4, 1::2] = w * c * c + half * main, w * s * s + half * main
    ab[3, 1::2] = -w * c * s
    ab[2, 2::2], ab[2, 3::2] = half * first, half * first
    ab[0, 4::2], ab[0, 5::2] = half, half
    rhs = np.empty(2 * n)
    rhs[0::2], rhs[1::2] = yw * c, -yw * s
    factor = cholesky_banded(ab, lower=False, check_finite=False)
    z = cho_solve_banded((factor, False), rhs, check_finite=False)
    for _ in range(REFINE):  # the system's condition grows as r^2: refined on its residual
        z = z + cho_solve_banded((factor, False), rhs - _apply(z, w, c, s, half),
                                 check_finite=False)  # fmt: skip
    A: ComplexArray = z[0::2] + 1j * z[1::2]
    return A


REFINE = 3
"""Steps of iterative refinement after the banded Cholesky solve: a 0.2 Hz filter at 4 kHz
has ``r^2 ~ 1e13`` and loses about that many times the float's precision in one solve;
each step takes the error down by as much again (to rounding in three)."""


def _apply(z: FloatArray, w: FloatArray, c: FloatArray, s: FloatArray,
           half: float) -> FloatArray:  # fmt: skip
    """The normal equations' matrix times the interleaved unknowns ``z`` (exactly, in
    float64: the residual that refines the banded solve)."""
    ar, ai = z[0::2], z[1::2]
    model = w * (ar * c - ai * s)

    def dtd(v: FloatArray) -> FloatArray:
        u = v[:-2] - 2 * v[1:-1] + v[2:]
        out = np.zeros_like(v)
        out[:-2] += u
        out[1:-1] -= 2 * u
        out[2:] += u
        return out

    out = np.empty_like(z)
    out[0::2] = model * c + half * dtd(ar)
    out[1::2] = -model * s + half * dtd(ai)
    return out
