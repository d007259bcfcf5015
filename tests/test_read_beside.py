"""A run read by a forked child while the process loads its modules gives what reading it
here gives: the same streams, the same warnings, the same errors, the same answer.

And the shared memory it hands them back through: the arrays come back equal, as
views of it; an answer too large for it, or a child that dies, goes the old way.
"""

from __future__ import annotations

import io
import json
import mmap
import os
from contextlib import redirect_stdout
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from synth import sine_run
from test_speed_paths import _same_streams

from stand.drivers.recording import Recording, read_streams, write_recording
from stand.errors import NoStatusError
from stand.process import beside, read_beside

pytestmark = pytest.mark.skipif(not beside.can_fork(), reason="no fork here")


def _arrays(n: int) -> dict[str, np.ndarray]:
    return {"a": np.arange(n, dtype=np.float64), "b": np.arange(3 * n, dtype=np.int16)[::3]}


def _in_shared_memory(a: np.ndarray) -> bool:
    """Whether the array's memory is a mapping's (not the bytes of a pickle)."""
    base: object = a
    while isinstance(base, np.ndarray) and base.base is not None:
        base = base.base
    return isinstance(base, memoryview) and isinstance(base.obj, mmap.mmap)


def test_an_answer_comes_back_through_shared_memory_as_views_of_it() -> None:
    got = beside.Beside(_arrays, 100_000, shared_bytes=2 << 20).result()
    want = _arrays(100_000)
    assert all(np.array_equal(got[k], want[k]) for k in want)
    # the contiguous array is a view of the shared mapping, not a copy from the pipe
    assert _in_shared_memory(got["a"])
    got["a"][0] = -1.0  # writable, as an array read from a pipe is
    # too small for it: the old way, through the pipe
    small = beside.Beside(_arrays, 100_000, shared_bytes=4096).result()
    assert np.array_equal(small["a"], want["a"]) and not _in_shared_memory(small["a"])


def test_no_shared_memory_to_be_had_the_pipe_carries_it(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse(*a: object) -> None:
        raise OSError(12, "Cannot allocate memory")

    monkeypatch.setattr(beside, "mmap", SimpleNamespace(mmap=refuse))
    got = beside.Beside(_arrays, 1000, shared_bytes=1 << 20).result()
    assert np.array_equal(got["a"], _arrays(1000)["a"]) and not _in_shared_memory(got["a"])


def test_an_error_in_the_child_is_raised_with_shared_memory_too() -> None:
    from stand.errors import MeasurementError

    def refuse() -> None:
        raise MeasurementError("node 2: no reference edges")

    with pytest.raises(MeasurementError, match="node 2: no reference edges"):
        beside.Beside(refuse, shared_bytes=1 << 20).result()


@pytest.fixture
def everywhere(monkeypatch: pytest.MonkeyPatch) -> list[object]:
    """Every run file read beside (whatever its size); the children forked, counted."""
    forks: list[object] = []

    class Counted(beside.Beside):
        def __init__(self, *a: object, **k: object) -> None:
            forks.append(a)
            super().__init__(*a, **k)  # type: ignore[arg-type]

    monkeypatch.setattr(read_beside, "AHEAD_BYTES", (0, 1 << 40))
    monkeypatch.setattr(read_beside, "Beside", Counted)
    return forks


def test_a_run_read_beside_is_the_run_read_here(demo_run: Path, everywhere: list[object]) -> None:
    with read_beside.read_beside(demo_run):
        assert read_beside.reading(demo_run)
        rec, streams = read_beside.take_streams(demo_run)
    assert len(everywhere) == 1 and not read_beside.reading(demo_run)
    assert _in_shared_memory(streams.nodes[1].counts)  # the child's, not read again here
    here_rec, here = read_streams(demo_run)
    _same_streams(streams, here)
    assert rec.meta == here_rec.meta and rec.warnings == here_rec.warnings


def test_a_file_without_its_seal_is_read_here_the_guarded_way(
    demo_run: Path, tmp_path: Path, everywhere: list[object], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The child read it without the seal's guard: its streams are not taken."""
    from stand.drivers import recording

    run = tmp_path / "unsealed.h5"
    run.write_bytes(b"\0" * 16 + demo_run.read_bytes()[16:])  # the seal's magic gone
    here: list[str] = []
    original = recording.read_streams

    def read_here(path: object, **k: object) -> object:
        here.append(str(path))
        return original(path, **k)  # type: ignore[arg-type]

    with read_beside.read_beside(run):
        assert len(everywhere) == 1
        monkeypatch.setattr(recording, "read_streams", read_here)
        _, streams = read_beside.take_streams(run)
    assert here == [str(run)]  # read here (the guarded way), not taken from the child
    _same_streams(streams, original(demo_run)[1])


def test_an_error_reading_beside_is_the_error_reading_here(
    tmp_path: Path, everywhere: list[object]
) -> None:
    """A sealed run whose node never sent a STATUS: the child's error, raised here, is the
    one reading it here raises."""
    f = sine_run(seconds=2.0)
    f = f.take((f.can_id & 0x7C0) != 0x140)  # every STATUS frame left out
    run = tmp_path / "nostatus.h5"
    write_recording(Recording("x", f, {}), run)
    with pytest.raises(NoStatusError) as here:
        read_streams(run)
    with read_beside.read_beside(run), pytest.raises(NoStatusError) as ahead:
        read_beside.take_streams(run)
    assert len(everywhere) == 1
    assert str(ahead.value) == str(here.value)


def test_a_child_not_taken_from_is_ended(demo_run: Path, everywhere: list[object]) -> None:
    with read_beside.read_beside(demo_run):
        pass
    assert len(everywhere) == 1 and not read_beside.reading(demo_run)


def test_solve_reads_beside_and_answers_as_ever(
    demo_run: Path, everywhere: list[object], monkeypatch: pytest.MonkeyPatch
) -> None:
    from stand.cli import main

    def solve() -> dict[str, object]:
        out = io.StringIO()
        with redirect_stdout(out):
            assert main(["solve", str(demo_run), "--json"]) == 0
        return dict(json.loads(out.getvalue()))

    beside_answer = solve()
    assert len(everywhere) == 1
    monkeypatch.setenv("STAND_SERIAL", "1")  # no fork: read here
    assert solve() == beside_answer and len(everywhere) == 1


def test_only_run_files_of_a_size_that_pays_are_read_beside(tmp_path: Path) -> None:
    lo, hi = read_beside.AHEAD_BYTES
    for name, size, expected in (
        ("small.h5", lo - 1, False),
        ("long.h5", lo, True),
        ("huge.h5", hi + 1, False),
        ("run.log", lo, False),
    ):
        p = tmp_path / name
        with open(p, "wb") as f:
            f.truncate(size)  # sparse: the size is what is judged before anything is read
        with read_beside.read_beside(p):
            assert read_beside.reading(p) is expected, name
        assert not read_beside.reading(p)
    assert not read_beside.reading(tmp_path / "missing.h5")
    assert os.environ.get("STAND_SERIAL", "") in ("", "0")
