"""The 1x fit from sums: a run of any length in chunks, in bounded memory.

Pure numerics (arrays in, arrays out).  :func:`stand.core.dsp.fit_1x` fits
the samples it is given at once; here the same estimator is built from
sums that chunks of samples add up, so a one-hour run never holds more than
a chunk of temporaries:

* **Base columns.**  With ``u = w / w0 - 1`` for a fixed speed ``w0``
  (the run's median, known from the edges before any sample is touched),
  ``P = (1 + u)^2`` and ``Q = P u``, every column the fit may use is a
  fixed combination of ``B = [P c, P s, Q c, Q s, c2, s2, c3, s3, 1]``
  (``c, s = cos, sin theta``; ``c2 ... s3`` the 2x and 3x): with
  ``k = w0 / w_ref``, ``g c = k^2 P c`` and ``g delta c = k^3 (P + Q) c -
  k^2 P c``.  So the normal equations of any window are ``T' (B'B) T`` and
  ``T' B'a`` (:func:`model_transform`; :func:`base_rows` gives ``B'``), whatever
  ``w_ref`` the window has.
* **Block sums** of ``cos, sin, 1`` per block of whole revolutions give the
  gate's and the block check's fits (:func:`block_sums`).
* **Side bands** need the fitted coefficients, so they take a second pass
  over the window (:func:`side_band_sums`).

The results equal :func:`~stand.core.dsp.fit_1x` on the same samples to
rounding (tested to 1e-12 relative).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
AnyFloat = NDArray[np.floating[Any]]
"""Single or double precision (the side bands run in single)."""

N_BASE = 9
"""Base columns: P c, P s, Q c, Q s, c2, s2, c3, s3, 1 (the constant last: :meth:`WindowSums.add`
takes its sums apart from the 8 x 8 products, which BLAS forms in two thirds of the time of
9 x 9)."""
ONE = N_BASE - 1
"""The constant base column."""


def base_rows(c: FloatArray, s: FloatArray, w: FloatArray, w0: float) -> FloatArray:
    """The base columns of samples with ``cos, sin theta = c, s`` and speed ``w``, one row
    each (9, n): ``B'`` (rows are written and multiplied contiguously)."""
    n = len(c)
    B = np.empty((N_BASE, n))
    P, Q = B[2], B[3]  # P and Q live where Q c and Q s go, until those are written
    np.divide(w, w0, out=Q)  # 1 + u
    np.multiply(Q, Q, out=P)  # (1 + u)^2
    Q -= 1.0  # u
    Q *= P  # P u
    np.multiply(P, c, out=B[0])
    np.multiply(P, s, out=B[1])
    np.multiply(Q, c, out=B[2])  # over P: no longer needed
    np.multiply(Q, s, out=B[3])  # Q s last: B[3] is Q itself
    c2, s2 = double_angle(c, s, out=(B[4], B[5]))
    np.multiply(c2, c, out=B[6])
    B[6] -= s2 * s
    np.multiply(s2, c, out=B[7])
    B[7] += c2 * s
    B[ONE] = 1.0
    return B


def model_transform(w0: float, w_ref: float, sloped: bool) -> FloatArray:
    """``T`` with model columns ``X = B T``: ``g c, g s, 1, [g d c, g d s], c2, s2, c3, s3``.

    ``g = (w / w_ref)^2`` and ``d = w / w_ref - 1``, as in :func:`~stand.core.dsp.fit_1x`.
    """
    k = w0 / w_ref
    k2, k3 = k * k, k * k * k
    cols = []
    for j in (0, 1):  # g c, g s
        t = np.zeros(N_BASE)
        t[j] = k2
        cols.append(t)
    t = np.zeros(N_BASE)
    t[ONE] = 1.0
    cols.append(t)
    if sloped:
        for j in (0, 1):  # g d c = k^3 (P + Q) c - k^2 P c
            t = np.zeros(N_BASE)
            t[j] = k3 - k2
            t[j + 2] = k3
            cols.append(t)
    for j in (4, 5, 6, 7):
        t = np.zeros(N_BASE)
        t[j] = 1.0
        cols.append(t)
    return np.column_stack(cols)


@dataclass
class WindowSums:
    """What a set of samples adds to the 1x fit (sums of base columns and speeds).

    Attributes
    ----------
    G : ndarray (9, 9)
        ``B' B``.
    Ba : ndarray (9,)
        ``B' a``.
    n : int
        Samples.
    w_sum : float
        Sum of the speeds [rad per sample].
    w_min, w_max : float
        Lowest and highest speed.
    """

    G: FloatArray
    Ba: FloatArray
    n: int = 0
    w_sum: float = 0.0
    w_min: float = math.inf
    w_max: float = -math.inf

    @classmethod
    def zero(cls) -> WindowSums:
        return cls(np.zeros((N_BASE, N_BASE)), np.zeros(N_BASE))

    def copy(self) -> WindowSums:
        """An independent copy (:meth:`add` changes the arrays in place)."""
        return WindowSums(self.G.copy(), self.Ba.copy(), self.n, self.w_sum, self.w_min, self.w_max)

    def add(self, B: FloatArray, a: FloatArray, w: FloatArray) -> None:
        """Add samples (their base rows :func:`base_rows`, accelerations and speeds)."""
        if not len(a):
            return
        R = B[:ONE]  # the constant's products are the other columns' sums
        self.G[:ONE, :ONE] += np.dot(R, R.T)  # np.dot lets other threads run (matmul holds the GIL)
        sums = R.sum(axis=1)
        self.G[ONE, :ONE] += sums
        self.G[:ONE, ONE] += sums
        self.G[ONE, ONE] += len(a)
        self.Ba += np.dot(B, a)
        self.n += len(a)
        self.w_sum += float(np.sum(w))
        self.w_min = min(self.w_min, float(np.min(w)))
        self.w_max = max(self.w_max, float(np.max(w)))

    def __iadd__(self, other: WindowSums) -> WindowSums:
        self.G = self.G + other.G
        self.Ba = self.Ba + other.Ba
        self.n += other.n
        self.w_sum += other.w_sum
        self.w_min = min(self.w_min, other.w_min)
        self.w_max = max(self.w_max, other.w_max)
        return self


def block_sums(
    c: FloatArray, s: FloatArray, a: FloatArray, starts: NDArray[np.int64], n_blocks: int
) -> FloatArray:
    """Per-block sums for a fit on ``cos, sin, 1``: rows ``cc cs c s n aa ac as a`` (n_blocks, 9).

    ``starts``: where each of ``n_blocks`` blocks begins in the chunk (sorted;
    a block may be empty).
    """
    out = np.zeros((n_blocks, 9))
    if not len(a):
        return out
    sizes = np.diff(np.append(starts, len(a)))
    has = sizes > 0
    at = starts[has]
    rows = np.empty((5, len(a)))  # the products; c, s and a summed as they are (no copy)
    np.multiply(c, c, out=rows[0])
    np.multiply(c, s, out=rows[1])
    np.multiply(a, a, out=rows[2])
    np.multiply(a, c, out=rows[3])
    np.multiply(a, s, out=rows[4])
    sums = np.add.reduceat(rows, at, axis=1)
    out[has, 0], out[has, 1] = sums[0], sums[1]
    out[has, 2], out[has, 3] = np.add.reduceat(c, at), np.add.reduceat(s, at)
    out[has, 4] = sizes[has]
    out[has, 5:8] = sums[2:].T
    out[has, 8] = np.add.reduceat(a, at)
    return out


def block_fits(sums: FloatArray) -> tuple[NDArray[np.complex128], FloatArray, FloatArray]:
    """1x phasor, sample count and residual variance per sample of each block.

    The same least squares as fitting ``cos theta, sin theta, 1`` on each
    block's samples (blocks with fewer than 8 samples get an infinite variance).
    """
    cc, cs, c1, s1, n, aa, ac, as_, a1 = sums.T
    ss = n - cc
    M = np.stack(
        [np.stack([cc, cs, c1], -1), np.stack([cs, ss, s1], -1), np.stack([c1, s1, n], -1)], -2
    )
    rhs = np.stack([ac, as_, a1], -1)
    ok = n >= 8
    coef = np.zeros((len(n), 3))
    if ok.any():
        coef[ok] = np.linalg.solve(M[ok], rhs[ok][..., None])[..., 0]
    resid = aa - np.einsum("bi,bi->b", coef, rhs)
    var = np.where(ok, np.maximum(resid, 0) / np.maximum(n - 3, 1), np.inf)
    return coef[:, 0] - 1j * coef[:, 1], n, var


SIDE_BAND_GROUP = 64
"""Samples per group for the side bands of a long window (:func:`side_band_sums`)."""
TAYLOR_TOL = 1e-9
"""Largest first term left out of the side bands' Taylor series, relative to the sums."""


def side_band_sums(
    residual: AnyFloat,
    c: AnyFloat,
    s: AnyFloat,
    phase: AnyFloat,
    side_bands: int,
) -> NDArray[np.complex128]:
    """Side-band sums of one chunk: ``sum r e^{-i theta} e^{-+ i k phase}``, ``k = 2 .. K+1``.

    ``phase = (theta - theta_first) / R`` for the window's first angle and its
    revolutions ``R``: one DFT bin next to 1x is one unit of it.  Single
    precision is ample for a noise level (1e-7 relative); the chunks' sums are
    added in double.  Returns shape (2, side_bands): the upper and lower bands.

    In a long window ``phase`` moves little within a group of
    :data:`SIDE_BAND_GROUP` samples, so ``e^{-i k phase}`` is taken at each
    group's middle sample times its Taylor series in the distance ``d`` from
    it: the sums need only the moments ``sum r e^{-i theta} d^p`` of each
    group, ``p < P``, with ``P`` the fewest terms whose first term left out,
    ``(K+1 max|d|)^P / P!``, is below :data:`TAYLOR_TOL` (a 600 s window: 3
    terms).  A window too short for 8 terms is summed sample by sample.
    """
    n = len(residual)
    groups = n // SIDE_BAND_GROUP
    m = groups * SIDE_BAND_GROUP
    ph = phase[:m].reshape(groups, SIDE_BAND_GROUP)
    mid = SIDE_BAND_GROUP // 2
    d = ph - ph[:, mid : mid + 1]  # each sample's distance from its group's middle
    terms = _taylor_terms(d, side_bands + 1) if groups >= 2 else None
    if terms is None:
        return _side_bands_direct(residual, c, s, phase, side_bands)
    out = _side_bands_grouped(residual[:m], c[:m], s[:m], ph[:, mid], d, side_bands, terms)
    if m < n:
        out += _side_bands_direct(residual[m:], c[m:], s[m:], phase[m:], side_bands)
    return out


def _taylor_terms(d: AnyFloat, k_max: int) -> int | None:
    """Terms of the Taylor series the groups need for distances ``d`` from their middles
    (None: more than 8)."""
    x = k_max * float(np.max(np.abs(d)))
    if not math.isfinite(x):
        return None  # summed sample by sample, as ever: whatever it gives, it gives there
    term, p = 1.0, 0
    while term > TAYLOR_TOL:
        p += 1
        term *= x / p
        if p > 8:
            return None
    return p


def _side_bands_grouped(
    residual: AnyFloat, c: AnyFloat, s: AnyFloat, middle: AnyFloat, d: AnyFloat,
    side_bands: int, terms: int,
) -> NDArray[np.complex128]:  # fmt: skip
    """:func:`side_band_sums` from each group's moments: ``middle`` is each group's phase at
    its middle, ``d`` (groups, :data:`SIDE_BAND_GROUP`) each sample's distance from it."""
    shape = d.shape
    groups = shape[0]
    ref = middle.astype(np.float64)
    base = np.empty((2, *shape), np.float32)  # r e^{-i theta}: real and imaginary rows
    np.multiply(residual.reshape(shape), c.reshape(shape), out=base[0])
    np.multiply(residual.reshape(shape), s.reshape(shape), out=base[1])
    np.negative(base[1], out=base[1])
    moments = np.empty((terms, 2, groups))
    dp = np.ones(shape, np.float32)
    for p in range(terms):  # einsum multiplies and sums in one pass
        moments[p] = np.einsum("agl,gl->ag", base, dp)
        if p + 1 < terms:
            dp *= d
    M = moments[:, 0] + 1j * moments[:, 1]  # (terms, groups)
    z = np.exp(-1j * ref)  # e^{-i phase} at each group's middle, then its powers 2 .. K+1
    E = np.empty((groups, side_bands), complex)
    E[:, 0] = z * z
    for j in range(1, side_bands):
        np.multiply(E[:, j - 1], z, out=E[:, j])
    k = np.arange(2, side_bands + 2)
    coef = np.array([(-1j * k) ** p / math.factorial(p) for p in range(terms)])  # (terms, K)
    up = np.sum((M @ E) * coef, axis=0)
    low = np.sum((M.conj() @ E) * coef, axis=0)
    return np.stack((up, low))


def _side_bands_direct(
    residual: AnyFloat, c: AnyFloat, s: AnyFloat, phase: AnyFloat, side_bands: int
) -> NDArray[np.complex128]:
    """:func:`side_band_sums` sample by sample."""
    n = len(residual)
    base = np.empty(n, np.complex64)  # the residual with 1x moved to 0: r e^{-i theta}
    base.real = residual * c
    base.imag = residual * s
    np.negative(base.imag, out=base.imag)
    ph = phase.astype(np.float32)
    step = np.empty(n, np.complex64)  # e^{-i phase}
    step.real = np.cos(ph)
    step.imag = np.sin(ph)
    np.negative(step.imag, out=step.imag)
    bins = np.empty((side_bands, n), dtype=np.complex64)
    bins[0] = step * step
    for k in range(1, side_bands):
        np.multiply(bins[k - 1], step, out=bins[k])
    out: NDArray[np.complex128] = (np.stack((base, np.conj(base))) @ bins.T).astype(np.complex128)
    return out


def double_angle(
    c: AnyFloat, s: AnyFloat, out: tuple[AnyFloat, AnyFloat] | None = None
) -> tuple[AnyFloat, AnyFloat]:
    """``cos 2 theta, sin 2 theta`` from ``cos theta, sin theta = c, s`` (into ``out``)."""
    c2, s2 = (np.empty_like(c), np.empty_like(s)) if out is None else out
    np.multiply(c, c, out=c2)
    c2 -= s * s
    np.multiply(s, c, out=s2)
    s2 *= 2.0
    return c2, s2


def model_values(
    c: AnyFloat, s: AnyFloat, w: AnyFloat, w0: float, coef_base: AnyFloat,
    c2: AnyFloat, s2: AnyFloat,
) -> AnyFloat:  # fmt: skip
    """``B coef_base`` without forming ``B``: the fitted signal at each sample (``c2, s2``:
    :func:`double_angle` of ``c, s``)."""
    v = w / w0  # 1 + u, as in base_rows
    P = v * v
    u = v - 1.0
    b = coef_base
    out: AnyFloat = (b[0] + b[2] * u) * c
    out += (b[1] + b[3] * u) * s
    out *= P
    out += b[ONE]
    # b4 c2 + b5 s2 + b6 c3 + b7 s3, with c3 = c2 c - s2 s and s3 = s2 c + c2 s
    h = b[6] * c
    h += b[7] * s
    h += b[4]
    h *= c2
    out += h
    h = b[7] * c
    h -= b[6] * s
    h += b[5]
    h *= s2
    out += h
    return out
