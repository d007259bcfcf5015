"""The live reader on python-can's virtual bus: lossless, bounded, clear failures."""

from __future__ import annotations

import socket
import threading
import time
import uuid
from collections.abc import Iterator
from typing import Any

import can
import numpy as np
import pytest
from synth import sine_run

from stand.drivers.bus import BusReader, open_bus, open_player_bus, play
from stand.drivers.frames import FLAG_ERROR, Frames
from stand.errors import BusError, BusTimeoutError


@pytest.fixture
def pair() -> Iterator[tuple[Any, Any]]:
    channel = f"test-{uuid.uuid4().hex}"
    tx = can.Bus(interface="virtual", channel=channel)
    rx = can.Bus(interface="virtual", channel=channel)
    yield tx, rx
    tx.shutdown()
    rx.shutdown()


def _drain(reader: BusReader) -> tuple[Frames, BaseException]:
    blocks = []
    while True:
        try:
            blocks.append(reader.read_block(0.05))
        except BusError as exc:
            return Frames.concat(blocks), exc


@pytest.mark.realtime
def test_reader_receives_every_frame_in_order_in_real_time(pair: tuple[Any, Any]) -> None:
    tx, rx = pair
    f = sine_run(seconds=1.5)
    with BusReader(rx, silence_timeout_s=0.5) as reader:
        threading.Thread(target=play, args=(tx, f), daemon=True).start()
        got, end = _drain(reader)
    assert isinstance(end, BusTimeoutError) and "no more frames" in str(end)
    assert len(got) == len(f) and reader.frames_received == len(f)
    assert np.array_equal(got.data, f.data) and np.array_equal(got.can_id, f.can_id)
    assert np.all(np.diff(got.t_s) >= 0) and reader.overruns == 0


def test_no_frames_at_all_is_a_timeout_that_says_so(pair: tuple[Any, Any]) -> None:
    _, rx = pair
    with BusReader(rx, silence_timeout_s=0.2, channel_info="virtual:x") as reader:
        got, end = _drain(reader)
    assert len(got) == 0 and isinstance(end, BusTimeoutError)
    assert str(end).startswith("virtual:x: no frames at all for 0.2 s")
    assert end.timeout_s == 0.2 and end.frames_received == 0


def test_pending_frames_are_bounded_and_overruns_counted(pair: tuple[Any, Any]) -> None:
    tx, rx = pair
    f = sine_run(seconds=0.2)
    reader = BusReader(rx, max_pending=100, silence_timeout_s=0.3)
    play(tx, f, realtime=False)
    deadline = time.monotonic() + 5
    while reader.overruns + 100 < len(f) and time.monotonic() < deadline:  # nobody reads yet
        time.sleep(0.01)
    got, _ = _drain(reader)
    reader.close()
    assert len(got) == 100 and reader.overruns == len(f) - 100


class _DyingBus(can.BusABC):  # type: ignore[misc]
    """A bus whose interface goes away after a few frames."""

    def __init__(self, frames: int) -> None:
        self.left = frames
        self.channel_info = "dying"
        super().__init__(channel="dying")

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        if self.left == 0:
            raise can.CanOperationError("device unplugged")
        self.left -= 1
        return can.Message(arbitration_id=0x101, data=bytes(8)), False

    def send(self, msg: can.Message, timeout: float | None = None) -> None:  # pragma: no cover
        pass


def test_interface_gone_keeps_what_came_and_says_what_happened() -> None:
    with BusReader(_DyingBus(7)) as reader:
        got, end = _drain(reader)
    assert len(got) == 7
    assert isinstance(end, BusError) and not isinstance(end, BusTimeoutError)
    assert "device unplugged" in str(end) and "7 frames received before" in str(end)
    assert end.frames_received == 7


def test_bus_off_error_frame_ends_the_run(pair: tuple[Any, Any]) -> None:
    tx, rx = pair
    with BusReader(rx, silence_timeout_s=1.0) as reader:
        tx.send(can.Message(arbitration_id=0x101, data=bytes(8)))
        tx.send(can.Message(arbitration_id=0x40, is_error_frame=True))
        got, end = _drain(reader)
    assert len(got) == 2 and (got.flags[1] & FLAG_ERROR)
    assert isinstance(end, BusError) and "bus-off" in str(end)


def test_close_is_idempotent_and_leaves_the_bus_to_its_owner(pair: tuple[Any, Any]) -> None:
    tx, rx = pair
    reader = BusReader(rx)
    reader.close()
    reader.close()
    tx.send(can.Message(arbitration_id=1, data=b"x"))
    assert rx.recv(1.0) is not None  # the bus still works: the reader did not shut it


def test_open_bus_failures_are_bus_errors() -> None:
    with pytest.raises(BusError, match=r"nosuch:can9: cannot open the bus"):
        open_bus({"interface": "nosuch", "channel": "can9"})
    with pytest.raises(BusError, match="no CAN interface given"):
        open_bus({"channel": "can0"})
    # this machine has no CAN in its kernel: socketcan cannot open
    with pytest.raises(BusError, match="socketcan:can-does-not-exist: cannot open the bus"):
        open_bus({"interface": "socketcan", "channel": "can-does-not-exist"})


class _Slow:
    """A bus whose ``send`` takes ``pause_s``: a player that falls behind its frames, as on
    a loaded machine."""

    def __init__(self, bus: Any, pause_s: float):
        self.bus, self.pause_s = bus, pause_s

    def send(self, msg: can.Message) -> None:
        time.sleep(self.pause_s)
        self.bus.send(msg)


@pytest.mark.realtime
@pytest.mark.parametrize("interface", ["virtual", "stand_loopback"])
def test_a_late_player_still_stamps_its_frames_with_their_wire_time(interface: str) -> None:
    channel: object = f"test-{uuid.uuid4().hex}"
    if interface == "stand_loopback":
        with socket.socket() as s:  # a port nobody holds now
            s.bind(("127.0.0.1", 0))
            channel = s.getsockname()[1]
    kwargs = {"interface": interface, "channel": channel}
    f = sine_run(seconds=0.15)
    span = float(f.t_s[-1] - f.t_s[0])
    pause = 2 * span / (len(f) - 1)  # every send takes twice the frames' mean spacing
    tx, stamps = open_player_bus(kwargs)
    rx = open_bus(kwargs)
    try:
        with BusReader(rx, silence_timeout_s=0.5) as reader:
            start = time.time()
            play(_Slow(tx, pause), f, wire_stamps=stamps)
            took_s = time.time() - start
            got, _ = _drain(reader)
    finally:
        tx.shutdown()
        rx.shutdown()
    # a sleep never ends early: the sends alone took twice the frames' span (late by one)
    assert stamps and took_s >= pause * len(f) > 2 * span
    assert len(got) == len(f)
    # each stamp is the start's time.time() plus the frame's offset: exact but for the
    # resolution of a double at 1.8e9 s (2.4e-7 s) and the microseconds between the two
    # clocks' reads at the start
    offset = got.t_s - f.t_s
    assert float(np.ptp(offset)) < 1e-5, float(np.ptp(offset))
