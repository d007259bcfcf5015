"""A CAN bus between processes of this machine only: python-can's interface
``stand_loopback`` (registered as a ``can.interface`` entry point), its channel a TCP
port on 127.0.0.1 (``-i stand_loopback -c 47001``).

python-can's ``virtual`` bus joins buses inside one process; its ``udp_multicast`` binds
its socket to every interface of the machine.  This one binds 127.0.0.1 and nothing else:
the first bus opened on a port becomes its hub (a thread that hands every frame one
member sends to every other member), every bus connects to it; the process that holds it
ends after the other members have left (30 s at most).  Frames cross as fixed
records of 78 bytes (time, id, flags, length, 64 data bytes), so CAN FD frames pass
whole; a member that receives its own messages gets them back from the hub, in the one
order every member sees.  For the simulated stand and the tests; a real stand uses its
interface's own driver.
"""

from __future__ import annotations

import contextlib
import select
import socket
import struct
import threading
import time
from typing import Any

import can

HOST = "127.0.0.1"
RECORD = struct.Struct("<dIBB64s")
"""One frame: time [s], arbitration id, flags (1 extended, 2 remote, 4 error, 8 FD, 16
bit-rate switch, 32 back to its sender too), data length, 64 data bytes: 78 bytes."""
LINGER_S = 30.0
"""A hub whose holder closed its bus serves the others this long at most [s]."""
FLAGS_AT = 12
"""The flags' byte in a record."""
ECHO = 32
"""A record with this flag goes back to its sender as well: a member that receives its own
messages receives them in the hub's one order, as a CAN bus's members see its frames."""


def _port(channel: Any) -> int:
    try:
        port = int(str(channel).rsplit(":", 1)[-1])
    except ValueError:
        raise can.CanInitializationError(
            f"stand_loopback: the channel is a TCP port on {HOST} (1024..65535), got {channel!r}"
        ) from None
    if not 1024 <= port <= 65535:
        raise can.CanInitializationError(f"stand_loopback: port {port} is not in 1024..65535")
    return port


class _Hub(threading.Thread):
    """The members of one port: every record one sends goes to every other (and back to
    its sender where it asks).  A thread of the process that opened the port first (a
    process of its own was measured slower on two cores: one more to schedule between
    a SYNC and its answer).  When that process closes its bus the hub stays while other
    members are on it, :data:`LINGER_S` at most: the process ends after them."""

    def __init__(self, server: socket.socket) -> None:
        super().__init__(name=f"stand_loopback hub {server.getsockname()[1]}", daemon=False)
        self.server = server
        self.members: list[socket.socket] = []
        self.stopped = False
        self.deadline = 0.0

    def stop(self) -> None:
        """Its holder closed its bus: end once the other members have left."""
        self.deadline = time.monotonic() + LINGER_S
        self.stopped = True

    def run(self) -> None:
        pending: dict[socket.socket, bytes] = {}
        while not (self.stopped and (not self.members or time.monotonic() > self.deadline)):
            ready, _, _ = select.select([self.server, *self.members], [], [], 0.1)
            for s in ready:
                if s is self.server:
                    conn, _ = self.server.accept()
                    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                    self.members.append(conn)
                    continue
                data = b""
                with contextlib.suppress(OSError):
                    data = s.recv(1 << 16)
                if not data:
                    self.members.remove(s)
                    s.close()
                    continue
                buf = pending.get(s, b"") + data
                whole = len(buf) - len(buf) % RECORD.size
                pending[s] = buf[whole:]
                back = b"".join(buf[k : k + RECORD.size] for k in range(0, whole, RECORD.size)
                                if buf[k + FLAGS_AT] & ECHO)  # fmt: skip
                for other in self.members:
                    with contextlib.suppress(OSError):
                        other.sendall(back if other is s else buf[:whole])
        for s in (*self.members, self.server):
            s.close()


class LoopbackBus(can.BusABC):
    """python-can's bus over a hub on 127.0.0.1 (see the module's docstring)."""

    def __init__(self, channel: Any, can_filters: Any = None, *,
                 receive_own_messages: bool = False, preserve_timestamps: bool = False,
                 **kwargs: Any) -> None:  # fmt: skip
        port = _port(channel)
        self._hub: _Hub | None = None
        self.sock = self._connect(port)
        self.channel_info = f"stand_loopback {HOST}:{port}"
        self.receive_own_messages = receive_own_messages
        self.preserve_timestamps = preserve_timestamps
        """Send a message's own timestamp (a simulated adapter's wire time), not the time
        of sending (as python-can's virtual interface does)."""
        self._buf = b""
        self._lock = threading.Lock()
        super().__init__(channel=channel, can_filters=can_filters, **kwargs)

    def _connect(self, port: int) -> socket.socket:
        """A connection to the port's hub; the hub started here where there is none."""
        for _ in range(3):  # another process may be becoming the hub just now
            try:
                return _connected(port)
            except ConnectionRefusedError:
                pass
            server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            try:
                server.bind((HOST, port))
            except OSError:
                server.close()
                time.sleep(0.05)
                continue
            server.listen(16)
            self._hub = _Hub(server)
            self._hub.start()
        try:
            return _connected(port)
        except OSError as exc:
            raise can.CanInitializationError(f"stand_loopback: no hub on {HOST}:{port} "
                                             f"({exc})") from exc  # fmt: skip

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        flags = (msg.is_extended_id * 1 | msg.is_remote_frame * 2 | msg.is_error_frame * 4
                 | msg.is_fd * 8 | msg.bitrate_switch * 16
                 | ECHO * self.receive_own_messages)  # fmt: skip
        stamp = msg.timestamp if self.preserve_timestamps else time.time()
        record = RECORD.pack(stamp, msg.arbitration_id, flags, msg.dlc,
                             bytes(msg.data).ljust(64, b"\0"))  # fmt: skip
        try:
            with self._lock:
                self.sock.sendall(record)
        except OSError as exc:
            raise can.CanOperationError(f"stand_loopback: the bus is gone ({exc})") from exc

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        if len(self._buf) < RECORD.size:
            ready, _, _ = select.select([self.sock], [], [], timeout)
            if not ready:
                return None, False
            try:
                data = self.sock.recv(1 << 16)
            except OSError as exc:
                raise can.CanOperationError(f"stand_loopback: the bus is gone ({exc})") from exc
            if not data:
                raise can.CanOperationError("stand_loopback: the hub closed the bus")
            self._buf += data
            if len(self._buf) < RECORD.size:
                return None, False
        t, cid, flags, dlc, payload = RECORD.unpack_from(self._buf)
        self._buf = self._buf[RECORD.size :]
        return can.Message(timestamp=t, arbitration_id=cid, is_extended_id=bool(flags & 1),
                           is_remote_frame=bool(flags & 2), is_error_frame=bool(flags & 4),
                           is_fd=bool(flags & 8), bitrate_switch=bool(flags & 16), dlc=dlc,
                           data=payload[:dlc], channel=self.channel_info), False  # fmt: skip

    def shutdown(self) -> None:
        super().shutdown()
        with contextlib.suppress(OSError):
            self.sock.close()
        if self._hub is not None:
            self._hub.stop()


def _connected(port: int) -> socket.socket:
    sock = socket.create_connection((HOST, port), timeout=1.0)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock
