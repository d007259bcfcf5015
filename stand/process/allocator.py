"""glibc's memory allocator: what it holds free handed back before a fork, or kept by a
process that solves run after run (Linux; elsewhere: nothing).

Memory touched for the first time is what costs most on the project's 2-core CI
machine (a page fault: 6 to 70 us); a process about to fork hands what it holds free
back first (:func:`release_free_memory`), so that the child does not share it and
neither process copies pages it reuses.  Another C library keeps its own defaults.
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


def release_free_memory() -> None:
    """Hand the allocator's free memory back to the system (``malloc_trim``), before a
    fork: not shared with the child, neither process copies pages it reuses, and the
    pair holds less (600 s run: the pair's peak 246 -> 202 MiB from the .h5, 2026-11-25;
    one hour: no change)."""
    libc = _glibc()
    try:
        if libc is not None:
            libc.malloc_trim(0)
    except AttributeError:  # a C library without it: nothing to hand back
        pass


M_TRIM_THRESHOLD = -1
M_MMAP_THRESHOLD = -3
"""mallopt's parameter numbers (glibc's malloc.h)."""
KEEP_MMAP_BYTES = 32 << 20
KEEP_TRIM_BYTES = 64 << 20
"""Blocks below 32 MiB come from the heap; up to 64 MiB freed at its top stays there."""


def keep_freed_memory() -> bool:
    """Fix glibc's thresholds where its own dynamic rule would end up (mmap threshold 32
    MiB, trim threshold 64 MiB) in a process that solves run after run: the arrays of one
    run are reused by the next instead of mapped, faulted in and returned each time.  Also
    undoes ``MALLOC_TRIM_THRESHOLD_=65536``, which Dask's nanny sets for its workers and
    which fixes the mmap threshold at 128 KiB.  Reprocessing 2000 runs of 8 s
    (``tests/bench/bench_reprocess.py``, 2026-11-25): one process 34.3 -> 43.5 runs/s, one
    Dask worker 24.7 -> 48.1 runs/s.  True if glibc took both."""
    libc = _glibc()
    try:
        if libc is None:
            return False
        return bool(libc.mallopt(M_MMAP_THRESHOLD, KEEP_MMAP_BYTES)) and bool(
            libc.mallopt(M_TRIM_THRESHOLD, KEEP_TRIM_BYTES)
        )
    except AttributeError:
        return False
