"""Live updates between full passes: the samples that came since, added to the sums.

A full pass (:func:`stand.measuring.measure.measure`) gates the run, fits it and
estimates the noise; it costs time in proportion to the run.  Between two
full passes a live update need not: the fit's normal equations are sums over
samples (:mod:`stand.core.fitsums`), so the revolutions that came since the
last update are added to them and the 9 x 9 system solved again.  An update
reads only the frames of the last few revolutions
(:meth:`stand.drivers.v1.build.StreamBuilder.tail`), so it costs the same at
10 s and at 10 min.

What carries over from the last full pass: the gate's start of the window,
the noise per sample (so the interval still narrows as ``1 / sqrt(n)``), the
blocks' scatter ratio, the 5x, the residual's rms, and the settling judged
at the window's start; a run's final answer is always a full pass.  What an
update refuses to extend, leaving it to a full pass (:func:`extend` returns
None): a node restart, a lost edge at the join, a revolution off the
window's speed by more than :data:`stand.measuring.gate.SPEED_TOLERANCE`, a STATUS
with a new scale or any flag, a new sample at the sensor's full scale (the
full pass judges whether the sensor saturates), a tapered fit.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from stand.core import StandParameters
from stand.core.beam import BeamRotor
from stand.core.dsp import angle_at, angle_knots
from stand.core.fitsums import base_rows
from stand.core.influence import InfluenceMap
from stand.core.trig import cos_sin
from stand.drivers.streams import SUPPORT_NODES, NodeStream, RunStreams
from stand.drivers.v1.protocol import WRAP
from stand.measuring.gate import FULL_SCALE_COUNT, SPEED_TOLERANCE
from stand.measuring.measure import CLOCK_TOLERANCE, Measurement, combine, judge_support
from stand.measuring.passes import NodeFit, sums_phasor


def _join(s: NodeStream, fit: NodeFit) -> int | None:
    """The tail's edge at the fit's last revolution, or None (not in the tail, or without
    the edge before it, whose slope the angle between them needs)."""
    rev = s.mark_rev % WRAP
    at = np.flatnonzero(rev == fit.last_rev % WRAP)
    if not len(at) or at[-1] < 1:
        return None
    return int(at[-1])


def _usable(s: NodeStream, fit: NodeFit) -> bool:
    """One clock segment, the scale and rate of the last full pass, no STATUS flag."""
    if len(s.segment_start) != 1 or (len(s.mark_segment) and s.mark_segment.max() > 0):
        return False
    if s.flags or (s.rate_hz is not None and s.rate_hz != fit.rate_hz):
        return False
    return s.scale_m_s2 is None or bool(np.all(s.scale_m_s2 == fit.scale_m_s2))


def extend(fit: NodeFit, s: NodeStream) -> NodeFit | None:
    """``fit`` with the revolutions of the tail ``s`` that it does not hold yet.

    The revolutions added end one edge before the tail's last (an edge's
    slope needs the edge after it).  Returns ``fit`` itself when no new
    revolution is complete, and None when the tail cannot be joined to it
    (see the module's list): a full pass is then due.
    """
    if not _usable(s, fit):
        return None
    e = _join(s, fit)
    if e is None:
        return None
    pos, rev = s.mark_position[e - 1 :], s.mark_rev[e - 1 :]
    last = len(pos) - 2  # the last edge whose slope has an edge on each side
    if last <= 1:
        return fit
    steps = np.diff(rev[: last + 1])
    period = np.diff(pos[: last + 1]) / np.maximum(steps, 1)
    if np.any(steps[1:] != 1) or np.any(np.abs(fit.period / period[1:] - 1) >= SPEED_TOLERANCE):
        return None  # a lost edge or an unsteady revolution: the gate must judge it
    lo, hi = np.searchsorted(s.index, np.floor(pos[[1, last]]).astype(np.int64), side="right")
    counts = s.counts[lo:hi]
    if len(counts) and max(int(counts.max()), -int(counts.min())) >= FULL_SCALE_COUNT:
        return None  # at the sensor's limit: whether it saturates is the full pass's to say
    knots = angle_knots(pos[: last + 2], rev[: last + 2])
    th, w = angle_at(knots, s.index[lo:hi].astype(np.float64))
    th += fit.gamma
    a = counts * np.float64(fit.scale_m_s2)
    sums = fit.sums.copy()
    c, sn = cos_sin(th)  # as the full pass computes them
    sums.add(base_rows(c, sn, w, fit.w0), a, w)
    revs = int(rev[last] - rev[1])
    # the window's start and end stay the full pass's: the tail's sample positions count
    # on a clock of their own
    return replace(
        fit,
        sums=sums,
        last_rev=int(rev[last]),
        window=replace(fit.window, revolutions=fit.window.revolutions + revs),
        span_rad=fit.span_rad + 2 * math.pi * revs,
    )


def remeasure(
    prev: Measurement,
    tails: RunStreams,
    p: StandParameters,
    *,
    sensor_gain: tuple[float, float] = (1.0, 1.0),
    sensor_delay_s: tuple[float, float] = (0.0, 0.0),
    clock_tolerance: float = CLOCK_TOLERANCE,
    influence: InfluenceMap | None = None,
    beam: BeamRotor | None = None,
    **_: Any,
) -> Measurement | None:
    """``prev`` (a full pass or an update) extended by the frames of ``tails``, judged and
    inverted as :func:`stand.measuring.measure.measure` does; None when a full pass is due.

    The options are :func:`~stand.measuring.measure.measure`'s (the reference angle is in the fits
    already); the gate's notes of the last full pass carry over.
    """
    if prev.fits is None:
        return None
    fits: list[NodeFit] = []
    for node, fit in zip(SUPPORT_NODES, prev.fits, strict=True):
        s = tails.nodes.get(node)
        new = None if s is None else extend(fit, s)
        if new is None:
            return None
        fits.append(new)
    supports, warnings = [], [w for w in prev.warnings if w.code == "gate"]
    for k, (node, fit) in enumerate(zip(SUPPORT_NODES, fits, strict=True)):
        ph, notes = judge_support(
            node, sums_phasor(fit), fit.window, fit.scatter, (sensor_gain[k], sensor_delay_s[k])
        )
        supports.append(ph)
        warnings.extend(notes)
    windows = [f.window for f in fits]
    rates = tuple(f.rate_hz for f in fits)
    m = combine(supports, windows, warnings, p, rates, clock_tolerance, influence, beam)
    return replace(m, fits=tuple(fits))
