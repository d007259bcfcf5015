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
from collections.abc import Sequence
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
    "import sys; from stand.drivers.runs.recording import read_run; "
    "read_run(sys.argv[1], guard=False)"
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
    bytes no longer match (altered or damaged since)."""
    p = Path(path)
    with p.open("rb") as f:
        head = f.read(USERBLOCK_BYTES)
    if not head.startswith(MAGIC):
        return "none"
    stored = head[len(MAGIC) : len(MAGIC) + 64]
    return "intact" if stored == _digest(p).encode("ascii") else "broken"


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
