"""The faster paths of a long run give the answers of the plain ones.

* ``cos_sin`` (a table and a Taylor series) against numpy's ``cos`` and
  ``sin``: within 4.5e-16 absolute.  The table's entries are within half an
  ulp of the true values (1.1e-16 near 1), the series' first term left out is
  below 1.3e-18, and the angle-sum formula adds two roundings: 4.4e-16 at
  most; numpy's own results are within one ulp.  Observed: 2.2e-16.
* The side bands from each group's Taylor moments against the sums sample
  by sample: within 1e-5 of the sums' natural size ``sqrt(sum r^2)`` (both
  in single precision, 6e-8 an operation, over 65,536 samples summed in
  another order; observed about 1e-6).
* A node measured in a forked child: the very same answer as measured in
  the process itself, and its errors raised as they were.
"""

from __future__ import annotations

import math
import os
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stand.core import fitsums, trig
from stand.errors import MeasurementError
from stand.measuring import measure
from stand.process import allocator, beside

finite = st.floats(-trig.THETA_MAX, trig.THETA_MAX, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(st.lists(finite, min_size=1, max_size=300), st.floats(1e-3, 1.0))
def test_cos_sin_is_numpy_to_the_last_bits(angles: list[float], scale: float) -> None:
    th = np.array(angles) * scale
    c, s = trig.cos_sin(th)
    assert np.max(np.abs(c - np.cos(th))) <= 4.5e-16
    assert np.max(np.abs(s - np.sin(th))) <= 4.5e-16


def test_cos_sin_over_a_million_angles_and_its_edges() -> None:
    rng = np.random.default_rng(7)
    th = (rng.random(1 << 20) * 2 - 1) * trig.THETA_MAX
    th[:6] = [trig.THETA_MAX, -trig.THETA_MAX, 0.0, -0.0, math.pi, 2 * math.pi * 131_071]
    c, s = trig.cos_sin(th)
    assert np.max(np.abs(c - np.cos(th))) <= 4.5e-16
    assert np.max(np.abs(s - np.sin(th))) <= 4.5e-16


@pytest.mark.parametrize("th", [[1e7, 1.0], [np.nan, 1.0], [np.inf, 0.0], []])
def test_cos_sin_leaves_what_the_table_cannot_take_to_numpy(th: list[float]) -> None:
    a = np.array(th, dtype=float)
    with np.errstate(invalid="ignore"):
        c, s = trig.cos_sin(a)
        assert np.array_equal(c, np.cos(a), equal_nan=True)
        assert np.array_equal(s, np.sin(a), equal_nan=True)


@pytest.mark.parametrize("window", [240_000, 2_400_000, 14_400_000])
@pytest.mark.parametrize("n", [65_536, 65_536 - 5, 1_000])
def test_grouped_side_bands_are_the_direct_sums(window: int, n: int) -> None:
    """A chunk of a window of ``window`` samples (60 s to one hour at 4 kHz)."""
    rng = np.random.default_rng(window + n)
    r = rng.standard_normal(n).astype(np.float32)
    th = np.arange(n) * 0.0235 + 0.3
    c, s = np.cos(th).astype(np.float32), np.sin(th).astype(np.float32)
    phase = ((np.arange(n) + 1234) * (2 * np.pi / window)).astype(np.float32)
    direct = fitsums._side_bands_direct(r, c, s, phase, 8)
    got = fitsums.side_band_sums(r, c, s, phase, 8)
    scale = float(np.sqrt(np.sum(r.astype(float) ** 2)))
    assert np.max(np.abs(got - direct)) <= 1e-5 * scale


def test_a_short_window_is_summed_sample_by_sample() -> None:
    """A 0.5 s window moves too far in a group for 8 Taylor terms: the direct sums, bitwise."""
    n = 2000
    r = np.ones(n, np.float32)
    c = s = np.full(n, 0.5, np.float32)
    phase = (np.arange(n) * (2 * np.pi / n)).astype(np.float32)
    ph = phase[: n // 64 * 64].reshape(-1, 64)
    assert fitsums._taylor_terms(ph - ph[:, 32:33], 9) is None
    assert np.array_equal(
        fitsums.side_band_sums(r, c, s, phase, 8), fitsums._side_bands_direct(r, c, s, phase, 8)
    )


def _square(x: int) -> int:
    return x * x


def _refuse(what: str) -> None:
    raise MeasurementError(f"node 2: {what}")


def _die_in_child(parent: int) -> int:
    if os.getpid() != parent:
        os._exit(3)  # a child killed before it could answer
    return 42


@pytest.mark.skipif(not beside.can_fork(), reason="no fork here")
def test_work_beside_returns_its_value_and_raises_its_errors() -> None:
    assert beside.Beside(_square, 7).result() == 49
    with pytest.raises(MeasurementError, match="node 2: no reference edges"):
        beside.Beside(_refuse, "no reference edges").result()
    # a child that dies: the parent does the work itself
    assert beside.Beside(_die_in_child, os.getpid()).result() == 42
    b = beside.Beside(time.sleep, 30)
    t0 = time.perf_counter()
    b.cancel()
    b.cancel()  # idempotent
    assert time.perf_counter() - t0 < 5


def test_no_process_to_fork_the_work_is_done_here(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse() -> int:
        raise BlockingIOError(11, "Resource temporarily unavailable")

    monkeypatch.setattr(os, "fork", refuse)
    b = beside.Beside(_square, 9)
    assert b.result() == 81
    b.cancel()  # nothing to end


def test_no_fork_with_other_threads_or_when_told(monkeypatch: pytest.MonkeyPatch) -> None:
    import threading

    stop = threading.Event()
    t = threading.Thread(target=stop.wait)
    t.start()
    try:
        assert not beside.can_fork()
    finally:
        stop.set()
        t.join()
    monkeypatch.setenv("STAND_SERIAL", "1")
    assert not beside.can_fork()


@pytest.mark.skipif(not beside.can_fork(), reason="no fork here")
def test_a_node_measured_beside_gives_the_same_answer(monkeypatch: pytest.MonkeyPatch) -> None:
    from stand.drivers.v1.build import rebuild
    from stand.sim import load_scene, simulate

    sc, p, _ = load_scene("demo")
    streams = rebuild(simulate(sc, p).frames)
    serial = measure.measure(streams, p)
    forks: list[object] = []

    class Counted(beside.Beside):
        def __init__(self, *a: object) -> None:
            forks.append(a)
            super().__init__(*a)  # type: ignore[arg-type]

    monkeypatch.setattr(measure, "FORK_SAMPLES", 1000)
    monkeypatch.setattr(measure, "Beside", Counted)
    forked = measure.measure(streams, p)
    assert len(forks) == 1
    assert np.array_equal(forked.solution.U_kg_m, serial.solution.U_kg_m)
    assert np.array_equal(forked.radius95_kg_m, serial.radius95_kg_m)
    assert [w.message for w in forked.warnings] == [w.message for w in serial.warnings]


def test_streams_released_are_the_streams() -> None:
    """A builder's blocks let go during the rebuild give the streams kept blocks give."""
    from stand.drivers.v1.build import StreamBuilder
    from stand.sim import load_scene, simulate

    sc, p, _ = load_scene("demo")
    frames = simulate(sc, p).frames
    a, b = StreamBuilder(merge=False), StreamBuilder(merge=False)
    for lo in range(0, len(frames), 7000):
        block = frames.take(np.arange(lo, min(lo + 7000, len(frames))))
        a.add(block)
        b.add(block)
    kept, released = a.streams(), b.streams(release=True)
    assert b.frames == 0
    _same_streams(kept, released)


def _same_streams(a: object, b: object) -> None:
    """Every node's every field equal (arrays, or what reads as one, element by element),
    and the same warnings."""
    from dataclasses import fields

    for node, s in a.nodes.items():  # type: ignore[attr-defined]
        r = b.nodes[node]  # type: ignore[attr-defined]
        for f in fields(s):
            x, y = getattr(s, f.name), getattr(r, f.name)
            assert np.array_equal(x, y) if hasattr(x, "__array__") else x == y, f.name
    assert [w.message for w in a.warnings] == [w.message for w in b.warnings]  # type: ignore[attr-defined]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's malloc_trim")
def test_free_memory_is_handed_back_before_a_fork(monkeypatch: pytest.MonkeyPatch) -> None:
    """64 MB freed below a block still in use stay with the process (glibc cannot trim
    its heap's top past that block) until they are handed back; elsewhere: nothing."""

    def resident() -> int:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")

    blocks = [bytearray(65536) for _ in range(1000)]  # from the heap (below mmap's threshold)
    for b in blocks:
        memoryview(b)[::4096] = bytes(16)  # every page touched
    last = blocks[-1]
    del blocks
    before = resident()
    allocator.release_free_memory()
    assert before - resident() > 32 << 20
    assert len(last) == 65536
    monkeypatch.setattr(allocator.sys, "platform", "darwin")
    allocator.release_free_memory()  # no glibc: nothing, and no error


def test_a_run_files_times_are_read_once_and_taken_without_a_copy(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Read in blocks, a run file's times are views of the one array read whole: the
    streams take that array itself (and what live blocks bring is still joined); the
    streams are those of the run read whole."""
    from stand.drivers import Recording, read_streams, write_recording
    from stand.drivers.v1 import build
    from stand.drivers.v1.build import StreamBuilder, _joined
    from stand.sim import load_scene, simulate

    sc, p, _ = load_scene("demo")
    frames = simulate(sc, p).frames
    run = tmp_path / "r.h5"
    write_recording(Recording("t", frames, {}), run)
    seen: list[np.ndarray] = []

    class Watch(StreamBuilder):
        def add(self, block: object) -> None:
            seen.append(block.t_s)  # type: ignore[attr-defined]
            super().add(block)  # type: ignore[arg-type]

    whole = read_streams(run, lambda meta: StreamBuilder())[1]
    monkeypatch.setattr(build, "READ_ROWS", 7000)
    blocks = read_streams(run, lambda meta: Watch())[1]
    assert len(seen) > 1 and seen[0].base is not None
    assert all(t.base is seen[0].base for t in seen)
    joined = _joined(seen)
    assert joined.base is seen[0].base and np.array_equal(joined, frames.t_s)
    assert blocks.duration_s == whole.duration_s and blocks.frames == whole.frames
    _same_streams(whole, blocks)
    apart = [frames.t_s[:10].copy(), frames.t_s[10:30].copy()]  # live blocks: joined, copied
    assert np.array_equal(_joined(apart), frames.t_s[:30]) and _joined(apart).base is None
    assert len(_joined([])) == 0
