"""Blocks of a file read one ahead, in a thread, while the one before is taken.

h5py lets go of the interpreter's lock while HDF5 reads, so the read of one block of a
run file and the decoding of the block before run side by side (one hour: 2.36 -> 2.26 s).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Generator
from typing import Any, TypeVar

T = TypeVar("T")


def read_ahead(
    read: Callable[[int, int], T], bounds: list[tuple[int, int]]
) -> Generator[T, None, None]:
    """``read(lo, hi)`` of each of ``bounds``, in order, the next one read in a thread while
    the one before is taken (h5py lets go of the interpreter's lock while HDF5 reads, so
    the read of one block and the decoding of the last run side by side).  Closing the
    generator waits for a read under way: the file stays open until it ends."""
    done: dict[int, tuple[bool, Any]] = {}

    def fetch(i: int) -> None:
        try:
            done[i] = (True, read(*bounds[i]))
        except BaseException as exc:  # raised where the block is taken
            done[i] = (False, exc)

    ahead: threading.Thread | None = None
    try:
        for i in range(len(bounds)):
            if ahead is None:
                fetch(i)
            else:
                ahead.join()
            ahead = None
            if i + 1 < len(bounds):
                ahead = threading.Thread(target=fetch, args=(i + 1,), daemon=True)
                ahead.start()
            ok, value = done.pop(i)
            if not ok:
                raise value
            yield value
    finally:
        if ahead is not None:
            ahead.join()
