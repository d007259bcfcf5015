"""Nodes left to build on first use (:mod:`stand.drivers.node_map`) are the nodes.

A long solve builds each support's node where it is measured: node 1 in the
process, node 2 in a forked child.  Whoever reads the streams must see what a
full rebuild gives: the same arrays, the same warnings in the same order, and
the same error when a node cannot be built or measured.
"""

from __future__ import annotations

from dataclasses import fields

import numpy as np
import pytest

from stand import beside, measure
from stand.drivers.protocol import MARK_BASE, SAMPLES_BASE, STATUS_BASE, Frames
from stand.drivers.streams import RunStreams, StreamBuilder
from stand.errors import MeasurementError, NoStatusError
from stand.sim import load_scene, simulate

SCENE, PARAMS, _ = load_scene("demo")


def _frames(drop: int | None = None, lose: bool = True) -> Frames:
    """The demo run with some SAMPLES frames of both nodes lost (their warnings), and
    without the frames of CAN id ``drop`` if given."""
    frames = simulate(SCENE, PARAMS).frames
    keep = np.ones(len(frames), bool)
    if lose:
        samples = np.flatnonzero((frames.can_id >> 6) == SAMPLES_BASE >> 6)
        keep[samples[5000:5012]] = False
    if drop is not None:
        keep &= frames.can_id != drop
    return frames.take(np.flatnonzero(keep))


def _streams(frames: Frames, later: tuple[int, ...] = (), later_from: int = 0) -> RunStreams:
    b = StreamBuilder(merge=False)
    for lo in range(0, len(frames), 7000):
        b.add(frames.take(np.arange(lo, min(lo + 7000, len(frames)))))
    return b.streams(release=True, later=later, later_from=later_from)


def _same_stream(a: object, b: object) -> None:
    for f in fields(a):  # type: ignore[arg-type]
        x, y = getattr(a, f.name), getattr(b, f.name)
        assert np.array_equal(x, y) if isinstance(x, np.ndarray) else x == y, f.name


def test_nodes_left_for_later_are_built_on_first_use_as_a_full_rebuild() -> None:
    frames = _frames()
    full, lazy = _streams(frames), _streams(frames, later=(1, 2))
    nodes = lazy.nodes
    assert nodes.pending() == [1, 2]
    assert 1 in nodes and 3 not in nodes and len(nodes) == 2 and list(nodes) == [1, 2]
    assert nodes.samples_of(1) == full.nodes[1].samples  # known before the build
    assert nodes.pending() == [1, 2]  # none of that built a node
    assert [w.message for w in lazy.warnings] == [w.message for w in full.warnings]
    assert any("node 2" in w.message for w in full.warnings)  # the comparison has teeth
    assert nodes.pending() == []  # the warnings needed both
    for n in (1, 2):
        _same_stream(full.nodes[n], nodes[n])
    assert "later=[]" in repr(nodes)
    n = full.nodes[1].samples
    assert _streams(frames, (1, 2), later_from=n + 1).nodes.pending() == []  # too short
    assert _streams(frames, (1, 2), later_from=n).nodes.pending() == [1, 2]


@pytest.mark.skipif(not beside.can_fork(), reason="no fork here")
def test_a_node_built_beside_is_not_built_here_and_gives_the_same_answer(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    frames = _frames()
    full = _streams(frames)
    serial = measure.measure(full, PARAMS)
    monkeypatch.setattr(measure, "FORK_SAMPLES", 1000)
    lazy = _streams(frames, later=(1, 2))
    forked = measure.measure(lazy, PARAMS)
    assert lazy.nodes.pending() == [2]  # built in the child only
    assert np.array_equal(forked.solution.U_kg_m, serial.solution.U_kg_m)
    assert np.array_equal(forked.radius95_kg_m, serial.radius95_kg_m)
    assert [w.message for w in forked.warnings] == [w.message for w in serial.warnings]
    assert [w.message for w in lazy.warnings] == [w.message for w in full.warnings]
    assert lazy.nodes.pending() == [2]  # its warnings came from the child
    _same_stream(full.nodes[2], lazy.nodes[2])  # asked for: built here, the same


@pytest.mark.parametrize("fork", [True, False])
@pytest.mark.parametrize(
    ("drop", "error", "match"),
    [
        (STATUS_BASE + 2, NoStatusError, "node 2"),  # node 2 cannot be built
        (STATUS_BASE + 1, NoStatusError, "node 1"),  # node 1 cannot be built
        (MARK_BASE + 1, MeasurementError, "node 1: no reference edges"),
        (MARK_BASE + 2, MeasurementError, "node 2: no reference edges"),
    ],
)
def test_errors_come_as_in_order(
    monkeypatch: pytest.MonkeyPatch, fork: bool, drop: int, error: type, match: str
) -> None:
    if fork and not beside.can_fork():
        pytest.skip("no fork here")
    monkeypatch.setattr(measure, "FORK_SAMPLES", 1000 if fork else 10**12)
    frames = _frames(drop, lose=False)
    with pytest.raises(error, match=match):
        _streams(frames)  # a full rebuild raises its errors at once ...
        measure.measure(_streams(frames), PARAMS)
    with pytest.raises(error, match=match):  # ... nodes left for later, when measured
        measure.measure(_streams(frames, later=(1, 2)), PARAMS)


@pytest.mark.skipif(not beside.can_fork(), reason="no fork here")
def test_node_2_unbuildable_comes_before_node_1_unmeasurable(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(measure, "FORK_SAMPLES", 1000)
    frames = simulate(SCENE, PARAMS).frames
    keep = (frames.can_id != STATUS_BASE + 2) & (frames.can_id != MARK_BASE + 1)
    frames = frames.take(np.flatnonzero(keep))
    with pytest.raises(NoStatusError, match="node 2"):
        _streams(frames)
    with pytest.raises(NoStatusError, match="node 2"):
        measure.measure(_streams(frames, later=(1, 2)), PARAMS)
