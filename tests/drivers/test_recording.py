"""Run files and python-can logs: lossless round trips, crash safety, bad files."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
from synth import sine_run

from stand.core import Diagnostic
from stand.drivers.frames import FLAG_ERROR, FLAG_EXTENDED, FLAG_REMOTE, Frames
from stand.drivers.runs.logs import read_candump, read_log, write_log
from stand.drivers.runs.recording import Recording, read_recording, read_run, write_recording
from stand.drivers.runs.run_writer import FLUSH_INTERVAL_S, RunWriter
from stand.drivers.runs.seal import MAGIC, USERBLOCK_BYTES, read_in_child, seal_state
from stand.drivers.v1.build import rebuild
from stand.errors import RecordingError, WriteError

TESTS = Path(__file__).resolve().parents[1]


def _mixed() -> Frames:
    """Protocol frames plus every odd kind a bus carries: extended, remote, error, short, FD."""
    f = sine_run(seconds=0.5)
    odd = Frames.build(
        f.t_s[10] + np.arange(5) * 1e-6,
        [0x18FF50E5, 0x123, 0x80, 0x101, 0x7FF],
        np.arange(40, dtype=np.uint8).reshape(5, 8),
        dlc=[8, 0, 0, 5, 8],
        flags=[FLAG_EXTENDED, FLAG_REMOTE, FLAG_ERROR | FLAG_EXTENDED, 0, 0],
    )
    odd.data[1:3] = 0  # a remote frame has no payload; this error frame neither
    odd.data[3, 5:] = 0  # a 5-byte frame
    return Frames.concat([f, odd]).sorted_by_time()


def _same_frames(a: Frames, b: Frames, t_tol: float) -> None:
    assert len(a) == len(b)
    # an error frame is only "an error frame" in a log: its id and flags are the format's
    err = (a.flags & FLAG_ERROR) != 0
    assert np.array_equal(err, (b.flags & FLAG_ERROR) != 0)
    assert np.array_equal(a.can_id[~err], b.can_id[~err])
    assert np.array_equal(a.flags[~err], b.flags[~err])
    assert np.array_equal(a.dlc, b.dlc)
    assert np.array_equal(a.data, b.data)
    assert np.max(np.abs((a.t_s - a.t_s[0]) - (b.t_s - b.t_s[0]))) <= t_tol


def test_run_file_round_trip_is_exact(tmp_path: Path) -> None:
    f = _mixed()
    path = tmp_path / "run.h5"
    with RunWriter(path, source="test", config_toml="[stand]\n", software="stand test") as w:
        w.append(f.take(slice(0, 1000)))
        w.append(f.take(slice(1000, None)))
        w.warn([Diagnostic("x", "a warning", 1.0)])
    rec = read_run(path)
    for name in ("t_s", "can_id", "dlc", "data", "flags"):
        assert np.array_equal(getattr(rec.frames, name), getattr(f, name)), name
    assert rec.meta["complete"] is True or rec.meta["complete"] == 1
    assert rec.meta["config_toml"] == "[stand]\n" and rec.meta["software"] == "stand test"
    assert [w.message for w in rec.warnings] == ["a warning"]


def test_run_file_holds_the_decoded_streams_for_other_tools(tmp_path: Path) -> None:
    f = sine_run(seconds=1.0)
    path = tmp_path / "run.h5"
    streams = rebuild(f)
    write_recording(Recording("x", f), path, streams)
    with h5py.File(path) as h:  # plain h5py, as another tool would open it
        g = h["nodes/1"]
        assert np.array_equal(g["index"][:], streams.nodes[1].index)
        assert np.array_equal(g["accel_m_s2"][:], streams.nodes[1].accel_m_s2)
        assert np.array_equal(g["mark_position"][:], streams.nodes[1].mark_position)
        assert g.attrs["rate_hz"] == 4000 and g.attrs["lost_frames"] == 0


@pytest.mark.parametrize("suffix", [".log", ".asc", ".blf"])
def test_python_can_logs_round_trip(tmp_path: Path, suffix: str) -> None:
    f = _mixed()
    path = tmp_path / f"run{suffix}"
    write_log(f, path)
    back = read_log(path)
    # candump keeps microseconds; ASC and BLF keep time relative to the start
    _same_frames(f, back, t_tol=2e-6)
    assert rebuild(back).nodes[1].frames == rebuild(f).nodes[1].frames


def test_fast_candump_reader_equals_python_can(tmp_path: Path) -> None:
    import can

    from stand.drivers.frames import frames_from_messages

    path = tmp_path / "run.log"
    write_log(_mixed(), path)
    with can.LogReader(path) as r:
        slow = frames_from_messages(r)
    fast = read_candump(path)
    _same_frames(slow, fast, t_tol=0.0)


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        (
            "garbage.log",
            b"(1.0) can0 101#0001020304050607\nhello world\n",
            r"garbage.log:2: not a candump",
        ),
        ("odd.log", b"(1.0) can0 101#000102030405060\n", r"odd number of hex digits"),
        ("empty.h5", b"", r"not a readable run file"),
        ("text.h5", b"not hdf5 at all", r"not a readable run file"),
        ("bad.blf", b"\x00" * 300, r"not a readable .blf log"),
        ("bad.asc", b"\xff\xfe garbage", r"not a readable .asc log"),
        ("what.xyz", b"1234", r"unknown log format '.xyz'"),
    ],
)
def test_bad_files_give_one_clear_error(
    tmp_path: Path, name: str, content: bytes, message: str
) -> None:
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(RecordingError, match=message) as e:
        read_recording(path).frames.t_s.sum()
    assert str(path) in str(e.value) and "\n" not in str(e.value)


def test_truncated_and_foreign_hdf5_files_are_refused(tmp_path: Path) -> None:
    f = sine_run(seconds=2.0)
    path = tmp_path / "run.h5"
    write_recording(Recording("x", f), path)
    cut = tmp_path / "cut.h5"
    cut.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with pytest.raises(RecordingError, match=r"cut\.h5: not a readable run file"):
        read_run(cut)
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as h:
        h["x"] = [1, 2]
    with pytest.raises(RecordingError, match="not a run file"):
        read_run(other)


def test_writer_refuses_to_overwrite_a_run(tmp_path: Path) -> None:
    path = tmp_path / "run.h5"
    RunWriter(path, source="a").close()
    with pytest.raises(WriteError, match="exists already"):
        RunWriter(path, source="b")


def test_writer_keeps_frames_while_the_file_is_locked_by_a_reader(tmp_path: Path) -> None:
    f = sine_run(seconds=1.0)
    path = tmp_path / "run.h5"
    w = RunWriter(path, source="t", flush_interval_s=0.0)
    w.append(f.take(slice(0, 100)))
    with h5py.File(path, "r"):  # another program holds the file (with HDF5's lock)
        w.append(f.take(slice(100, 200)))  # the flush fails and is retried later
    w.append(f.take(slice(200, None)))
    w.close()
    assert np.array_equal(read_run(path).frames.data, f.data)


KILL_SCRIPT = textwrap.dedent(
    """
    import os, sys, threading, time
    sys.path.insert(0, {tests!r})
    import can
    from synth import sine_run
    from stand.drivers.bus import play
    from stand.cli import main

    frames = sine_run(seconds=30.0)
    tx = can.Bus(interface="virtual", channel="kill-test", receive_own_messages=False)

    def player():
        while not os.path.exists({out!r}):  # the recorder has made its run file ...
            time.sleep(0.01)
        time.sleep(0.3)  # ... and opens its end of the virtual bus right after
        with open({stamp!r}, "w") as f:
            f.write(repr(time.time()))
        play(tx, frames)

    threading.Thread(target=player, daemon=True).start()
    sys.exit(main(["record", "-i", "virtual", "-c", "kill-test", "--out", {out!r}, "--quiet"]))
    """
)


@pytest.mark.realtime
@pytest.mark.parametrize("after_s", [1.3, 2.15, 3.4])
def test_killing_a_recording_loses_at_most_the_last_second(tmp_path: Path, after_s: float) -> None:
    out, stamp = tmp_path / "run.h5", tmp_path / "t0"
    script = KILL_SCRIPT.format(tests=str(TESTS / "helpers"), stamp=str(stamp), out=str(out))
    env = {**os.environ, "PYTHONPATH": str(TESTS.parent)}
    proc = subprocess.Popen([sys.executable, "-c", script], env=env)
    try:
        deadline = time.time() + 30
        while not stamp.exists() or not stamp.read_text():
            assert time.time() < deadline and proc.poll() is None, "recorder did not start"
            time.sleep(0.02)
        t0 = float(stamp.read_text())
        time.sleep(max(0.0, t0 + after_s - time.time()))
        killed_at = time.time()
        proc.send_signal(signal.SIGKILL)
        proc.wait(10)
    finally:
        if proc.poll() is None:
            proc.kill()
    with h5py.File(out) as h:  # opens with plain h5py: no repair tool needed
        assert h.attrs["complete"] == 0
    assert seal_state(out) == "none"  # never closed: read by a child with a time limit first
    rec = read_run(out)
    sent = sine_run(seconds=30.0)
    n = len(rec.frames)
    # what was kept is exactly the first n frames sent, in order
    assert np.array_equal(rec.frames.data, sent.data[:n])
    assert np.array_equal(rec.frames.can_id, sent.can_id[:n])
    # and it reaches to within a second of the kill (the writer flushes every 0.5 s)
    sent_by_kill = np.searchsorted(sent.t_s - sent.t_s[0], killed_at - t0)
    one_second = np.searchsorted(sent.t_s - sent.t_s[0], 1.0)
    assert n >= sent_by_kill - one_second, (n, sent_by_kill)
    assert FLUSH_INTERVAL_S <= 0.5
    rebuild(rec.frames)  # and decodes


def test_a_closed_run_is_sealed_and_any_byte_changed_after_is_refused(tmp_path: Path) -> None:
    """The writer seals the run with the SHA-256 of its bytes; a byte changed where HDF5
    itself notices nothing (inside the text of the ``source`` attribute) is refused."""
    run = tmp_path / "run.h5"
    write_recording(Recording("x", sine_run(seconds=0.2), {"source": "bench-unit-7"}), run)
    head = run.read_bytes()[:USERBLOCK_BYTES]
    assert head.startswith(MAGIC) and seal_state(run) == "intact"
    read_run(run)
    blob = bytearray(run.read_bytes())
    at = blob.index(b"bench-unit-7", USERBLOCK_BYTES)
    blob[at] ^= 0x20  # "Bench-unit-7": still a valid attribute
    run.write_bytes(bytes(blob))
    assert seal_state(run) == "broken"
    with pytest.raises(RecordingError, match="no longer match the SHA-256 sealed"):
        read_run(run)


def test_a_reader_that_does_not_finish_is_refused_not_waited_for(tmp_path: Path) -> None:
    """What happens to a file on which HDF5 would loop for ever: the child reading it is
    still at it when its time is up, and the file is refused in one line, in time."""
    run = tmp_path / "run.h5"
    run.write_bytes(b"\0" * 1024)
    start = time.monotonic()
    with pytest.raises(RecordingError, match="did not finish reading it within 1 s"):
        read_in_child(run, timeout_s=1.0, argv=[sys.executable, "-c", "while True: pass"])
    assert time.monotonic() - start < 5.0
