"""A run file read and decoded by a forked child while this process loads its modules.

``stand solve RUN.h5`` spends about 0.12 s loading its modules, pydantic and the
config's models, and (600 s run) another 0.12 s reading and decoding the run:
one after the other, on one core.  Here a child forked before those imports
reads the run (:func:`stand.drivers.recording.read_streams`) on the second
core meanwhile, and hands the streams back through memory both share
(:class:`stand.process.beside.Beside` with ``shared_bytes``: the arrays are not copied
again).  600 s run: 0.525 -> 0.476 s median of 12 turns, the tree's memory no
larger.

Only where it pays and is safe: a run file (``.h5``) of :data:`AHEAD_BYTES`,
and a process that may fork (:func:`stand.process.beside.can_fork`).  The child reads
without the seal's guard (hashing the file first would lengthen its path);
this process hashes it meanwhile in a thread (:func:`stand.drivers.seal.seal_ahead`,
started after the fork) and takes the child's streams only when the seal is
intact.  Otherwise the child is ended (whatever it was doing with the file)
and the run is read here as ever: an unsealed file by a child with a time
limit first.  Either way the streams, the warnings and the errors are those of
``read_streams``.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from functools import partial
from pathlib import Path
from typing import Any

from stand.process.beside import Beside, can_fork

AHEAD_BYTES = (8 << 20, 128 << 20)
"""Run files read beside: from 8 MB (about 2 min of the demo stand: below, the read is
shorter than the fork and the hand-over cost; 60 s measured no faster) to 128 MB (about
35 min: above, copying the streams into the shared memory costs what the overlap saves,
and the process tree holds them twice for a while)."""
SHARED_PER_FILE_BYTE = 1.5
"""Shared memory reserved per byte of the file: its streams take 0.65 of it (a run read
without loss, 14 bytes a frame against 22) and at most about 1.4 (every sample's index
kept, 30 bytes a frame); only the pages written are ever memory."""

_AHEAD: dict[str, Beside] = {}


def _key(path: str | Path) -> str:
    return os.path.realpath(path)


@contextmanager
def read_beside(path: str | Path) -> Iterator[None]:
    """Read the run file ``path`` in a forked child for the time of the block, when it pays
    (:data:`AHEAD_BYTES`) and the process may fork; :func:`take_streams` takes what it read.
    A child not taken from by the end of the block is ended."""
    key = _key(path)
    started = _start(Path(path), key)
    try:
        yield
    finally:
        if started and key in _AHEAD:
            _AHEAD.pop(key).cancel()


def _start(p: Path, key: str) -> bool:
    try:
        size = p.stat().st_size
    except OSError:
        return False  # read here, which says why
    lo, hi = AHEAD_BYTES
    if p.suffix.lower() != ".h5" or not lo <= size <= hi or not can_fork():
        return False
    import h5py  # noqa: F401  # loaded here, once for both processes

    from stand.drivers.recording import read_streams

    reserve = int(size * SHARED_PER_FILE_BYTE) + (1 << 20)
    _AHEAD[key] = Beside(partial(read_streams, guard=False), str(p), shared_bytes=reserve)
    return True


def reading(path: str | Path) -> bool:
    """Whether a child is reading ``path`` (:func:`read_beside`)."""
    return _key(path) in _AHEAD


def take_streams(path: str | Path) -> Any:
    """``read_streams(path)``: the child's, if one read it and the file's seal is intact;
    else read here."""
    from stand.drivers.recording import read_streams
    from stand.drivers.seal import seal_state

    ahead = _AHEAD.pop(_key(path), None)
    if ahead is None:
        return read_streams(path)
    try:
        intact = seal_state(path) == "intact"
    except OSError:
        intact = False
    if not intact:  # the guard's way: the child read it unguarded, so it is not used
        ahead.cancel()
        return read_streams(path)
    return ahead.result()
