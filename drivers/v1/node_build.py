"""One node's stream built from the decoded frames, step by step (the rules of
:mod:`stand.drivers.streams`): STATUS (rate, scale, in time), restarts and lost or
duplicate frames (``seq`` unwrapped), the samples' index, the scale runs, the reference
edges (their ``seq`` unwrapped against the nearest SAMPLES frame, inconsistent ones
dropped), the STATUS flags as warnings.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.core import Diagnostic
from stand.drivers.frame_index import FrameIndex
from stand.drivers.streams import SUPPORT_NODES, NodeStream
from stand.drivers.v1.protocol import (
    FRAC_SCALE,
    INVALID_COUNT,
    SAMPLES_PER_FRAME,
    STATUS_FLAG_NAMES,
    WRAP,
    Decoded,
)
from stand.errors import NoStatusError
from stand.i18n.words import said

STATUS_WITHIN_S = 1.5
"""A node's first STATUS must come within this time of its first frame [s]."""
SILENCE_S = 0.5
"""A STATUS after this much silence from its node marks a restart [s] ..."""
DROPOUT_TOLERANCE = 0.1
"""... unless ``seq`` advanced as the host time that passed predicts (within 10 %
and 20 frames): that is a bus dropout (lost frames), not a restart."""

_WRAP = WRAP
assert _WRAP & (_WRAP - 1) == 0  # a power of two: x & (_WRAP - 1) is x % _WRAP


EDGE_SLACK = 0.25
"""An edge is where its neighbours put it to within a quarter revolution (speed from the
median of the nearby revolutions), or its position or counter is corrupt."""


def _local_period(dp: NDArray[np.float64], dr: NDArray[np.int64], ok: NDArray[np.bool_]) -> Any:
    """Samples per revolution around each interval: the median of up to 9 nearby good ones."""
    per = np.where(ok, dp / np.maximum(dr, 1), np.nan)
    half = 4
    padded = np.concatenate((np.full(half, np.nan), per, np.full(half, np.nan)))
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1)
    counts = np.sum(np.isfinite(windows), axis=1)
    T = np.full(len(per), np.nan)
    has = np.flatnonzero(counts > 0)
    if len(has):  # np.nanmedian's answer (NaN sorts last), without its import of numpy.ma
        ranked = np.sort(windows[has], axis=1)
        k = counts[has]
        rows = np.arange(len(has))
        T[has] = 0.5 * (ranked[rows, (k - 1) // 2] + ranked[rows, k // 2])
    return T


def consistent_edges(
    pos: NDArray[np.float64], seg: NDArray[np.int32], rev: NDArray[np.int64]
) -> NDArray[np.bool_]:
    """Which reference edges agree with their neighbours (sorted by segment and position).

    An interval between two edges is *wrong* when its length, in revolutions
    of the local speed, differs from what the counters say by more than
    :data:`EDGE_SLACK`.  An edge is dropped when both its intervals are wrong
    and the interval that skips it is right (a corrupt counter or position
    moves one edge; it spoils both its intervals and nothing else), or, at the
    end of a segment, when its one interval is wrong and the next is right.
    """
    keep = np.ones(len(pos), dtype=bool)
    for _ in range(3):  # rounds: two bad edges side by side may need a second look
        idx = np.flatnonzero(keep)
        p, s, r = pos[idx], seg[idx], rev[idx]
        if len(p) < 4:
            break
        same = s[1:] == s[:-1]
        dp = np.diff(p)
        dr = np.diff(r) % _WRAP
        T = _local_period(dp, dr, same & (dr >= 1) & (dr <= 8) & (dp > 0))
        with np.errstate(all="ignore"):
            wrong = same & ~(np.abs(dp / T - dr) <= EDGE_SLACK)
            skip_dr = (r[2:] - r[:-2]) % _WRAP
            skip_ok = np.abs((p[2:] - p[:-2]) / T[:-1] - skip_dr) <= EDGE_SLACK
        bad = np.zeros(len(p), dtype=bool)
        bad[1:-1] = wrong[:-1] & wrong[1:] & skip_ok & same[:-1] & same[1:]
        first = np.concatenate(([True], ~same))[:-1]  # edge k starts its segment
        bad[:-2] |= first[:-1] & wrong[:-1] & ~wrong[1:] & same[1:]
        last = np.concatenate((~same, [True]))  # edge k ends its segment
        bad[2:] |= last[2:] & wrong[1:] & ~wrong[:-1] & same[:-1]
        if not bad.any():
            break
        keep[idx[bad]] = False
    return keep


def _most_common(values: NDArray[np.float64]) -> float | None:
    """The value most STATUS frames say (a corrupt first STATUS is outvoted); None if none."""
    if not len(values):
        return None
    uniq, counts = np.unique(values, return_counts=True)
    return float(uniq[np.argmax(counts)])


class _Triple:
    """``frame_start`` when every sample is valid: frame ``j`` starts at ``3 j``."""

    def __getitem__(self, j: Any) -> Any:
        return SAMPLES_PER_FRAME * np.asarray(j, dtype=np.int64)


def _unwrap_samples(
    seq: NDArray[np.int64], restart_at: NDArray[np.bool_]
) -> tuple[NDArray[np.bool_], NDArray[np.int64], NDArray[np.int32], int]:
    """Keep-mask (duplicates dropped), unwrapped frame numbers, segments, lost frames.

    In place where it can: a node of a one-hour run has millions of frames.
    """
    n = len(seq)
    d = np.empty(n, dtype=np.int64)
    d[0] = 0
    np.subtract(seq[1:], seq[:-1], out=d[1:])
    d &= _WRAP - 1  # the step modulo 2^16, as % gives it, without a division per frame
    keep = np.ones(n, dtype=bool)
    keep[1:] = (d[1:] != 0) | restart_at[1:]  # a repeated seq is a duplicate, unless a restart
    all_kept = bool(keep.all())
    if not all_kept:
        seq, d, restart_at = seq[keep], d[keep], restart_at[keep]
    start = restart_at | (d >= _WRAP // 2)
    start[0] = True
    d[start] = 0  # now the step from the frame before (0 at a segment's start)
    lost = int(np.sum(d[d > 0] - 1))
    seg = np.cumsum(start, dtype=np.int32)
    seg -= 1
    first = np.flatnonzero(start)
    del start
    F = np.cumsum(d)  # the running frame count, then moved to each segment's first seq
    del d
    offset = seq[first] - F[first]
    F += offset[seg] if len(first) > 1 else offset[0]
    return keep, F, seg, lost


def _node_warnings(
    node: int, st_t: NDArray[np.float64], flags: NDArray[np.uint8], t0: float
) -> tuple[list[Diagnostic], tuple[str, ...]]:
    out: list[Diagnostic] = []
    seen: list[str] = []
    for bit, name in STATUS_FLAG_NAMES.items():
        on = ((flags >> bit) & 1).astype(bool)
        if not on.any():
            continue
        seen.append(name)
        starts = np.flatnonzero(on & ~np.concatenate(([False], on[:-1])))
        ends = np.flatnonzero(on & ~np.concatenate((on[1:], [False])))
        for a, b in zip(starts.tolist(), ends.tolist(), strict=True):
            t, until = f"{st_t[a] - t0:.2f}", f"{st_t[b] - t0:.2f}"
            when = (said("at {t} s (in {n} STATUS frames, until {until} s)", t=t, n=b - a + 1,
                         until=until) if b > a else said("at {t} s", t=t))  # fmt: skip
            out.append(Diagnostic(f"status_{name}", said(
                "node {node}: STATUS reports {flag} {when}", node=node,
                flag=name.replace("_", " "), when=when), float(b - a + 1),
                float(st_t[a] - t0)))  # fmt: skip
    return out, tuple(seen)


def _status(
    node: int,
    dec: Decoded,
    st_sel: NDArray[np.bool_],
    st_t: NDArray[np.float64],
    frames: tuple[int, int],
    first_t: float,
    t0: float,
    strict_status: bool,
) -> tuple[NDArray[np.float64], NDArray[np.float64], list[Diagnostic]]:
    """The node's STATUS: its rate and scale per STATUS frame, and whether one came in time
    (a support node without one is refused when ``strict_status``) and stayed the same."""
    warn: list[Diagnostic] = []
    rate = dec.status.rate[st_sel].astype(np.float64)
    scale = dec.status.scale[st_sel].astype(np.float64)
    if len(st_t) == 0 or st_t[0] - first_t > STATUS_WITHIN_S:
        came = "none came" if len(st_t) == 0 else f"the first came after {st_t[0] - first_t:.2f} s"
        what = (
            f"node {node}: no STATUS within {STATUS_WITHIN_S} s of its first frame "
            f"(frame {frames[0]}, {came}): its samples cannot be scaled"
        )
        if strict_status and node in SUPPORT_NODES:
            raise NoStatusError(what, node=node, frame=frames[0])
        if node not in SUPPORT_NODES:
            what += f" (not a support node: {frames[1]} frames left aside)"
        warn.append(Diagnostic("no_status", what, None, float(first_t - t0)))
    for name, values, unit in (("rate", rate, "Hz"), ("scale", scale, "µm/s² per count")):
        if len(values) and bool(np.any(values != values[0])):
            seen = sorted(set(values.tolist()))
            message = f"node {node}: STATUS {name} changed during the run: {seen} {unit}"
            warn.append(Diagnostic(f"{name}_changed", message, float(values[-1])))
    return rate, scale, warn


def _restarts(
    seq: NDArray[np.int64],
    s_frame: NDArray[Any],
    st_frame: NDArray[Any],
    t_s: NDArray[np.float64],
    m_frame: NDArray[Any],
    rate: NDArray[np.float64],
) -> NDArray[np.bool_]:
    """Where the node restarted: a STATUS after silence, unless seq runs on across it as the
    time passed predicts (a bus dropout is silence too)."""
    st_t = t_s[st_frame]
    prev = np.full(len(st_frame), -1, np.int64)  # the node's frame before each STATUS
    for frames in (s_frame, st_frame, m_frame):  # each sorted: no sort of the node's frames
        j = np.searchsorted(frames, st_frame)
        has = j > 0
        prev[has] = np.maximum(prev[has], frames[j[has] - 1])
    gap_before = np.where(prev >= 0, st_t - t_s[np.maximum(prev, 0)], 0.0)
    after_silence = gap_before > SILENCE_S
    restart_at = np.zeros(len(seq), dtype=bool)
    hit = np.searchsorted(s_frame, st_frame[after_silence])
    ok = (hit > 0) & (hit < len(seq))  # a SAMPLES frame on either side of the silence
    hit, st_rate = hit[ok], rate[after_silence][ok]
    elapsed = t_s[s_frame[hit]] - t_s[s_frame[hit - 1]]
    expected = elapsed * st_rate / SAMPLES_PER_FRAME
    advance = (seq[hit] - seq[hit - 1]) % _WRAP
    continues = np.abs(advance - expected) <= DROPOUT_TOLERANCE * expected + 20
    restart_at[hit[~continues]] = True
    return restart_at


def _frame_warnings(node: int, n_seg: int, lost: int, kept: int) -> list[Diagnostic]:
    """Restarts and lost SAMPLES frames, in words."""
    warn = []
    if n_seg > 1:
        warn.append(Diagnostic("node_restart", said(
            "node {node}: restarted {n} time(s); each part is timed on its own", node=node,
            n=n_seg - 1), float(n_seg - 1)))  # fmt: skip
    if lost:
        warn.append(Diagnostic("lost_frames", said(
            "node {node}: {n} SAMPLES frames lost ({pct} %): their samples are missing, the "
            "others keep their index", node=node, n=lost,
            pct=f"{100 * lost / (lost + kept):.2g}"), float(lost)))  # fmt: skip
    return warn


def _scale_runs(
    st_frame: NDArray[Any], s_frame_k: NDArray[Any], scale: NDArray[np.float64], frame_start: Any
) -> tuple[Any, Any]:
    """Each STATUS scales the frames from the first one after it (the first STATUS also
    those before it): runs of one scale [m/s^2 per count], found per STATUS, not per frame;
    ``(first valid sample of each run, its scale)``, or ``(None, None)`` without STATUS."""
    if not len(st_frame):
        return None, None
    begins = np.searchsorted(s_frame_k, st_frame)
    begins[0] = 0
    runs = np.concatenate((begins[1:] > begins[:-1], [True]))  # the STATUS that got frames
    runs[0] = True
    begins, values = begins[runs], scale[runs] * 1e-6
    new = np.concatenate(([True], values[1:] != values[:-1]))  # merge equal neighbours
    return frame_start[begins[new]].astype(np.int64), values[new]


def _marks(
    node: int,
    dec: Decoded,
    m_sel: NDArray[np.bool_],
    m_frame: NDArray[Any],
    s_frame_k: NDArray[Any],
    seq_k: NDArray[np.int64],
    F: NDArray[np.int64],
    seg: NDArray[np.int32],
) -> tuple[NDArray[np.float64], NDArray[np.int32], NDArray[np.int64], int, list[Diagnostic]]:
    """The node's reference edges: each MARK's seq unwrapped against the nearest SAMPLES
    frame of the node (by arrival), duplicates and inconsistent edges dropped, the
    revolution counter unwrapped per segment; ``(position, segment, revolution, lost
    marks, warnings)``."""
    if not (len(m_frame) and len(s_frame_k)):
        return np.zeros(0), np.zeros(0, np.int32), np.zeros(0, np.int64), 0, []
    warn = []
    j = np.searchsorted(s_frame_k, m_frame)
    prev = np.maximum(j - 1, 0)
    nxt = np.minimum(j, len(s_frame_k) - 1)
    mseq = dec.marks.seq[m_sel].astype(np.int64)

    def signed(ref: NDArray[np.int64]) -> NDArray[np.int64]:
        d: NDArray[np.int64] = (mseq - seq_k[ref] + _WRAP // 2) % _WRAP - _WRAP // 2
        return d

    dp, dn = signed(prev), signed(nxt)
    use_next = np.abs(dn) < np.abs(dp)
    ref = np.where(use_next, nxt, prev)
    Fm = F[ref] + np.where(use_next, dn, dp)
    pos = SAMPLES_PER_FRAME * Fm + dec.marks.slot[m_sel] + dec.marks.frac[m_sel] / FRAC_SCALE
    mseg = seg[ref]
    rev = dec.marks.rev[m_sel].astype(np.int64)
    order = np.lexsort((pos, mseg))
    pos, mseg, rev = pos[order], mseg[order], rev[order]
    uniq = np.ones(len(pos), dtype=bool)
    uniq[1:] = (pos[1:] != pos[:-1]) | (mseg[1:] != mseg[:-1])
    pos, mseg, rev = pos[uniq], mseg[uniq], rev[uniq]
    good = consistent_edges(pos, mseg, rev)
    if not good.all():
        dropped = int(np.count_nonzero(~good))
        warn.append(Diagnostic("edges_dropped", said(
            "node {node}: {n} reference edge(s) dropped: their position or revolution "
            "counter disagrees with their neighbours (a corrupt MARK frame)", node=node,
            n=dropped), float(dropped)))  # fmt: skip
        pos, mseg, rev = pos[good], mseg[good], rev[good]
    new_seg = np.ones(len(pos), dtype=bool)
    new_seg[1:] = mseg[1:] != mseg[:-1]
    dr = np.zeros(len(rev), np.int64)
    dr[1:] = (rev[1:] - rev[:-1]) % _WRAP
    dr[new_seg] = 0
    lost_marks = int(np.sum(dr[dr > 1] - 1))
    first = np.flatnonzero(new_seg)
    cum = np.cumsum(dr)
    segi = np.cumsum(new_seg) - 1
    m_rev = rev[first][segi] + cum - cum[first][segi]
    return pos, mseg.astype(np.int32), m_rev, lost_marks, warn


def _samples(F: NDArray[np.int64], counts: NDArray[Any], one_segment: bool) -> tuple[Any, ...]:
    """Each kept frame's three samples by their index in the node's sample clock: the
    index, the counts, which are valid, and where each frame's valid samples begin in the
    valid-sample arrays (:class:`_Triple` when all are valid: the common case, no copies;
    then, in one segment, the index is the frames' numbers alone, a :class:`FrameIndex`)."""
    flat = counts.reshape(-1)
    valid = flat != INVALID_COUNT
    if bool(valid.all()) and one_segment:
        return FrameIndex(F, SAMPLES_PER_FRAME), flat, valid, _Triple()
    index = np.empty(SAMPLES_PER_FRAME * len(F), np.int64)
    triples = index.reshape(-1, SAMPLES_PER_FRAME)
    np.multiply(F, SAMPLES_PER_FRAME, out=triples[:, 0])  # no temporary of the run's length
    for k in range(1, SAMPLES_PER_FRAME):
        np.add(triples[:, 0], k, out=triples[:, k])
    if bool(valid.all()):
        return index, flat, valid, _Triple()
    starts = np.concatenate(([0], np.cumsum(valid.reshape(-1, SAMPLES_PER_FRAME).sum(1))))
    return index, flat, valid, starts


def rebuild_node(
    node: int, dec: Decoded, t_s: NDArray[np.float64], t0: float, strict_status: bool
) -> tuple[NodeStream, list[Diagnostic]]:
    """One node's stream from the decoded frames: STATUS, restarts and lost frames, the
    samples' index, the scale runs, the reference edges (each a step of its own above)."""
    s_sel = dec.samples.node == node
    st_sel = dec.status.node == node
    m_sel = dec.marks.node == node
    s_all = bool(s_sel.all())  # records gathered for this node alone: views, not copies
    s_frame = dec.samples.frame if s_all else dec.samples.frame[s_sel]
    st_frame = dec.status.frame[st_sel]
    m_frame = dec.marks.frame[m_sel]
    # three sorted runs: their ends give the node's first and last frames
    runs = [f for f in (s_frame, st_frame, m_frame) if len(f)]
    first, last = min(int(f[0]) for f in runs), max(int(f[-1]) for f in runs)
    first_t, last_t = float(t_s[first]), float(t_s[last])
    st_t = t_s[st_frame]
    n_frames = len(s_frame) + len(st_frame) + len(m_frame)
    rate, scale, warn = _status(
        node, dec, st_sel, st_t, (first, n_frames), first_t, t0, strict_status
    )

    seq = (dec.samples.seq if s_all else dec.samples.seq[s_sel]).astype(np.int64)
    restart_at = _restarts(seq, s_frame, st_frame, t_s, m_frame, rate)
    keep, F, seg, lost = (
        _unwrap_samples(seq, restart_at)
        if len(seq)
        else (np.zeros(0, bool), np.zeros(0, np.int64), np.zeros(0, np.int32), 0)
    )
    kept_all = bool(keep.all())  # no duplicates: views, not copies
    s_frame_k = s_frame if kept_all else s_frame[keep]
    seq_k = seq if kept_all else seq[keep]
    counts = dec.samples.counts
    counts = counts if s_all else counts[s_sel]
    counts = counts if kept_all else counts[keep]
    duplicates = int(len(seq) - len(seq_k))
    del seq, s_frame, restart_at, keep
    n_seg = int(seg[-1]) + 1 if len(seg) else 0
    warn += _frame_warnings(node, n_seg, lost, len(seq_k))

    index, flat, valid, frame_start = _samples(F, counts, n_seg == 1)
    all_valid = isinstance(frame_start, _Triple)
    seg_first = np.flatnonzero(seg[1:] != seg[:-1]) + 1 if len(seg) else np.zeros(0, np.int64)
    if len(seg):
        seg_first = np.concatenate(([0], seg_first))
    scale_start, scale_m_s2 = _scale_runs(st_frame, s_frame_k, scale, frame_start)
    m_pos, m_seg, m_rev, lost_marks, mark_warn = _marks(
        node, dec, m_sel, m_frame, s_frame_k, seq_k, F, seg
    )
    warn += mark_warn
    flag_warn, flag_names = _node_warnings(node, st_t, dec.status.flags[st_sel], t0)
    warn.extend(flag_warn)
    stream = NodeStream(
        node=node,
        rate_hz=_most_common(rate),
        scale_um_s2=float(scale[-1]) if len(scale) else None,
        index=index if all_valid else index[valid],
        counts=flat if all_valid else flat[valid],
        segment_start=frame_start[seg_first].astype(np.int64),
        scale_start=scale_start,
        scale_m_s2=scale_m_s2,
        mark_position=m_pos,
        mark_segment=m_seg,
        mark_rev=m_rev,
        frames=len(seq_k),
        samples=len(flat),
        invalid_samples=int(np.count_nonzero(~valid)),
        lost_frames=lost,
        duplicate_frames=duplicates,
        status_frames=len(st_frame),
        lost_marks=lost_marks,
        segments=n_seg,
        flags=flag_names,
        first_t_s=first_t,
        last_t_s=last_t,
    )
    return stream, warn
