"""The stand_loopback bus: frames of every kind cross between members on 127.0.0.1 only,
a member's own messages come back in the hub's one order, bad channels are refused, and
the hub outlives its holder while others are on it."""

from __future__ import annotations

import socket

import can
import pytest


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
    return port


def _bus(port: int, **kw: object) -> can.BusABC:
    return can.Bus(interface="stand_loopback", channel=port, **kw)


def test_frames_of_every_kind_cross_and_own_ones_come_back_in_order() -> None:
    port = _port()
    a, b = _bus(port), _bus(port, receive_own_messages=True)
    try:
        sent = [
            can.Message(arbitration_id=0x80, data=b"", is_extended_id=False),
            can.Message(arbitration_id=0x1ABCDE0, data=b"\x01\x02", is_extended_id=True),
            can.Message(
                arbitration_id=0x300,
                data=bytes(range(64)),
                is_fd=True,
                bitrate_switch=True,
                is_extended_id=False,
            ),
            can.Message(arbitration_id=0x123, is_remote_frame=True, dlc=3, is_extended_id=False),
        ]
        for m in sent:
            b.send(m)
        for bus in (a, b):  # b's own come back to it too
            got = [bus.recv(2.0) for _ in sent]
            for g, m in zip(got, sent, strict=True):
                assert g is not None
                assert (g.arbitration_id, g.is_extended_id, g.is_fd, g.is_remote_frame) == (
                    m.arbitration_id, m.is_extended_id, m.is_fd, m.is_remote_frame)  # fmt: skip
                assert g.dlc == m.dlc and (m.is_remote_frame or bytes(g.data) == bytes(m.data))
        a.send(can.Message(arbitration_id=0x181, data=b"x", is_extended_id=False))
        assert b.recv(2.0).arbitration_id == 0x181  # type: ignore[union-attr]
        assert a.recv(0.2) is None  # a does not receive its own
    finally:
        a.shutdown()
        b.shutdown()


def test_the_hub_serves_the_others_after_its_holder_closed() -> None:
    port = _port()
    holder, b, c = _bus(port), _bus(port), _bus(port)
    holder.shutdown()
    try:
        b.send(can.Message(arbitration_id=0x42, data=b"ok", is_extended_id=False))
        got = c.recv(2.0)
        assert got is not None and bytes(got.data) == b"ok"
    finally:
        b.shutdown()
        c.shutdown()


@pytest.mark.parametrize("channel", ["abc", "80", "70000", ""])
def test_a_bad_channel_is_refused(channel: str) -> None:
    with pytest.raises(can.CanInitializationError, match="stand_loopback"):
        _bus(channel)  # type: ignore[arg-type]


def test_its_hub_listens_on_the_loopback_address_only() -> None:
    port = _port()
    bus = _bus(port)
    try:
        hub = bus._hub  # type: ignore[attr-defined]
        assert hub is not None and hub.server.getsockname() == ("127.0.0.1", port)
    finally:
        bus.shutdown()
