"""The vectorised decoder against the DBC (via cantools), and the bad-frame matrix."""

from __future__ import annotations

import cantools
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from stand.drivers.frames import FLAG_ERROR, FLAG_EXTENDED, FLAG_FD, FLAG_REMOTE, Frames
from stand.drivers.v1.codec import decode, edge_fields, encode_marks, encode_samples, encode_status
from stand.drivers.v1.protocol import DBC_PATH, LAYOUT

DB = cantools.database.load_file(DBC_PATH, strict=True)
KINDS = {0x100: "SAMPLES", 0x140: "STATUS", 0x180: "MARK"}


def test_dbc_holds_three_messages_per_node_for_nodes_1_and_2() -> None:
    names = sorted(m.name for m in DB.messages)
    assert names == sorted(f"{k}_{n}" for k in KINDS.values() for n in (1, 2))
    for m in DB.messages:
        assert m.length == 8 and not m.is_extended_frame
        assert m.frame_id - {"SAMPLES": 0x100, "STATUS": 0x140, "MARK": 0x180}[
            m.name.split("_")[0]
        ] == int(m.name.split("_")[1])


@pytest.mark.parametrize("kind", LAYOUT)
def test_decoder_layout_is_the_dbc_layout(kind: str) -> None:
    """Every field the decoder reads is a DBC signal (or, for flags, the DBC's flag bits)."""
    msg = DB.get_message_by_name(f"{kind}_1")
    signals = {s.name: s for s in msg.signals}
    for name, (offset, dtype) in LAYOUT[kind].items():
        size = np.dtype(dtype).itemsize
        if name == "flags":
            bits = [
                signals[n] for n in ("overrange", "sensor_fault", "no_reference", "flags_unused")
            ]
            assert [s.start for s in bits] == [
                8 * offset,
                8 * offset + 1,
                8 * offset + 2,
                8 * offset + 3,
            ]
            assert sum(s.length for s in bits) == 8 * size
            continue
        s = signals[name]
        assert (s.start, s.length, s.byte_order) == (8 * offset, 8 * size, "little_endian")
        assert s.is_signed == (np.dtype(dtype).kind == "i")
        assert (s.scale, s.offset) == (1, 0)


protocol_ids = st.sampled_from([b + n for b in KINDS for n in (1, 2)])
payloads = st.binary(min_size=8, max_size=8)


@given(st.lists(st.tuples(protocol_ids, payloads), min_size=1, max_size=60))
def test_decode_equals_cantools_for_random_frames(frames: list[tuple[int, bytes]]) -> None:
    f = Frames.build(
        np.arange(len(frames)) * 1e-3,
        [i for i, _ in frames],
        np.frombuffer(b"".join(d for _, d in frames), np.uint8).reshape(-1, 8),
    )
    dec = decode(f)
    bad = {b.frame: b for b in dec.bad}
    seen = 0
    for rec_name, rec in (("SAMPLES", dec.samples), ("STATUS", dec.status), ("MARK", dec.marks)):
        for j, frame in enumerate(rec.frame.tolist()):
            can_id, data = frames[frame]
            ref = DB.decode_message(can_id, data, decode_choices=False)
            assert rec.node[j] == can_id & 0xF
            if rec_name == "SAMPLES":
                got = dict(
                    seq=rec.seq[j], s0=rec.counts[j, 0], s1=rec.counts[j, 1], s2=rec.counts[j, 2]
                )
            elif rec_name == "STATUS":
                flags = int(rec.flags[j])
                got = dict(
                    rate=rec.rate[j],
                    scale=rec.scale[j],
                    version=rec.version[j],
                    overrange=flags & 1,
                    sensor_fault=flags >> 1 & 1,
                    no_reference=flags >> 2 & 1,
                    flags_unused=flags >> 3,
                )
            else:
                got = dict(seq=rec.seq[j], slot=rec.slot[j], frac=rec.frac[j], rev=rec.rev[j])
            assert {k: int(v) for k, v in got.items()} == {k: ref[k] for k in got}
            seen += 1
    # the frames the decoder refuses are exactly those the protocol rules out
    for i, (can_id, data) in enumerate(frames):
        ref = DB.decode_message(can_id, data, decode_choices=False)
        kind = KINDS[can_id & ~0x3F]
        should_be_bad = (kind == "MARK" and ref["slot"] > 2) or (
            kind == "STATUS" and ref["version"] != 1
        )
        assert (i in bad) == should_be_bad
    assert seen + len(bad) == len(frames)


@given(
    st.integers(1, 15),
    st.lists(st.integers(0, 2**20), min_size=1, max_size=20),
    st.integers(-32768, 32767),
)
def test_encode_then_decode_round_trips(node: int, seqs: list[int], count: int) -> None:
    counts = np.full((len(seqs), 3), count)
    dec = decode(encode_samples(node, seqs, counts, np.zeros(len(seqs))))
    assert dec.samples.seq.tolist() == [s % 65536 for s in seqs]
    assert (dec.samples.counts == count).all() and (dec.samples.node == node).all()
    dec = decode(encode_status(node, 4000, 100, 5, [0.0]))
    assert (dec.status.rate[0], dec.status.scale[0], dec.status.flags[0]) == (4000, 100, 5)
    dec = decode(encode_marks(node, seqs, 2, 65535, seqs, np.zeros(len(seqs))))
    assert dec.marks.rev.tolist() == [s % 65536 for s in seqs]


@given(st.floats(0, 1e7, allow_nan=False))
def test_edge_fields_place_the_edge_within_half_a_tick(p: float) -> None:
    F, slot, frac = edge_fields(p)
    assert 0 <= slot <= 2 and 0 <= frac < 65536
    assert abs(3 * F + slot + frac / 65536 - p) <= 0.5 / 65536 * (1 + 1e-9) + p * 2e-16


def _one(can_id: int, dlc: int = 8, flags: int = 0, data: bytes = bytes(8)) -> Frames:
    """A good SAMPLES frame of node 1, then the frame under test, then another good one."""
    good = encode_samples(1, [0], [[1, 2, 3]], [0.0])
    odd = Frames.build([1e-3], can_id, np.frombuffer(data, np.uint8)[None, :], dlc=dlc, flags=flags)
    return Frames.concat([good, odd, encode_samples(1, [1], [[4, 5, 6]], [2e-3])])


@pytest.mark.parametrize(
    ("can_id", "dlc", "flags", "data", "expect"),
    [
        (0x101, 6, 0, bytes(8), "bad:wrong length: DLC 6, expected 8"),
        (0x141, 0, 0, bytes(8), "bad:wrong length: DLC 0, expected 8"),
        (0x181, 7, 0, bytes(8), "bad:wrong length"),
        (0x101, 8, FLAG_REMOTE, bytes(8), "bad:remote frame"),
        (0x101, 8, FLAG_FD, bytes(8), "bad:CAN FD"),
        (0x181, 8, 0, bytes([0, 0, 3, 0, 0, 0, 0, 0]), "bad:MARK slot 3"),
        (0x141, 8, 0, bytes([0xA0, 0x0F, 100, 0, 0, 2, 0, 0]), "bad:STATUS protocol version 2"),
        (0x101, 8, FLAG_EXTENDED, bytes(8), "unknown"),  # 29-bit id space: not ours
        (0x100, 8, 0, bytes(8), "unknown"),  # node 0 does not exist
        (0x110, 8, 0, bytes(8), "unknown"),  # node 16 does not exist
        (0x7FF, 8, 0, bytes(8), "unknown"),
        (0x000, 0, FLAG_ERROR, bytes(8), "error"),
    ],
)
def test_bad_frame_matrix(can_id: int, dlc: int, flags: int, data: bytes, expect: str) -> None:
    dec = decode(_one(can_id, dlc, flags, data))
    assert dec.samples.frame.tolist() == [0, 2]  # the frames around it still decode
    kind, _, text = expect.partition(":")
    assert (len(dec.bad), dec.unknown_frames, dec.error_frames) == (
        kind == "bad",
        kind == "unknown",
        kind == "error",
    )
    if kind == "bad":
        assert dec.bad[0].frame == 1 and dec.bad[0].reason.startswith(text)


def test_frames_keep_can_fd_payloads_whole() -> None:
    long = Frames.build([0.0], 0x300, np.arange(64, dtype=np.uint8)[None, :], dlc=64, flags=FLAG_FD)
    both = Frames.concat([encode_samples(1, [0], [[1, 2, 3]], [0.0]), long])
    assert both.data.shape == (2, 64) and both.data[1].tolist() == list(range(64))
    assert decode(both).unknown_frames == 1
