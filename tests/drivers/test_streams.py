"""Per-node streams: seq unwrap, gaps, restarts, invalid samples, MARK matching, STATUS."""

from __future__ import annotations

import functools
import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from synth import sine_run

from stand.drivers.frames import Frames
from stand.drivers.v1.build import rebuild
from stand.drivers.v1.codec import decode
from stand.drivers.v1.nodes import merge, node_frames
from stand.drivers.v1.protocol import INVALID_COUNT, MARK_BASE, SAMPLES_BASE, STATUS_BASE
from stand.errors import NoStatusError


def _drop(frames: Frames, mask: np.ndarray) -> Frames:
    return frames.take(~mask)


def test_clean_run_gives_every_sample_edge_and_the_speed() -> None:
    r = rebuild(sine_run(seconds=8.0, rpm=900.0))
    assert sorted(r.nodes) == [1, 2]
    assert (r.unknown_frames, r.bad_frames, r.warnings) == (0, 0, ())
    for s in r.nodes.values():
        assert s.frames == 10666 and s.samples == 31998 and s.lost_frames == 0
        assert (s.rate_hz, s.scale_um_s2, s.flags, s.segments) == (4000.0, 100.0, (), 1)
        assert s.marks == 120 and s.lost_marks == 0
        assert np.array_equal(s.index, np.arange(31998))
        # the edges: 10.25 + k * 4000*60/900 samples, to the 1/65536-sample tick
        period = 4000 * 60 / 900
        assert np.max(np.abs(s.mark_position - (10.25 + period * np.arange(120)))) <= 0.5 / 65536
        assert s.rpm() == pytest.approx(900.0, rel=1e-9)  # edge rounding only
        assert s.accel_m_s2 is not None
        assert np.array_equal(s.accel_m_s2, s.counts * (100 * 1e-6))


def test_seq_wraps_without_loss_and_indices_run_on() -> None:
    r = rebuild(sine_run(seconds=2.0, first_seq=65000, first_rev=65500))
    s = r.nodes[1]
    assert s.lost_frames == 0 and s.segments == 1 and s.lost_marks == 0
    assert (np.diff(s.index) == 1).all() and np.asarray(s.index)[0] == 3 * 65000
    assert s.mark_rev[0] == 65500 and (np.diff(s.mark_rev) == 1).all()
    assert np.all(np.diff(s.mark_position) > 0)


def test_a_gap_keeps_later_samples_at_their_true_index() -> None:
    f = sine_run(seconds=2.0)
    full = rebuild(f).nodes[1]
    dec = decode(f)
    lost_frames = dec.samples.frame[(dec.samples.node == 1)][100:105]  # five frames in a row
    r = rebuild(f.take(np.setdiff1d(np.arange(len(f)), lost_frames)))
    s = r.nodes[1]
    assert s.lost_frames == 5 and s.frames == full.frames - 5
    index = np.asarray(full.index)
    keep = (index < 300) | (index >= 315)
    assert np.array_equal(s.index, np.asarray(full.index)[keep])
    assert np.array_equal(s.accel_m_s2, full.accel_m_s2[keep])
    assert np.array_equal(s.mark_position, full.mark_position)  # MARKs still name their frame
    assert any(w.code == "lost_frames" for w in r.warnings)


def test_invalid_samples_are_counted_not_values() -> None:
    counts = np.arange(30, dtype=np.int16)
    counts[[4, 5, 17]] = INVALID_COUNT
    f = node_frames(1, counts, rate_hz=1000, scale_um_s2=10)
    s = rebuild(f).nodes[1]
    assert s.invalid_samples == 3 and s.samples == 30
    assert np.asarray(s.index).tolist() == [i for i in range(30) if i not in (4, 5, 17)]
    assert s.accel_m_s2 is not None and not np.isin(s.accel_m_s2, INVALID_COUNT * 1e-5).any()


def test_restart_with_seq_back_starts_a_segment() -> None:
    a = node_frames(
        1, np.ones(3000), rate_hz=1000, scale_um_s2=10, first_seq=5000, edges=[10.0, 1010.0]
    )
    b = node_frames(
        1, np.ones(3000), rate_hz=1000, scale_um_s2=10, first_seq=0, t0_s=3.1, edges=[20.5, 1020.5]
    )
    s = rebuild(merge([a, b])).nodes[1]
    assert s.segments == 2 and s.lost_frames == 0
    assert np.asarray(s.index)[s.segment == 1][0] == 0
    assert s.mark_position[s.mark_segment == 1].tolist() == [20.5, 1020.5]
    assert s.rpm() == pytest.approx(60.0)  # 1000 samples per revolution at 1 kHz, per segment


def test_restart_detected_by_status_after_silence_even_if_seq_runs_forward() -> None:
    a = node_frames(1, np.ones(3000), rate_hz=1000, scale_um_s2=10, first_seq=100)
    b = node_frames(1, np.ones(3000), rate_hz=1000, scale_um_s2=10, first_seq=1200, t0_s=4.0)
    s = rebuild(merge([a, b])).nodes[1]
    assert s.segments == 2 and s.lost_frames == 0  # not 100 "lost" frames


def test_a_bus_dropout_is_lost_frames_not_a_restart() -> None:
    f = node_frames(1, np.ones(9000), rate_hz=1000, scale_um_s2=10, first_seq=65400)
    rel = f.t_s - f.t_s[0]
    s = rebuild(f.take((rel < 2.2) | (rel >= 4.0 - 1e-9))).nodes[1]  # 1.8 s silent, then STATUS
    assert s.segments == 1
    assert s.lost_frames == 3000 - s.frames  # seq wrapped inside the dropout, too
    assert (
        np.all(np.diff(s.index) >= 1) and np.asarray(s.index)[-1] - np.asarray(s.index)[0] == 8999
    )


def test_duplicated_frames_are_dropped() -> None:
    f = node_frames(1, np.arange(30), rate_hz=1000, scale_um_s2=10)
    # frames: STATUS, SAMPLES 0, 1, 2, 3, ...: SAMPLES 3 arrives twice in a row
    twice = Frames.concat([f.take(slice(0, 5)), f.take(slice(4, 5)), f.take(slice(5, None))])
    s = rebuild(twice).nodes[1]
    assert (
        s.duplicate_frames == 1
        and s.frames == 10
        and np.asarray(s.index).tolist() == list(range(30))
    )


@settings(deadline=None)
@given(st.integers(0, 2**16 - 1), st.data())
def test_marks_match_their_samples_whichever_arrives_first(
    first_seq: int, data: st.DataObject
) -> None:
    """Move every MARK up to 40 frames earlier or later in arrival order: same edges."""
    edges = np.arange(7.3, 3000, 333.37)
    f = node_frames(
        1, np.zeros(3000), rate_hz=1000, scale_um_s2=10, edges=edges, first_seq=first_seq
    )
    ref = rebuild(f).nodes[1]
    shift = np.zeros(len(f))
    is_mark = f.can_id == MARK_BASE + 1
    shift[is_mark] = data.draw(
        st.lists(st.integers(-40, 40), min_size=int(is_mark.sum()), max_size=int(is_mark.sum()))
    )
    order = np.argsort(np.arange(len(f)) + shift + 0.5 * is_mark, kind="stable")
    s = rebuild(f.take(order)).nodes[1]
    assert np.array_equal(s.mark_position, ref.mark_position)
    assert np.array_equal(s.mark_rev, ref.mark_rev)
    assert np.max(np.abs(s.mark_position - edges - 3 * first_seq)) <= 0.5 / 65536


@settings(deadline=None)
@given(
    st.integers(0, 2**16 - 1),
    st.lists(st.integers(0, 1999), max_size=200),
)
def test_any_pattern_of_lost_frames_keeps_every_true_index(first_seq: int, lost: list[int]) -> None:
    counts = np.arange(6000) % 30000
    f = node_frames(1, counts, rate_hz=1000, scale_um_s2=10, first_seq=first_seq)
    dec = decode(f)
    drop = dec.samples.frame[np.unique(np.asarray(lost, dtype=np.int64))]
    drop = drop[drop != dec.samples.frame[0]]  # keep the first frame: it fixes the origin
    s = rebuild(f.take(np.setdiff1d(np.arange(len(f)), drop))).nodes[1]
    kept_frames = np.setdiff1d(np.arange(2000), [k for k in lost if k != 0])
    truth = (3 * kept_frames[:, None] + np.arange(3)).reshape(-1)
    assert np.array_equal(np.asarray(s.index) - 3 * first_seq, truth)
    assert np.array_equal(s.counts, counts[truth])
    # frames lost after the last one received leave no gap: nobody can count them
    assert s.lost_frames == kept_frames[-1] + 1 - len(kept_frames)


def _status_at(f: Frames, t_first_status: float | None) -> Frames:
    """Move the node's STATUS frames: none at all, or only those from ``t_first_status`` on."""
    is_status = (f.can_id & 0x7C0) == STATUS_BASE
    keep = (
        ~is_status if t_first_status is None else ~is_status | (f.t_s - f.t_s[0] >= t_first_status)
    )
    return f.take(keep)


def test_no_status_is_a_clear_error_or_a_warning_if_chosen() -> None:
    f = _status_at(node_frames(1, np.ones(9000), rate_hz=4000, scale_um_s2=10), None)
    with pytest.raises(NoStatusError, match=r"node 1: no STATUS within 1.5 s .*none came") as e:
        rebuild(f)
    assert e.value.node == 1 and e.value.frame == 0
    r = rebuild(f, strict_status=False)
    assert r.nodes[1].accel_m_s2 is None and r.nodes[1].samples == 9000
    assert [w.code for w in r.warnings] == ["no_status"]


def test_status_later_than_1_5_s_is_refused_in_strict_mode() -> None:
    f = _status_at(node_frames(1, np.ones(12000), rate_hz=4000, scale_um_s2=10), 1.9)
    with pytest.raises(NoStatusError, match=r"the first came after 2\.00 s"):
        rebuild(f)
    r = rebuild(f, strict_status=False)  # scaled from the late STATUS, with a warning
    assert r.nodes[1].accel_m_s2 is not None and r.nodes[1].accel_m_s2[0] == pytest.approx(1e-5)
    ok = _status_at(node_frames(1, np.ones(12000), rate_hz=4000, scale_um_s2=10), 0.9)
    assert rebuild(ok).nodes[1].scale_um_s2 == 10


def test_status_flags_become_warnings_with_their_time() -> None:
    flags = [0, 0, 0, 2, 2, 0, 1]
    f = node_frames(1, np.ones(28000), rate_hz=4000, scale_um_s2=10, status_flags=flags)
    r = rebuild(f)
    assert r.nodes[1].flags == ("overrange", "sensor_fault")
    msgs = {w.code: w for w in r.warnings}
    assert msgs["status_sensor_fault"].t_s == pytest.approx(3.0, abs=1e-3)
    assert (
        "sensor fault at 3.00 s (in 2 STATUS frames, until 4.00 s)"
        in msgs["status_sensor_fault"].message
    )
    assert msgs["status_overrange"].t_s == pytest.approx(6.0, abs=1e-3)


def test_other_ids_and_bad_frames_are_counted_never_fatal() -> None:
    f = sine_run(seconds=1.0)
    other = Frames.build([f.t_s[5]] * 3, [0x7E0, 0x101, 0x181], np.zeros((3, 8)), dlc=[8, 5, 8])
    other.data[2, 2] = 9  # MARK slot 9
    both = Frames.concat([f, other]).sorted_by_time()
    r = rebuild(both)
    assert (r.unknown_frames, r.bad_frames) == (1, 2)
    assert r.nodes[1].frames == rebuild(f).nodes[1].frames
    assert any(w.code == "bad_frames" and "DLC 5" in w.message for w in r.warnings)


def test_samples_scale_by_the_latest_status() -> None:
    f = node_frames(1, np.ones(6000), rate_hz=1000, scale_um_s2=10)
    f.data[(f.can_id == STATUS_BASE + 1) & (f.t_s > 2.5), 2] = 20  # the scale from 3 s on
    s = rebuild(f).nodes[1]
    assert s.accel_m_s2 is not None
    assert s.accel_m_s2[0] == pytest.approx(1e-5) and s.accel_m_s2[-1] == pytest.approx(2e-5)
    assert any(w.code == "scale_changed" for w in rebuild(f).warnings)


def test_samples_ids_are_the_protocol_ids() -> None:
    assert (SAMPLES_BASE, STATUS_BASE, MARK_BASE) == (0x100, 0x140, 0x180)


@settings(max_examples=40, deadline=None)
@given(cuts=st.lists(st.integers(0, 21_588), max_size=30))
def test_a_builder_fed_in_any_blocks_gives_what_rebuild_gives(cuts: list[int]) -> None:
    """Live, blocks are decoded as they come and merged; the streams are the same."""
    from stand.drivers.v1.build import StreamBuilder

    frames = _demo_frames()
    bounds = sorted({0, len(frames), *cuts})
    builder = StreamBuilder()
    for lo, hi in itertools.pairwise(bounds):
        builder.add(frames.take(slice(lo, hi)))
    # merged like a binary counter: part sizes strictly fall (blocks of one size: log2 parts)
    assert all(a > b for a, b in itertools.pairwise(builder._sizes))
    got, want = builder.streams(), rebuild(frames)
    assert got.frames == want.frames and got.warnings == want.warnings
    for n in (1, 2):
        a, b = got.nodes[n], want.nodes[n]
        for name in ("index", "counts", "segment_start", "scale_start", "scale_m_s2",
                     "mark_position", "mark_rev"):  # fmt: skip
            assert np.array_equal(getattr(a, name), getattr(b, name)), name


@functools.cache
def _demo_frames() -> Frames:
    from stand.sim import load_scene, simulate

    sc, p, _ = load_scene("demo")
    return simulate(sc, p).frames
