"""The candump fast path (byte columns) reads exactly what the regular expression reads."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stand.drivers.runs import candump, logs
from stand.errors import RecordingError

FIELDS = ("t_s", "can_id", "dlc", "data", "flags")


def same(a: object, b: object) -> bool:
    return all(np.array_equal(getattr(a, f), getattr(b, f)) for f in FIELDS)


line = st.builds(
    lambda t, d, chan, ext, can_id, data, tail: (
        f"({t}.{d}) {chan} "
        + (f"{can_id & 0x1FFFFFFF:08X}" if ext else f"{can_id & 0x7FF:03X}")
        + "#"
        + data.hex().upper()
        + tail
    ),
    st.integers(0, 2_000_000_000),
    st.sampled_from(["000000", "5", "123456", "999999999"]),
    st.sampled_from(["can0", "vcan1", "x"]),
    st.booleans(),
    st.integers(0, 0x1FFFFFFF),
    st.binary(min_size=0, max_size=8),
    st.sampled_from(["", " R", " T"]),
)


@settings(max_examples=200)
@given(lines=st.lists(line, min_size=1, max_size=40), last_newline=st.booleans())
def test_fast_and_regular_expression_agree(
    tmp_path_factory: pytest.TempPathFactory, lines: list[str], last_newline: bool
) -> None:
    path = tmp_path_factory.mktemp("c") / "x.log"
    path.write_text("\n".join(lines) + ("\n" if last_newline else ""))
    fast = candump._fast_candump(np.fromfile(path, np.uint8))
    slow = candump._read_candump_text(path)
    # a stamp whose digits, as one integer, are no exact double takes the slow path
    ticks = max(int(x[1 : x.index(")")].replace(".", "")) for x in lines)
    assert (fast is None) == (ticks >= 2**53), ticks
    assert fast is None or same(fast, slow)
    assert same(candump.read_candump(path), slow)


@settings(max_examples=200)
@given(lines=st.lists(line, min_size=1, max_size=20), at=st.integers(0, 10_000),
       junk=st.sampled_from([b"garbage", b"(1.0) can0 12#R", b"(x) can0 123#00", b"",
                             b"  (1.0) can0 123#00", b"(1.0) can0 123##011", b"(-1.0) can0 1#0",
                             b"(1.0)  can0 123#00", b"(1.0) can0 123#0"]))  # fmt: skip
def test_an_unusual_line_takes_the_slow_path_with_the_same_answer(
    tmp_path_factory: pytest.TempPathFactory, lines: list[str], at: int, junk: bytes
) -> None:
    raw = [x.encode() for x in lines]
    raw.insert(at % (len(raw) + 1), junk)
    path = tmp_path_factory.mktemp("c") / "x.log"
    path.write_bytes(b"\n".join(raw) + b"\n")
    try:
        slow = candump._read_candump_text(path)
    except RecordingError as exc:
        with pytest.raises(RecordingError) as got:
            candump.read_candump(path)
        assert str(got.value) == str(exc)  # the same file and line named
        return
    assert same(candump.read_candump(path), slow)


def test_blocks_split_at_line_ends(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    lines = [f"({k}.000100) can0 101#{k % 256:02X}00000000000000" for k in range(2000)]
    path = tmp_path / "x.log"
    path.write_text("\n".join(lines) + "\n")
    monkeypatch.setattr(candump, "CANDUMP_BLOCK", 1000)  # many blocks, each cut mid-line
    assert same(candump.read_candump(path), candump._read_candump_text(path))


def test_streaming_a_log_falls_back_whole_when_a_late_block_is_unusual(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Blocks already decoded are dropped and the whole file is read the slow way."""
    from stand.drivers import read_streams
    from stand.drivers.v1.build import StreamBuilder, rebuild
    from stand.sim import load_scene, simulate

    sc, p, _ = load_scene("demo")
    frames = simulate(sc, p).frames
    path = tmp_path / "x.log"
    logs.write_log(frames, path)
    with path.open("a") as f:
        f.write("(99.000000) can0 123#R\n")  # a remote frame: only the slow path reads it
    monkeypatch.setattr(candump, "CANDUMP_BLOCK", 50_000)
    _, got = read_streams(path, lambda meta: StreamBuilder(), strict_status=False)
    want = rebuild(logs.read_log(path), strict_status=False)
    assert got.frames == want.frames == len(frames) + 1
    for n in (1, 2):
        assert np.array_equal(got.nodes[n].index, want.nodes[n].index)
        assert np.array_equal(got.nodes[n].counts, want.nodes[n].counts)


def test_epoch_stamps_take_the_fast_path_with_the_same_doubles(tmp_path: Path) -> None:
    """candump -l and python-can's logger stamp frames with epoch seconds and microseconds
    (16 digits): the fast path takes them (no fallback) and gives the very doubles float()
    gives the text; 19 digits (beyond an int64) fall back, with the same answer."""
    stamps = [f"({1763799999 + k // 7}.{(k * 131071) % 1_000_000:06d})" for k in range(3000)]
    text = "".join(f"{s} can0 141#A00F6400000100{k % 100:02d} R\n" for k, s in enumerate(stamps))
    path = tmp_path / "epoch.log"
    path.write_text(text)
    fast = list(candump.iter_candump_fast(path))  # raises UnusualLogError on a fallback
    t = np.concatenate([f.t_s for f in fast])
    assert np.array_equal(t, [float(s[1:-1]) for s in stamps])
    assert same(candump._fast_candump(np.frombuffer(text.encode(), np.uint8)),
                candump._read_candump_text(path))  # fmt: skip
    long = tmp_path / "long.log"
    long.write_text("(1763799999999.999999) can0 141#00\n")
    assert candump._fast_candump(np.frombuffer(long.read_bytes(), np.uint8)) is None
    assert candump.read_candump(long).t_s[0] == float("1763799999999.999999")
