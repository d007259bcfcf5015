"""A null-modem cable between two pseudo-terminals: what one side writes, the other reads,
as two serial ports wired back to back (RS-485 without the adapters), for the Modbus RTU
tests.  Linux's pseudo-terminals take 8 N 1 (a parity bit is refused by their driver)."""

from __future__ import annotations

import os
import select
import threading
import tty
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def null_modem() -> Iterator[tuple[str, str]]:
    """Two serial lines' device paths, wired to each other while inside."""
    pairs = [os.openpty() for _ in range(2)]
    for _, follower in pairs:
        tty.setraw(follower)
    (a, _), (b, _) = pairs
    done = threading.Event()

    def pump() -> None:
        while not done.is_set():
            ready, _, _ = select.select([a, b], [], [], 0.1)
            for fd in ready:
                try:
                    data = os.read(fd, 4096)
                except OSError:  # the other side not open (yet, or any more)
                    continue
                os.write(b if fd == a else a, data)

    thread = threading.Thread(target=pump, daemon=True, name="null-modem")
    thread.start()
    try:
        yield os.ttyname(pairs[0][1]), os.ttyname(pairs[1][1])
    finally:
        done.set()
        thread.join(2.0)
        for fds in pairs:
            for fd in fds:
                os.close(fd)
