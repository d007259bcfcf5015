"""The gate of one node's run: which part of it is measured, and whether to trust it.

Revolutions at steady speed (within :data:`SPEED_TOLERANCE` of the median),
the first block of :data:`BLOCK_REVS` revolutions from which the supports
have settled (:data:`SETTLED`), the scatter of the blocks' 1x about the
fit, a sensor at its limit (:func:`check_saturation`), the window's
revolutions (:data:`MIN_REVS`).  Used by the passes of the 1x fit
(:mod:`stand.measuring.passes`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from stand.core.dsp import median
from stand.core.fitsums import block_fits
from stand.drivers.streams import LATE_FLAG, LATE_SHARE, OFF_BEAT_FLAG, NodeStream
from stand.errors import MeasurementError, SensorFaultError
from stand.i18n.words import said

SPEED_TOLERANCE = 0.03
"""A revolution is at steady speed within 3 % of the steady part's median."""
BLOCK_REVS = 8
"""Revolutions per block when checking that the supports have settled."""
SETTLED = 0.02
"""A block agrees with the settled response within 2 % (or 4 standard errors).  A speed
ripple moves the 1x amplitude quasi-steadily by about its own size; a run-up's transient
decays through 2 % within a few damping times, and what is left averages out."""
SCATTER_FLOOR = 1e-3
"""Block scatter under 0.1 % of the 1x reading is never flagged."""
MIN_REVS = 30
"""A steady, settled window shorter than this many revolutions draws a warning."""


@dataclass(frozen=True)
class Window:
    """The gated part of one node's run, in its own sample positions."""

    start: float
    end: float
    revolutions: int
    settled_from: float
    edge_jitter_rad: float = 0.0
    """Rms shaft-angle error of one edge from its timing jitter [rad]
    (:func:`~stand.core.dsp.edge_jitter` times the speed)."""
    drift: tuple[float, float] = (0.0, 0.0)
    """How much the blocks' 1x changes across the window along a straight line through them,
    and that change's standard error, both relative to the 1x (:func:`block_drift`)."""


def node_segment(s: NodeStream) -> tuple[int, int, np.ndarray, np.ndarray]:
    """The node's longest clock segment: its samples ``lo:hi``, edge positions and revs."""
    if s.scale_m_s2 is None:
        raise MeasurementError("no STATUS, its samples cannot be scaled")
    if len(s.index) == 0 and s.samples:
        raise SensorFaultError(
            f"all {s.samples} samples are invalid (count -32768: sensor fault or overrange)"
        )
    if len(s.index) == 0:
        raise MeasurementError(
            f"no samples, only {s.status_frames} STATUS and {s.marks} MARK frames"
        )
    if len(s.mark_segment) == 0:
        raise MeasurementError(
            "no reference edges: is the reference sensor wired and the mark passing it?"
        )
    seg = int(np.bincount(s.mark_segment).argmax())
    m = s.mark_segment == seg
    lo, hi = s.segment_bounds(seg)
    assert s.scale_m_s2 is not None
    if not np.any(s.scale_m_s2):
        raise SensorFaultError("its STATUS scale is 0: the samples mean nothing (sensor fault?)")
    if not s.rate_hz or s.rate_hz <= 0:
        raise SensorFaultError(f"its STATUS says a sample rate of {s.rate_hz} Hz")
    revs = s.mark_rev[m]
    if len(revs) >= 3 and np.count_nonzero(np.diff(np.sort(revs))) < 2:  # < 3 values
        raise SensorFaultError(
            f"its reference edges' revolution counter does not count: {len(revs)} edges "
            f"say only {sorted(set(revs.tolist()))[:3]}"
        )
    counts = s.counts[lo:hi]
    if len(counts) and counts.min() == counts.max():
        raise SensorFaultError(
            f"the sensor reads a constant {int(counts[0])} counts in all {len(counts)} samples: "
            "dead, disconnected or stuck"
        )
    return lo, hi, s.mark_position[m], s.mark_rev[m]


FULL_SCALE_COUNT = 32767
"""The largest count a node can send (-32768 marks an invalid sample)."""
SATURATION_SHARE = 2e-3
"""A sensor is saturated when its extreme count recurs in more than 0.2 % of the samples
(and at least 8): a sine's peak is met by a handful of samples, a clipped one by many."""


def check_timing(s: NodeStream) -> None:
    """Refuse a node whose samples' times are not known: a CANopen module whose TPDOs came
    in backlogs for more than :data:`stand.drivers.streams.LATE_SHARE` of them
    (flag ``late_backlog``): placed by guess they would lag the 1x, a shift no interval
    holds; or whose SYNCs came off the beat for as many (flag ``sync_off_beat``): the
    gaps and bursts of a host that lost the pace hide the mark's edges."""
    if OFF_BEAT_FLAG in s.flags:
        total = s.samples + s.off_beat_samples
        raise MeasurementError(
            f"{s.off_beat_samples} of its samples were taken on a SYNC off the clock's beat "
            f"({100 * s.off_beat_samples / max(total, 1):.0f} %, more than "
            f"{100 * LATE_SHARE:.0f} %): the host did not keep the SYNC's pace (a loaded "
            "machine; a SYNC sent by a program's thread), so too few whole revolutions are "
            "left to count the mark by; record again with the interface's or the kernel's "
            "cyclic transmit (SocketCAN's broadcast manager), or on a lighter machine"
        )
    if LATE_FLAG not in s.flags:
        return
    total = s.samples + s.duplicate_frames
    raise MeasurementError(
        f"{s.duplicate_frames} of its {total} samples came late, in backlogs "
        f"({100 * s.duplicate_frames / max(total, 1):.0f} %, more than "
        f"{100 * LATE_SHARE:.0f} %): which SYNC each answered is not known for so many, "
        "so no sample's time can be trusted; record again with a host that keeps the "
        "SYNC's pace"
    )


def check_saturation(s: NodeStream) -> None:
    """Refuse a node whose sensor clipped: a clipped 1x reads low, and no interval says so.

    A limit counts when STATUS reported ``overrange`` or it is the count's
    full scale, and its extreme value recurs in more than
    :data:`SATURATION_SHARE` of the samples.  (Leaving the clipped samples
    out was tried: the samples kept near the limit are those whose noise
    happened to be negative, and the 1x still read 0.6 to 1.6 % low, two to
    six times its interval, on the demo with twice its unbalance.)
    """
    c = s.counts
    if len(c) < 16:
        return
    hi, lo = int(c.max()), int(c.min())
    allowed = "overrange" in s.flags
    limit = max(8.0, SATURATION_SHARE * len(c))
    for v in (hi, lo):
        n = int(np.sum(c == v))
        if v != 0 and (allowed or abs(v) >= FULL_SCALE_COUNT) and n > limit:
            raise SensorFaultError(
                f"the sensor saturates: {n} samples ({100 * n / len(c):.1f} %) sit at its limit "
                f"of {v:+d} counts, so the 1x would read low; measure at a lower speed or with "
                "a sensor of larger range"
            )


def steady_revolutions(pos: np.ndarray, rev: np.ndarray) -> tuple[int, int, list[str]]:
    """The longest run of steady-speed revolutions: its edges ``(a, b)``, and notes.

    Each revolution within :data:`SPEED_TOLERANCE` of the median speed.
    """
    notes: list[str] = []
    if len(pos) < 3:
        raise MeasurementError(f"only {len(pos)} reference edges: need at least 3")
    period = np.diff(pos) / np.maximum(np.diff(rev), 1)  # samples per revolution
    speed = 1.0 / period
    steady = np.abs(speed / median(speed) - 1) < SPEED_TOLERANCE
    best: tuple[int, int] = (0, 0)
    start: int | None = None
    for k, ok in enumerate([*steady.tolist(), False]):  # revolution k: edges k .. k+1
        if ok and start is None:
            start = k
        elif not ok and start is not None:
            if k - start > best[1] - best[0]:
                best = (start, k)
            start = None
    a, b = best  # revolutions a .. b-1, edges a .. b
    if b - a < 2:
        raise MeasurementError("the speed is never steady for two revolutions in a row")
    if a > 0 or b < len(steady):
        notes.append(said("speed steady over revolutions {a}..{b} of {n}", a=a, b=b, n=len(steady)))
    return a, b, notes


def settled_block(sums: np.ndarray) -> int:
    """The first block from which every block's 1x agrees with the last half's.

    Within 4 of its standard errors, or :data:`SETTLED`, or 3 times the
    scatter of the last half's blocks (a beat with a neighbour near 1x is not
    a transient).  ``sums``: :func:`~stand.core.fitsums.block_sums` rows.
    """
    n_blocks = len(sums)
    if n_blocks < 4:
        return 0
    A_blocks, n, var = block_fits(sums)
    std = np.sqrt(2 * var / np.maximum(n, 1))  # per component of each block's 1x
    tail = slice(n_blocks // 2, n_blocks)
    if np.sum(n[tail]) == 0:  # no samples between the edges: the window says so
        return 0
    A_tail = np.sum(A_blocks[tail] * n[tail]) / np.sum(n[tail])
    spread = float(np.sqrt(np.mean(np.abs(A_blocks[tail] - A_tail) ** 2)))
    ok = np.abs(A_blocks - A_tail) <= np.maximum.reduce(
        [4 * std, np.full(n_blocks, SETTLED * abs(A_tail)), np.full(n_blocks, 3 * spread)]
    )
    first_good = n_blocks
    for k in range(n_blocks - 1, -1, -1):
        if not ok[k]:
            break
        first_good = k
    return first_good


def block_drift(sums: np.ndarray) -> tuple[float, float]:
    """The change of the blocks' 1x across them along a least-squares line (weighted by
    their samples), and its standard error from the blocks' scatter about the line, both
    relative to the mean 1x; ``(0, 0)`` with fewer than 4 blocks."""
    n_blocks = len(sums)
    if n_blocks < 4:
        return 0.0, 0.0
    A, n, _ = block_fits(sums)
    k = np.arange(n_blocks, dtype=float)
    wts = n / np.sum(n)
    k0 = float(np.sum(wts * k))
    mean = complex(np.sum(wts * A))
    sxx = float(np.sum(wts * (k - k0) ** 2))
    slope = complex(np.sum(wts * (k - k0) * (A - mean))) / sxx
    resid = A - mean - slope * (k - k0)
    var = float(np.sum(wts * np.abs(resid) ** 2)) * n_blocks / (n_blocks - 2)
    span, scale = n_blocks - 1, max(abs(mean), 1e-300)
    se = math.sqrt(var / (sxx * n_blocks))
    return abs(slope) * span / scale, se * span / scale


def block_scatter(sums: np.ndarray, noise: float) -> float:
    """How much blocks of whole revolutions scatter, against what the noise explains.

    Returns the scatter of the blocks' 1x around their mean over its
    expectation from ``noise`` (about 1 when only noise moves them; 0 with
    fewer than 3 blocks, which cannot tell).
    """
    n_blocks = len(sums)
    if n_blocks < 3 or noise <= 0:
        return 0.0
    A, n, _ = block_fits(sums)
    mean = np.sum(A * n) / np.sum(n)
    dev2 = np.abs(A - mean) ** 2
    if np.sqrt(np.mean(dev2)) < SCATTER_FLOOR * abs(mean):
        return 0.0  # immaterial, however many standard errors it is
    expected = 4 * noise**2 / np.maximum(n, 1)  # E|A_b - A|^2 from noise: 2 sigma^2/n per part
    return float(np.sum(dev2 / expected) / (n_blocks - 1))
