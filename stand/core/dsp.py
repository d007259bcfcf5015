"""The 1x complex amplitude of a support's acceleration, with its uncertainty.

Pure numerics: arrays in, arrays out, SI units, no I/O.

**Shaft angle.**  A node reports its reference edges as sample positions
``p_k`` with revolution counts ``r_k``.  The shaft angle at sample ``n`` is
``theta(n) = gamma + 2 pi r(n)``, with ``r(n)`` a cubic Hermite curve through
``(p_k, r_k)`` whose slopes are the three-point derivatives, exact for a
constant angular acceleration (:func:`shaft_angle`).  So non-integer
revolutions, a speed ramp and gaps need no resampling: every sample present
gets its own angle, and a lost MARK only widens one interval.

**Estimator** (:func:`fit_1x`).  Least squares of the samples on::

    a_n = Re(A g_n e^{i theta_n}) + Re(A2 e^{2 i theta_n}) + Re(A3 e^{3 i theta_n}) + c

with ``g_n = (w_n / w_ref)^2`` (the amplitude growing as the speed squared;
1 at a constant speed) and ``w_ref`` the mean speed.  ``A`` is then the 1x
phasor at ``w_ref``.  No stand's amplitude grows exactly as ``w^2`` (near
its resonances the exponent is lower), so once the speed spans more than
3 % a free first-order term ``Re(B g_n (w_n / w_ref - 1) e^{i theta_n})`` is
fitted too: what is left is second order in the speed change.

An optional taper (Hann) weights the samples against a non-synchronous
neighbour close to 1x; it costs ``sum(w^2) N / sum(w)^2`` (1.5 for Hann) in
noise variance, reported as ``noise_cost``.

**Uncertainty.**  The noise at 1x is estimated from the residuals' power in
side bands around 1x (orders ``1 +- k/R``, ``k = 2 .. K+1``, ``R`` the
revolutions measured: the DFT bins next to 1x), not from the whole residual.
For white noise the two agree; for coloured noise (a neighbour, structural
resonances) the side bands see what is near 1x.  The coefficient covariance
is the weighted least-squares sandwich with that noise level.

In white noise of variance ``sigma^2`` the estimator reaches the Cramer-Rao
bound ``var(Re A) = var(Im A) = 2 sigma^2 / N`` to within the few columns
it fits besides 1x (tested by Monte Carlo to 10 %).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stand.core.inverse import Diagnostic
from stand.core.model import FloatArray

SIDE_BANDS = 8
"""Side bands each side of 1x used to estimate the noise at 1x."""


def median(x: ArrayLike) -> float:
    """``np.median`` of the values ``x`` (NaN if one is NaN or there are none), to the bit.

    The same partition and the same mean of the middle two; numpy's own
    imports ``numpy.ma`` on its first call (8 ms of every command that measures).
    """
    a = np.asarray(x, dtype=np.float64).ravel()
    n = len(a)
    if n == 0:
        return math.nan
    k = n // 2
    part = np.partition(a, [k - 1, k, n - 1] if n % 2 == 0 else [k, n - 1])
    if math.isnan(part[-1]):  # NaN sorts last
        return math.nan
    return float(part[k]) if n % 2 else 0.5 * (float(part[k - 1]) + float(part[k]))


def radius_factor(dof: float, p: float = 0.95) -> float:
    """``k`` such that ``k^2 var`` is the squared radius holding a complex error with probability p.

    The error's two components have variance ``var`` each, estimated with
    ``dof`` real degrees of freedom: ``|e|^2 / (2 var_hat)`` follows F(2, dof),
    whose quantile is ``(dof / 2) ((1 - p)^(-2 / dof) - 1)`` in closed form.
    With ``dof`` infinite it is the chi-square radius ``sqrt(-2 ln(1 - p))``.

    >>> round(radius_factor(float("inf")), 4), round(radius_factor(32.0), 4)
    (2.4477, 2.5669)
    """
    if math.isinf(dof):
        return math.sqrt(-2.0 * math.log(1 - p))
    return math.sqrt(2.0 * (dof / 2) * ((1 - p) ** (-2.0 / dof) - 1))


def radius95(cov: ArrayLike, dof: float = float("inf")) -> float:
    """Radius of the 95 % circle of a complex error with covariance ``cov`` (2 x 2).

    Taken on the largest axis of the error ellipse (conservative), with
    :func:`radius_factor` for a noise level estimated with ``dof`` degrees of
    freedom.

    >>> round(radius95([[1.0, 0.0], [0.0, 4.0]]), 4)
    4.8955
    """
    var = float(np.max(np.linalg.eigvalsh(np.asarray(cov, dtype=float))))
    return radius_factor(dof) * math.sqrt(max(var, 0.0))


def sensor_response(gain: float, delay_s: float, omega_rad_s: float) -> complex:
    """What a sensor does to a phasor at ``omega``: it reads ``gain * a(t - delay)``.

    The node's phasor is the support's times ``gain e^{-i omega delay}``.

    >>> sensor_response(2.0, 0.0, 100.0)
    (2+0j)
    """
    return complex(gain * np.exp(-1j * omega_rad_s * delay_s))


HANN_NOISE_COST = 1.5
SPEED_SPAN_SLOPE = 0.03
"""Speed span (max - min over mean) beyond which the 1x amplitude also gets a free
first-order term in speed."""


def _hermite_slopes(x: FloatArray, y: FloatArray) -> FloatArray:
    """Three-point derivatives at the knots (exact for quadratics, any spacing)."""
    n = len(x)
    m = np.empty(n)
    if n == 2:
        m[:] = (y[1] - y[0]) / (x[1] - x[0])
        return m
    h = np.diff(x)
    d = np.diff(y) / h
    h0, h1, d0, d1 = h[:-1], h[1:], d[:-1], d[1:]
    m[1:-1] = (h1 * d0 + h0 * d1) / (h0 + h1)
    m[0] = ((2 * h[0] + h[1]) * d[0] - h[0] * d[1]) / (h[0] + h[1])
    m[-1] = ((2 * h[-1] + h[-2]) * d[-1] - h[-1] * d[-2]) / (h[-1] + h[-2])
    return m


def shaft_angle(
    sample_index: ArrayLike, edge_position: ArrayLike, edge_rev: ArrayLike, gamma_rad: float = 0.0
) -> tuple[NDArray[np.bool_], FloatArray, FloatArray]:
    """Shaft angle and speed at every sample between the first and the last edge.

    Parameters
    ----------
    sample_index
        Sample indices (one node, one clock segment), increasing.
    edge_position
        Reference edges as sample positions (sub-sample), increasing.
    edge_rev
        Revolution count of each edge (unwrapped; a gap means lost MARKs).
    gamma_rad
        Angle of the reference sensor from the accelerometer axis [rad].

    Returns
    -------
    inside : ndarray of bool
        Samples between the first and last edge (the others get no angle).
    theta_rad : ndarray
        Shaft angle of each inside sample [rad] (the seed's ``w t``).
    omega_rad_per_sample : ndarray
        Its rate [rad per sample].

    Examples
    --------
    >>> inside, th, w = shaft_angle([0, 5, 10, 15, 20], [0.0, 10.0, 20.0], [0, 1, 2])
    >>> inside.tolist(), [round(float(t / np.pi), 6) for t in th]
    ([True, True, True, True, True], [0.0, 1.0, 2.0, 3.0, 4.0])
    """
    n = np.asarray(sample_index, dtype=float)
    knots = angle_knots(edge_position, edge_rev)
    x = knots[0]
    if len(x) < 2:
        return np.zeros(len(n), bool), np.zeros(0), np.zeros(0)
    inside = (n >= x[0]) & (n <= x[-1])
    theta, dtheta = angle_at(knots, n[inside])
    return inside, gamma_rad + theta, dtheta


def angle_knots(
    edge_position: ArrayLike, edge_rev: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The shaft angle's knots: edge positions, their angles [rad] and slopes [rad per sample]."""
    x = np.asarray(edge_position, dtype=float)
    rev = np.asarray(edge_rev, dtype=float)
    if len(x) < 2:
        return x, np.zeros(len(x)), np.zeros(len(x))
    y = 2 * math.pi * (rev - rev[0])
    return x, y, _hermite_slopes(x, y)


def edge_jitter(edge_position: ArrayLike, edge_rev: ArrayLike) -> float:
    """Rms timing jitter of the reference edges [samples], robustly from their second
    differences.

    For consecutive revolutions, ``x[k+1] - 2 x[k] + x[k-1]`` of independent
    jitter of rms ``sigma`` has variance ``6 sigma^2``; a steady or slowly
    changing speed adds an almost constant part, which the median removes.
    The scale is ``1.4826 MAD / sqrt(6)`` (Gaussian-consistent); fewer than 8
    second differences give 0.  A speed that varies from one revolution to the
    next also reads as jitter: the interval is then widened, never narrowed.
    """
    x = np.asarray(edge_position, dtype=float)
    r = np.diff(np.asarray(edge_rev, dtype=np.int64))
    one = (r[:-1] == 1) & (r[1:] == 1)
    d2 = np.diff(x, 2)[one]
    if len(d2) < 8:
        return 0.0
    mad = median(np.abs(d2 - median(d2)))
    return 1.4826 * mad / math.sqrt(6.0)


def angle_at(
    knots: tuple[FloatArray, FloatArray, FloatArray], s: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Shaft angle [rad, from the first edge] and speed [rad per sample] at positions ``s``
    (increasing) between the first and the last knot (cubic Hermite, :func:`shaft_angle`).

    Only the knots around ``s`` are touched, and each interval's cubic is
    spread over its samples by :func:`numpy.repeat`: the cost is that of ``s``,
    whatever the length of the run the knots cover.
    """
    x, y, m = knots
    n = len(s)
    if n == 0:
        return np.zeros(0), np.zeros(0)
    inner = x[1:-1]
    # interval k (between knots k and k + 1) holds the samples past k inner knots
    k0, k1 = np.minimum(np.searchsorted(inner, [s[0], s[-1]], side="left"), len(x) - 2)
    cuts = np.searchsorted(s, x[k0 + 1 : k1 + 1], side="right")
    counts = np.diff(cuts, prepend=0, append=n)
    xk, yk, mk = x[k0 : k1 + 2], y[k0 : k1 + 2], m[k0 : k1 + 2]
    h = np.diff(xk)
    hm0, hm1 = h * mk[:-1], h * mk[1:]
    dy = np.diff(yk)
    # the cubic per interval, in t = u / h: y + hm0 t + c2 t^2 + c3 t^3; here in u (the
    # samples past the interval's first knot): y + m u + b2 u^2 + b3 u^3, no division a sample
    b2 = (3 * dy - 2 * hm0 - hm1) / (h * h)
    b3 = (hm0 + hm1 - 2 * dy) / (h * h * h)
    u = s - np.repeat(xk[:-1], counts)
    g1, g2 = np.repeat(mk[:-1], counts), np.repeat(b2, counts)
    theta = np.repeat(b3, counts)
    theta *= u  # b3 u
    w = theta * 3.0
    theta += g2
    g2 *= 2.0
    w += g2
    w *= u
    w += g1  # the derivative: m + 2 b2 u + 3 b3 u^2
    theta *= u
    theta += g1
    theta *= u
    theta += np.repeat(yk[:-1], counts)
    return theta, w


@dataclass(frozen=True)
class Phasor:
    """One support's 1x acceleration, as measured.

    Attributes
    ----------
    A_m_s2 : complex
        1x phasor at ``omega_ref``: ``a = Re(A e^{i theta})`` [m/s^2].
    cov_m2_s4 : ndarray, shape (2, 2)
        Covariance of ``(Re A, Im A)`` [(m/s^2)^2].
    harmonics_m_s2 : dict
        ``{2: A2, 3: A3, 5: A5}``: the 2x and 3x phasors fitted alongside, and the 5x
        projected from the residual (absent when 5x is beyond half the sample rate).
    omega_ref_rad_s : float
        The speed ``A`` refers to (the mean speed over the samples) [rad/s].
    samples : int
        Samples used.
    revolutions : float
        Revolutions they span.
    noise_m_s2 : float
        Noise level at 1x from the side bands (rms per sample) [m/s^2].
    residual_m_s2 : float
        Rms of all residuals [m/s^2].
    noise_cost : float
        Variance factor of the taper (1 without).
    noise_dof : float
        Real degrees of freedom of the noise estimate (4 per side band pair).
    """

    A_m_s2: complex
    cov_m2_s4: FloatArray
    harmonics_m_s2: dict[int, complex]
    omega_ref_rad_s: float
    samples: int
    revolutions: float
    noise_m_s2: float
    residual_m_s2: float
    noise_cost: float = 1.0
    noise_dof: float = float("inf")
    diagnostics: tuple[Diagnostic, ...] = field(default=())

    @property
    def radius95_m_s2(self) -> float:
        """Radius of the 95 % circle around ``A`` (on the largest axis of the error ellipse)."""
        return radius95(self.cov_m2_s4, self.noise_dof)


def fit_1x(
    theta_rad: ArrayLike,
    accel_m_s2: ArrayLike,
    omega_rad_per_sample: ArrayLike | None = None,
    *,
    rate_hz: float = 1.0,
    orders: tuple[int, ...] = (2, 3),
    speed_squared: bool = True,
    taper: bool = False,
    side_bands: int = SIDE_BANDS,
) -> Phasor:
    """The 1x phasor of samples at known shaft angles, and its covariance.

    Parameters
    ----------
    theta_rad
        Shaft angle of each sample [rad] (:func:`shaft_angle`).
    accel_m_s2
        The samples [m/s^2] (only those present: gaps are simply absent).
    omega_rad_per_sample
        Speed at each sample [rad per sample]; needed for ``speed_squared``
        and for ``omega_ref_rad_s``.
    rate_hz
        Sample rate, to report ``omega_ref_rad_s`` in rad/s.
    orders
        Further orders fitted alongside (2x, 3x by default).
    speed_squared
        Let the 1x amplitude grow as ``(w / w_ref)^2``.
    taper
        Hann weights over the samples (against a neighbour close to 1x).
    side_bands
        Side bands each side of 1x for the noise estimate.

    Returns
    -------
    Phasor
    """
    th = np.asarray(theta_rad, dtype=float)
    a = np.asarray(accel_m_s2, dtype=float)
    n = len(th)
    if omega_rad_per_sample is None:
        w = np.full(n, (th[-1] - th[0]) / max(n - 1, 1))
    else:
        w = np.asarray(omega_rad_per_sample, dtype=float)
    w_ref = float(np.mean(w))
    g = (w / w_ref) ** 2 if speed_squared else np.ones(n)
    c1, s1 = np.cos(th), np.sin(th)
    cols = [g * c1, g * s1, np.ones(n)]
    delta = w / w_ref - 1.0
    sloped = speed_squared and float(np.max(delta) - np.min(delta)) > SPEED_SPAN_SLOPE
    if sloped:  # no stand's amplitude grows exactly as w^2: a free first-order term too
        cols += [g * delta * c1, g * delta * s1]
    ck, sk = c1, s1
    for k in range(2, max(orders, default=1) + 1):  # cos k theta by recurrence
        ck, sk = ck * c1 - sk * s1, sk * c1 + ck * s1
        if k in orders:
            cols += [ck, sk]
    X = np.column_stack(cols)
    span = th[-1] - th[0]
    if taper and span > 0:
        wt = np.sin(math.pi * (th - th[0]) / span) ** 2
        Xw = X * wt[:, None]
    else:
        wt, Xw = np.ones(n), X
    XtWX = X.T @ Xw
    coef = np.linalg.solve(XtWX, Xw.T @ a)
    r = a - X @ coef
    # noise at 1x from the residual's side bands (orders 1 +- k/R)
    revs = (th[-1] - th[0]) / (2 * math.pi)
    base = ((wt * r if taper else r) * (c1 - 1j * s1)).astype(np.complex64)  # 1x moved to 0
    # one bin is order 1/R; single precision is ample for a noise level (1e-7 relative)
    step = np.exp(-1j * (th - th[0]) / max(revs, 1e-12)).astype(np.complex64)
    bins = np.empty((side_bands, n), dtype=np.complex64)  # step^k, k = 2 .. K+1
    bins[0] = step * step
    for k in range(1, side_bands):
        np.multiply(bins[k - 1], step, out=bins[k])
    # sum(base step^k) and sum(base conj(step)^k) = conj(sum(conj(base) step^k)): one product
    sums = np.stack((base, np.conj(base))) @ bins.T
    sigma2 = float(np.mean(np.abs(sums.astype(complex)) ** 2)) / float(np.sum(wt * wt))
    bread = np.linalg.inv(XtWX)
    cov_coef = sigma2 * (bread @ (Xw.T @ Xw) @ bread if Xw is not X else bread)
    cc, cs, ss = cov_coef[0, 0], cov_coef[0, 1], cov_coef[1, 1]
    harmonics: dict[int, complex] = {}
    j = 5 if sloped else 3
    for k in range(2, max(orders, default=1) + 1):
        if k in orders:
            harmonics[k] = complex(coef[j], -coef[j + 1])
            j += 2
    cost = float(np.sum(wt * wt) * n / np.sum(wt) ** 2)
    return Phasor(
        A_m_s2=complex(coef[0], -coef[1]),
        cov_m2_s4=np.array([[cc, -cs], [-cs, ss]]),
        harmonics_m_s2=harmonics,
        omega_ref_rad_s=w_ref * rate_hz,
        samples=n,
        revolutions=revs,
        noise_m_s2=math.sqrt(sigma2),
        residual_m_s2=float(np.sqrt(np.mean(r * r))),
        noise_cost=cost,
        noise_dof=4.0 * side_bands,
    )
