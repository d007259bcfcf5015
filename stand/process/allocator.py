"""glibc's memory allocator, told how to treat freed memory (Linux; elsewhere: nothing).

Memory touched for the first time is what costs most on the project's 2-core CI
machine (a page fault: 6 to 70 us), so the commands that read whole runs keep
what they free for reuse (:func:`keep_freed_memory`), and a process about to
fork hands what it holds free back first, so that the child does not share it
(:func:`release_free_memory`).  Another C library keeps its own defaults.
"""

from __future__ import annotations

import ctypes
import sys
from typing import Any


def _glibc() -> Any:
    """The C library, where it is glibc (None elsewhere or if it cannot be loaded)."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        return ctypes.CDLL("libc.so.6")
    except OSError:
        return None


def keep_freed_memory() -> None:
    """Blocks under 32 MB from the heap, and freed heap kept (up to 1 GB).

    A run is read and measured in blocks and chunks of 1 to 8 MB; by default
    glibc maps each such block afresh and unmaps it when freed (a one-hour
    run, three solves each way: 0.75 to 1.7 s of system time, 0.45 to 1.24 s
    with this).  For the one-shot commands that read whole runs; not the station.
    """
    libc = _glibc()
    try:
        if libc is not None:
            libc.mallopt(-3, 32 << 20)  # M_MMAP_THRESHOLD
            libc.mallopt(-1, 1 << 30)  # M_TRIM_THRESHOLD
    except AttributeError:  # a C library without it: its own defaults
        pass


def release_free_memory() -> None:
    """Hand the allocator's free memory back to the system (``malloc_trim``), before a
    fork: not shared with the child, neither process copies pages it reuses, and the
    pair holds less (600 s run: the pair's peak 276 -> 221 MiB from the .h5, 288 -> 210
    MiB from the log; 0.65 -> 0.61 s)."""
    libc = _glibc()
    try:
        if libc is not None:
            libc.malloc_trim(0)
    except AttributeError:  # a C library without it: nothing to hand back
        pass
