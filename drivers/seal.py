"""A run file's seal: the SHA-256 of its content, written when the writer closes it.

HDF5 reads a file whose bytes were damaged as far as its structure lets it; on
some damage the library itself never returns (fuzzing found a flipped byte on
which libhdf5 loops for ever reading the root attributes).  So a run file is
created with a 512-byte user block in front of the HDF5 data (HDF5 finds its
superblock at offset 512 and ignores what lies before), and when the writer
closes the run it writes there::

    rotor-stand-run sha256 <64 hex digits of the SHA-256 of every byte after 512>\\n

Before a run file is read, :func:`seal_state` hashes it again.  An intact seal
means the bytes are the ones the writer closed: HDF5 reads them as it wrote
them.  A file without a seal (a recording cut short by a crash, a file written
by another program) or with a broken one is first read by a child process
with a time limit (:func:`read_in_child`): a file on which HDF5 would hang is
refused instead of hanging the command.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import threading
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Literal

from stand.errors import RecordingError

USERBLOCK_BYTES = 512
"""Bytes in front of the HDF5 data (the smallest user block HDF5 allows)."""
MAGIC = b"rotor-stand-run sha256 "
CHILD_SECONDS = 10.0
"""A child's time to read an unsealed run file [s], plus :data:`CHILD_BYTES_PER_S`."""
CHILD_BYTES_PER_S = 10e6
"""A tenth of the speed the readers reach on this project's test machine (about 100 MB/s)."""
_READ = (
    "import sys; from stand.drivers.recording import read_run; read_run(sys.argv[1], guard=False)"
)

SealState = Literal["intact", "none", "broken"]


def _digest(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as f:
        f.seek(USERBLOCK_BYTES)
        while chunk := f.read(1 << 20):
            h.update(chunk)
    return h.hexdigest()


def seal(path: str | Path) -> None:
    """Write the seal of a closed run file into its user block (and sync it).

    The seal is one 512-byte write inside the first sector: a crash leaves the old
    block (no seal) or the new one.
    """
    p = Path(path)
    line = MAGIC + _digest(p).encode("ascii") + b"\n"
    with p.open("r+b") as f:
        f.write(line.ljust(USERBLOCK_BYTES, b"\0"))
        f.flush()
        os.fsync(f.fileno())


def seal_state(path: str | Path) -> SealState:
    """``"intact"``: the bytes are those the writer sealed; ``"none"``: no seal (cut
    short by a crash, or not written by this software); ``"broken"``: a seal that the
    bytes no longer match (altered or damaged since).

    Taken from :func:`prefetch_seal` when it hashed this very file (same size,
    modification time and inode) in the background.
    """
    p = Path(path)
    key = _file_key(p)
    found = _take_ahead(p, key)
    return found if found is not None else _state(p)


def _take_ahead(p: Path, key: tuple[str, int, int, int] | None) -> SealState | None:
    """The state hashed ahead for ``key`` (None: none); every check of this file ahead,
    stale or not, is joined and forgotten."""
    found: SealState | None = None
    name = os.path.realpath(p)  # never raises (a symlink loop stays as it is)
    for k in [k for k in _AHEAD if k[0] == name]:
        thread, box = _AHEAD.pop(k)
        thread.join()
        if k == key and box:
            found = box[0]
    return found


def _state(p: Path) -> SealState:
    with p.open("rb") as f:
        head = f.read(USERBLOCK_BYTES)
    if not head.startswith(MAGIC):
        return "none"
    stored = head[len(MAGIC) : len(MAGIC) + 64]
    return "intact" if stored == _digest(p).encode("ascii") else "broken"


_AHEAD: dict[tuple[str, int, int, int], tuple[threading.Thread, list[SealState]]] = {}
"""Seals being checked ahead, by file (:func:`prefetch_seal`)."""


def _file_key(p: Path) -> tuple[str, int, int, int]:
    st = p.stat()
    return (os.path.realpath(p), st.st_size, st.st_mtime_ns, st.st_ino)


@contextmanager
def seal_ahead(path: str | Path) -> Iterator[None]:
    """:func:`prefetch_seal` for the time of the block; what was not taken up by then is
    joined and forgotten (a command that ends before it reads leaves no thread)."""
    prefetch_seal(path)
    try:
        yield
    finally:
        _take_ahead(Path(path), None)


def prefetch_seal(path: str | Path) -> None:
    """Start checking a run file's seal in a thread, for :func:`seal_state` to take up.

    Hashing a one-hour run takes about 0.15 s; hashlib lets go of the
    interpreter's lock while it hashes, so a command that starts it first
    hashes on the second core while it imports its modules.  Nothing happens
    for a path that cannot be read (the read itself says why, later).
    """
    p = Path(path)
    try:
        key = _file_key(p)
    except OSError:
        return
    box: list[SealState] = []

    def check() -> None:
        try:
            box.append(_state(p))
        except OSError:
            pass  # seal_state checks again, and says why

    thread = threading.Thread(target=check, name="seal", daemon=True)
    thread.start()
    _AHEAD[key] = (thread, box)


def read_in_child(
    path: str | Path, *, timeout_s: float | None = None, argv: Sequence[str] | None = None
) -> None:
    """Read the run file in a child process first; refuse it if the child is still at it
    after ``timeout_s`` (default: :data:`CHILD_SECONDS` plus the file's size at
    :data:`CHILD_BYTES_PER_S`).  Whatever else the child meets, the caller's own read
    meets again and says in its own words.

    Parameters
    ----------
    argv
        The child's command (tests); by default this Python reading ``path``.
    """
    p = Path(path)
    if timeout_s is None:
        timeout_s = CHILD_SECONDS + p.stat().st_size / CHILD_BYTES_PER_S
    cmd = list(argv) if argv is not None else [sys.executable, "-c", _READ, str(p)]
    try:
        subprocess.run(cmd, capture_output=True, timeout=timeout_s, check=False)
    except subprocess.TimeoutExpired as exc:
        raise RecordingError(
            f"HDF5 did not finish reading it within {timeout_s:.0f} s: the file is damaged "
            "(it has no intact seal, so it was cut short, altered or not written here)",
            path=str(p),
        ) from exc
    except OSError as exc:
        raise RecordingError(f"cannot start a reader for it ({exc})", path=str(p)) from exc
