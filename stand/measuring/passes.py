"""One node's stream read in chunks: the gate and the passes of the 1x fit.

:func:`node_phasor` is what :func:`stand.measuring.measure.measure` does per node.  A
node's samples are read in chunks of :data:`CHUNK` samples.  The first pass
computes each chunk's shaft angle once, and from the same cos and sin it adds
up the sums the gate and the block check need (per block of
:data:`BLOCK_REVS` revolutions) and the fit's normal equations (per chunk; a
chunk holds whole blocks, so a window that starts at any block is a sum of
chunks, and of one chunk redone).  A second pass over the window adds the
residual's side bands (the noise at 1x) once the coefficients are known,
from a single-precision copy the first pass kept (16 bytes a sample, up to
:data:`KEEP_BYTES`), or computing each chunk's angle again.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from stand.core import rad_s_to_rpm
from stand.core.dsp import (
    SIDE_BANDS,
    SPEED_SPAN_SLOPE,
    Phasor,
    angle_at,
    angle_knots,
    edge_jitter,
    median,
)
from stand.core.fitsums import (
    WindowSums,
    base_rows,
    block_sums,
    double_angle,
    model_transform,
    model_values,
    side_band_sums,
)
from stand.core.trig import cos_sin
from stand.drivers.streams import NodeStream
from stand.errors import MeasurementError, SensorFaultError
from stand.i18n.words import said
from stand.measuring.gate import (
    BLOCK_REVS,
    Window,
    node_segment,
    settled_block,
    steady_revolutions,
)

CHUNK = 1 << 16
"""Samples per chunk (about): a chunk holds whole blocks of revolutions."""
KEEP_BYTES = 64 << 20
"""The first pass keeps a single-precision copy of each sample's angle, cos, sin and speed
(16 bytes a sample) for the second when it takes no more than this (a node's 17 min at
4 kHz); a longer run's second pass computes them again.  Kept: 0.145 s a node at 600 s;
computed again: 0.19 s (fresh memory costs more than the arithmetic only past that)."""


@dataclass(frozen=True)
class NodeFit:
    """What a live update needs to extend one node's untapered fit
    (:mod:`stand.measuring.live_fit`).

    ``sums`` are the fit's normal equations over the window, which ends at the
    edge whose revolution counter reads ``last_rev``; ``period`` is the
    window's median revolution [samples] (the new revolutions must keep to it);
    the noise (``sigma2``, per sample), the 5x and the residual's rms carry
    over from the last full pass, as does ``scatter`` (the blocks' scatter
    ratio, set by :func:`stand.measuring.measure.measure`).
    """

    gamma: float
    w0: float
    sums: WindowSums
    last_rev: int
    period: float
    window: Window
    span_rad: float
    sigma2: float
    h5: complex
    residual_m_s2: float
    rate_hz: float
    scale_m_s2: float
    scatter: float = 0.0


class _NodeRun:
    """One node's longest segment, read in chunks: the passes of :func:`_node_phasor`."""

    def __init__(self, s: NodeStream, gamma: float) -> None:
        self.s = s
        self.lo, self.hi, self.pos, self.rev = node_segment(s)
        self.knots = angle_knots(self.pos, self.rev)
        self.gamma = gamma

    def find(self, positions: np.ndarray, side: str = "left") -> np.ndarray:
        """The first sample at or after each position (``side="right"``: after), absolute.

        Sample indices are integers: searching for ``ceil`` (``floor``) of a
        position needs no conversion of the whole index array.
        """
        seg = self.s.index[self.lo : self.hi]
        key = np.ceil(positions) if side == "left" else np.floor(positions)
        found = np.searchsorted(seg, key.astype(np.int64), side=side)  # type: ignore[call-overload]
        return self.lo + np.asarray(found, dtype=np.int64)

    def chunk(self, i0: int, i1: int) -> tuple[np.ndarray, ...]:
        """Samples ``i0:i1``: shaft angle, speed, acceleration, cos and sin of the angle."""
        at = self.s.index[i0:i1].astype(np.float64)
        th, w = angle_at(self.knots, at)
        th += self.gamma
        return th, w, self.s.accel(i0, i1), *cos_sin(th)

    def angle(self, i: int) -> float:
        """The shaft angle at sample ``i`` [rad]."""
        th, _ = angle_at(self.knots, self.s.index[i : i + 1].astype(np.float64))
        return float(th[0]) + self.gamma


@dataclass
class _Kept:
    """What the first pass keeps for the second, in single precision (16 bytes a sample).

    The side bands are a noise level (single precision already); the residual
    from ``c, s, w`` in single precision is off by about 1e-7 of the 1x
    amplitude, far below any noise.  ``phase`` is the angle from the first
    sample kept [rad].
    """

    lo: int
    phase: np.ndarray
    c: np.ndarray
    s: np.ndarray
    w: np.ndarray


def _first_pass(
    run: _NodeRun, starts: np.ndarray, end: int, n_full: int, w0: float
) -> tuple[np.ndarray, list[tuple[int, int, WindowSums]], _Kept | None]:
    """Block sums of the ``n_full`` full blocks, and the fit's sums per chunk of blocks.

    ``starts``: the first sample of each block (the last one is the tail up to
    ``end``).  Returns the block sums, ``(first block, last block + 1, sums)``
    per chunk, and the copy the second pass reads (None past :data:`KEEP_BYTES`).
    """
    lo = int(starts[0])
    kept = None
    if 16 * (end - lo) <= KEEP_BYTES:
        # one allocation: past 32 MB (9 min at 4 kHz) it is memory mapped afresh, in huge
        # pages where the kernel offers them, not heap pages shared with a forked child
        # (each first write to one of those is copied: 58,000 page faults -> 39,000 at 600 s)
        kept = _Kept(lo, *np.empty((4, end - lo), np.float32))
    th_lo = run.angle(lo) if end > lo else 0.0
    blocks = np.zeros((n_full, 9))
    chunks: list[tuple[int, int, WindowSums]] = []
    bounds = np.append(starts, end)
    j0 = 0
    while j0 < len(starts):
        j1 = int(np.searchsorted(bounds, bounds[j0] + CHUNK, side="right"))
        j1 = min(max(j1 - 1, j0 + 1), len(starts))
        i0, i1 = int(bounds[j0]), int(bounds[j1])
        th, w, a, c, s = run.chunk(i0, i1)
        if kept is not None:
            k = slice(i0 - lo, i1 - lo)
            np.subtract(th, th_lo, out=kept.phase[k], casting="same_kind")
            kept.c[k], kept.s[k], kept.w[k] = c, s, w
        full = min(j1, n_full)
        if full > j0:
            upto = int(bounds[full]) - i0
            blocks[j0:full] = block_sums(
                c[:upto], s[:upto], a[:upto], starts[j0:full] - i0, full - j0
            )
        sums = WindowSums.zero()
        sums.add(base_rows(c, s, w, w0), a, w)
        chunks.append((j0, j1, sums))
        j0 = j1
    return blocks, chunks, kept


def _window_sums(
    run: _NodeRun, chunks: list[tuple[int, int, WindowSums]], starts: np.ndarray, end: int,
    first: int, w0: float,
) -> WindowSums:  # fmt: skip
    """The fit's sums from block ``first`` to the end (one chunk redone if it starts inside)."""
    total = WindowSums.zero()
    for j0, j1, sums in chunks:
        if j0 >= first:
            total += sums
        elif j1 > first:  # the window starts inside this chunk: redo its part
            i1 = int(starts[j1]) if j1 < len(starts) else end
            _, w, a, c, s = run.chunk(int(starts[first]), i1)
            total.add(base_rows(c, s, w, w0), a, w)
    return total


def _window_chunks(
    run: _NodeRun, kept: _Kept | None, i0: int, i1: int
) -> Iterator[tuple[np.ndarray, ...]]:
    """The window's samples by chunks: angle from the window's start, speed, acceleration,
    cos and sin; read from the first pass's copy, or computed again."""
    ph0 = run.angle(i0) if kept is None else kept.phase[i0 - kept.lo]
    for k0 in range(i0, i1, CHUNK):
        k1 = min(k0 + CHUNK, i1)
        if kept is None:
            th, w, a, c, s = run.chunk(k0, k1)
            th -= ph0
            yield th, w, a, c, s
        else:
            k = slice(k0 - kept.lo, k1 - kept.lo)
            yield kept.phase[k] - ph0, kept.w[k], run.s.accel(k0, k1), kept.c[k], kept.s[k]


def _second_pass(
    run: _NodeRun, kept: _Kept | None, i0: int, i1: int, w0: float, T: np.ndarray,
    coef: np.ndarray, span: float, taper: bool,
) -> tuple[np.ndarray, float, float, float, complex]:  # fmt: skip
    """Side-band sums of the residual over the window, sum r^2, sum wt^2, sum wt, and
    ``sum r e^{-5 i theta}`` (the fit has no 5x column: the residual holds all of it)."""
    revs = span / (2 * math.pi)
    bands: np.ndarray = np.zeros((2, SIDE_BANDS), complex)
    rr = wt2 = wt1 = 0.0
    h5 = 0j
    b = T @ coef
    per_bin = 1.0 / max(revs, 1e-12)
    for th, w, a, c, s in _window_chunks(run, kept, i0, i1):
        c2, s2 = double_angle(c, s)
        r = a - model_values(c, s, w, w0, b.astype(c.dtype), c2, s2)
        rr += float(np.dot(r, r))
        if taper and span > 0:
            wt = np.sin((math.pi / span) * th) ** 2
            wt2 += float(np.dot(wt, wt))
            wt1 += float(np.sum(wt))
            r *= wt
        else:
            wt2 += len(r)
            wt1 += len(r)
        phase = (th * per_bin).astype(np.float32)
        bands += side_band_sums(r, c, s, phase, SIDE_BANDS)
        c5, s5 = _fifth(c, s, c2, s2)
        h5 += complex(float(np.dot(r, c5)), -float(np.dot(r, s5)))
    return bands, rr, wt2, wt1, h5


def _fifth(
    c: np.ndarray, s: np.ndarray, c2: np.ndarray, s2: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``cos 5 theta, sin 5 theta`` from ``cos, sin`` of ``theta`` and ``2 theta``, by the
    double angle once more and one sum (real arithmetic: a third of the time of complex
    powers)."""
    c4, s4 = double_angle(c2, s2)
    c5 = c4 * c
    c5 -= s4 * s
    s4 *= c
    s4 += c4 * s
    return c5, s4


def _tapered_normal_equations(
    run: _NodeRun, i0: int, i1: int, w0: float, T: np.ndarray, th0: float, span: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``X'WX``, ``X'Wa`` and ``X'W^2 X`` with Hann weights over the window."""
    m = T.shape[1]
    XtWX, XtWa, XtW2X = np.zeros((m, m)), np.zeros(m), np.zeros((m, m))
    for k0 in range(i0, i1, CHUNK):
        k1 = min(k0 + CHUNK, i1)
        th, w, a, c, s = run.chunk(k0, k1)
        X = (T.T @ base_rows(c, s, w, w0)).T
        wt = np.sin(math.pi * (th - th0) / span) ** 2
        Xw = X * wt[:, None]
        XtWX += X.T @ Xw
        XtWa += Xw.T @ a
        XtW2X += Xw.T @ Xw
    return XtWX, XtWa, XtW2X


def _steady(pos: np.ndarray, rev: np.ndarray, gate: bool) -> tuple[int, int, list[str]]:
    """The edges the fit spans: the steady revolutions (gated), or all of them."""
    if gate:
        return steady_revolutions(pos, rev)
    if len(pos) < 2:
        raise MeasurementError(f"only {len(pos)} reference edges: need at least 2")
    return 0, len(pos) - 1, []


def _check_aliasing(w_ref: float, rate: float) -> None:
    """The fit's 3x columns must stay below half the sample rate (``w_ref`` in radians per
    sample), else they alias: refused, naming the speed and the rate."""
    if w_ref > math.pi / 3:
        raise SensorFaultError(
            f"the shaft turns at {rad_s_to_rpm(w_ref * rate):.0f} rpm: its 3x "
            f"({3 * w_ref * rate / (2 * math.pi):.0f} Hz) is beyond half the node's sample rate "
            f"({rate / 2:g} Hz); it cannot be measured at this rate"
        )


def _harmonics(coef: np.ndarray, sloped: bool, w_ref: float, h5: complex) -> dict[int, complex]:
    """The 2x and 3x phasors from the fit's coefficients, and the 5x (from the residual,
    ``h5``) when it lies below half the sample rate."""
    j = 5 if sloped else 3
    out = {2: complex(coef[j], -coef[j + 1]), 3: complex(coef[j + 2], -coef[j + 3])}
    if 5 * w_ref < math.pi:
        out[5] = h5
    return out


def _phasor(
    coef: np.ndarray, cov_coef: np.ndarray, sloped: bool, w_ref: float, rate_hz: float,
    n: int, span: float, sigma2: float, residual: float, h5: complex, noise_cost: float,
) -> Phasor:  # fmt: skip
    """The phasor of a fit's coefficients and their covariance (``w_ref`` in radians per
    sample, ``span`` the window's shaft angle [rad], ``sigma2`` the noise per sample)."""
    cc, cs, ss = cov_coef[0, 0], cov_coef[0, 1], cov_coef[1, 1]
    return Phasor(
        A_m_s2=complex(coef[0], -coef[1]),
        cov_m2_s4=np.array([[cc, -cs], [-cs, ss]]),
        harmonics_m_s2=_harmonics(coef, sloped, w_ref, h5),
        omega_ref_rad_s=w_ref * rate_hz,
        samples=n,
        revolutions=span / (2 * math.pi),
        noise_m_s2=math.sqrt(sigma2),
        residual_m_s2=residual,
        noise_cost=noise_cost,
        noise_dof=4.0 * SIDE_BANDS,
    )


def sums_phasor(fit: NodeFit) -> Phasor:
    """The untapered phasor of a :class:`NodeFit`'s sums (its noise carried over)."""
    sums = fit.sums
    w_ref = sums.w_sum / sums.n
    sloped = (sums.w_max - sums.w_min) / w_ref > SPEED_SPAN_SLOPE
    T = model_transform(fit.w0, w_ref, sloped)
    XtWX = T.T @ sums.G @ T
    coef = np.linalg.solve(XtWX, T.T @ sums.Ba)
    cov_coef = fit.sigma2 * np.linalg.inv(XtWX)
    return _phasor(
        coef, cov_coef, sloped, w_ref, fit.rate_hz, sums.n, fit.span_rad, fit.sigma2,
        fit.residual_m_s2, fit.h5, 1.0,
    )  # fmt: skip


def node_phasor(
    s: NodeStream, gamma: float, taper: bool, gate: bool
) -> tuple[Phasor, Window, np.ndarray, list[str], NodeFit | None]:
    """One node's 1x phasor over its steady, settled window (in chunks).

    Returns the phasor, the window, the block sums over the window (for the
    block check), the gate's notes, and what a live update extends (None when
    tapered: a taper's weights change with the window's length).
    """
    run = _NodeRun(s, gamma)
    pos, rev = run.pos, run.rev
    a, b, notes = _steady(pos, rev, gate)
    n_full = (b - a) // BLOCK_REVS
    edges = pos[a + BLOCK_REVS * np.arange(n_full + 1)]
    starts = run.find(edges)  # the first sample of the n_full blocks and of the tail
    end = int(run.find(pos[b : b + 1], "right")[0])
    per_rev = np.diff(pos[a : b + 1]) / np.maximum(np.diff(rev[a : b + 1]), 1)
    period = median(per_rev)  # samples a revolution
    w0 = 2 * math.pi / period  # a fixed speed for the base columns
    blocks, chunks, kept = _first_pass(run, starts, end, n_full, w0)
    first = settled_block(blocks) if gate else 0
    if first > 0:
        notes.append(said("supports settled after {n} revolutions", n=first * BLOCK_REVS))
    e0 = a + BLOCK_REVS * first
    window = Window(
        start=float(pos[e0]),
        end=float(pos[b]),
        revolutions=int(rev[b] - rev[e0]),
        settled_from=float(pos[e0]),
        edge_jitter_rad=w0 * edge_jitter(pos[e0 : b + 1], rev[e0 : b + 1]),
    )
    sums = _window_sums(run, chunks, starts, end, first, w0)
    i0 = int(starts[first])
    if sums.n < 8:
        raise MeasurementError(f"only {sums.n} samples in the steady window: measure longer")
    w_ref = sums.w_sum / sums.n
    _check_aliasing(w_ref, float(s.rate_hz or 0.0))
    sloped = (sums.w_max - sums.w_min) / w_ref > SPEED_SPAN_SLOPE
    T = model_transform(w0, w_ref, sloped)
    th0, th1 = run.angle(i0), run.angle(end - 1)
    span = th1 - th0
    tapered = taper and span > 0
    if tapered:
        XtWX, XtWa, XtW2X = _tapered_normal_equations(run, i0, end, w0, T, th0, span)
    else:
        XtWX, XtWa = T.T @ sums.G @ T, T.T @ sums.Ba
    coef = np.linalg.solve(XtWX, XtWa)
    bands, rr, wt2, wt1, h5 = _second_pass(run, kept, i0, end, w0, T, coef, span, tapered)
    del kept
    sigma2 = float(np.mean(np.abs(bands) ** 2)) / wt2
    bread = np.linalg.inv(XtWX)
    cov_coef = sigma2 * (bread @ XtW2X @ bread if tapered else bread)
    rate = float(s.rate_hz or 0.0)
    residual = math.sqrt(max(rr, 0.0) / sums.n)
    ph = _phasor(
        coef, cov_coef, sloped, w_ref, rate, sums.n, span, sigma2, residual, 2 * h5 / wt1,
        wt2 * sums.n / wt1**2 if tapered else 1.0,
    )  # fmt: skip
    fit = None
    if not tapered:
        scale = float(s.scale_m_s2[-1]) if s.scale_m_s2 is not None else 0.0
        fit = NodeFit(
            gamma, w0, sums.copy(), int(rev[b]), period, window, span,
            sigma2, 2 * h5 / wt1, residual, rate, scale,
        )  # fmt: skip
    return ph, window, blocks[first:], notes, fit
