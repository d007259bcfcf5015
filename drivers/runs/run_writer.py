"""The run file's writer: frames appended as they arrive, safe at any crash.

The format and its reader are :mod:`stand.drivers.runs.recording` (its docstring
describes the file, the crash safety and the seal); this module writes it:
:class:`RunWriter` keeps the file closed between flushes, and
:func:`write_streams` adds the decoded per-node streams at the end.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from stand.core import Diagnostic
from stand.drivers.frames import FRAME_DLC, MAX_PAYLOAD, Frames
from stand.drivers.runs.run_format import (
    FRAME_FIELDS,
    RUN_FORMAT,
    RUN_FORMAT_VERSION,
    config_digest,
    h5py_module,
    utc_now,
)
from stand.drivers.runs.seal import USERBLOCK_BYTES, seal
from stand.drivers.streams import RunStreams
from stand.errors import RecordingError, WriteError
from stand.files import check_output, ensure_room, publish, temporary_beside, write_error

FLUSH_INTERVAL_S = 0.5
"""Frames reach the disk at least this often [s]; a crash loses at most this much."""
RETRY_FOR_S = 10.0
"""A flush that fails (file locked by a reader) is retried for this long before giving up [s]."""
_CHUNK_ROWS = 16384
# the decoded streams are written once, at the end: compress them (the raw frames are
# not compressed, so an append never moves a chunk that is already on disk)
_COMPRESSED: dict[str, Any] = {"compression": "gzip", "compression_opts": 1, "shuffle": True}
_MAX_WIDTH = MAX_PAYLOAD


def _empty_datasets(f: Any, h5py: Any) -> None:
    """The run file's datasets, empty and growable: ``/frames`` (chunked, Fletcher32; the
    payload widens to CAN FD's 64 bytes when one comes) and ``/warnings``."""
    g = f.create_group("frames")
    for name, dtype in FRAME_FIELDS.items():
        g.create_dataset(
            name, shape=(0,), maxshape=(None,), dtype=dtype, chunks=(_CHUNK_ROWS,), fletcher32=True
        )
    g.create_dataset(
        "data",
        shape=(0, FRAME_DLC),
        maxshape=(None, _MAX_WIDTH),
        dtype=np.uint8,
        chunks=(_CHUNK_ROWS, FRAME_DLC),
        fletcher32=True,
    )
    w = f.create_group("warnings")
    for name in ("code", "message"):
        w.create_dataset(
            name, shape=(0,), maxshape=(None,), dtype=h5py.string_dtype(), chunks=(256,)
        )


class RunWriter:
    """Append frames to an HDF5 run file as they arrive.

    Parameters
    ----------
    path
        The run file to create (an existing file is refused).
    source
        What the frames come from (e.g. ``"socketcan:can0"``, ``"replay of x.log"``).
    config_toml
        The configuration text in force, stored verbatim.
    software
        Software name and version.
    flush_interval_s
        Longest time frames wait in memory [s].
    attrs
        More text attributes to store with the run (e.g. the influence matrix used).

    Use as a context manager; :meth:`close` is idempotent and is where the
    decoded streams are added.
    """

    def __init__(
        self,
        path: str | Path,
        *,
        source: str,
        config_toml: str = "",
        software: str = "",
        flush_interval_s: float = FLUSH_INTERVAL_S,
        force: bool = False,
        attrs: Mapping[str, str] | None = None,
    ):
        self.path = Path(path)
        self.software = software
        self.source = source
        self.end_time = ""
        self.warnings: tuple[Diagnostic, ...] = ()
        """Every warning recorded so far."""
        self.flush_interval_s = flush_interval_s
        self._pending: list[Frames] = []
        self._warnings: list[Diagnostic] = []
        self._attrs: dict[str, str] = {}
        self._n = 0
        self._width = FRAME_DLC
        self._closed = False
        self._last_flush = self._last_success = time.monotonic()
        self._broken = False
        check_output(self.path, force=force, exists="exists already: a run is never overwritten")
        ensure_room(self.path.parent, 0, self.path)
        h5py = h5py_module()
        self.start_time = utc_now()
        tmp: Path | None = None
        try:
            tmp = temporary_beside(self.path)
            with h5py.File(tmp, "w", userblock_size=USERBLOCK_BYTES) as f:  # for the seal
                f.attrs.update(
                    format=RUN_FORMAT,
                    format_version=RUN_FORMAT_VERSION,
                    software=software,
                    start_time=self.start_time,
                    source=source,
                    config_toml=config_toml,
                    config_sha256=config_digest(config_toml),
                    frames_committed=0,
                    complete=False,
                )
                f.attrs.update(dict(attrs or {}))
                _empty_datasets(f, h5py)
            publish(tmp, self.path, force=force)  # of two writers of one name, one wins
        except OSError as exc:
            if tmp is not None:
                tmp.unlink(missing_ok=True)
            raise write_error(exc, self.path, "cannot create the run file") from exc

    @property
    def frames_written(self) -> int:
        """Frames committed to the file so far."""
        return self._n

    def append(self, frames: Frames) -> None:
        """Take a block of frames; they reach the disk within ``flush_interval_s``."""
        if self._closed:
            raise RecordingError("run file already closed", path=str(self.path))
        if len(frames):
            self._pending.append(frames)
        if time.monotonic() - self._last_flush >= self.flush_interval_s:
            try:
                self.flush()
            except RecordingError:
                # e.g. another program holds the file's lock for a moment: keep the frames
                # and retry at the next interval; give up only after RETRY_FOR_S
                if time.monotonic() - self._last_success > RETRY_FOR_S:
                    raise

    def warn(self, warnings: Iterable[Diagnostic]) -> None:
        """Record warnings (written with the next flush)."""
        warnings = list(warnings)
        self._warnings.extend(warnings)
        self.warnings = (*self.warnings, *warnings)

    def add_attrs(self, attrs: Mapping[str, str]) -> None:
        """More text attributes of the run (written with the next flush)."""
        self._attrs.update(attrs)

    def flush(self) -> None:
        """Open the file, append what is pending, commit, close."""
        self._last_flush = time.monotonic()
        if not self._pending and not self._warnings and not self._attrs:
            return
        if self._broken:
            raise WriteError(
                "a write failed before: the run file is left as it was", path=str(self.path)
            )
        block = Frames.concat(self._pending)
        warns, self._warnings = self._warnings, []
        n, k = self._n, len(block)
        # HDF5 does not survive a write that fails half way: make sure of the room first
        width = max(self._width, block.data.shape[1])
        ensure_room(self.path.parent, (k + 2 * _CHUNK_ROWS) * (14 + width), self.path)
        try:
            with h5py_module().File(self.path, "a") as f:
                g = f["frames"]
                if k:
                    for name in FRAME_FIELDS:
                        g[name].resize((n + k,))
                        g[name][n:] = getattr(block, name)
                    width = max(self._width, block.data.shape[1])
                    if width != self._width:
                        g["data"].resize((g["data"].shape[0], width))
                        self._width = width
                    g["data"].resize((n + k, width))
                    g["data"][n:, : block.data.shape[1]] = block.data
                if warns:
                    w = f["warnings"]
                    m = w["code"].shape[0]
                    for name in ("code", "message"):
                        w[name].resize((m + len(warns),))
                        w[name][m:] = [getattr(x, name) for x in warns]
                f.attrs.update(self._attrs)
                f.flush()
                f.attrs["frames_committed"] = n + k
        except OSError as exc:
            self._pending = [block]  # keep them: a later flush may succeed
            self._warnings = warns + self._warnings
            if _lock_busy(exc):  # another program holds the lock a moment: retried
                raise RecordingError(
                    f"cannot append to the run file: {exc}", path=str(self.path)
                ) from None
            self._broken = True  # never touch a file HDF5 failed to write again
            raise write_error(exc, self.path, "cannot append to the run file") from exc
        self._pending = []
        self._attrs = {}
        self._n = n + k
        self._last_success = time.monotonic()

    def close(self, streams: RunStreams | None = None) -> None:
        """Flush, add the decoded streams (if given), mark the run complete.  Idempotent."""
        if self._closed:
            return
        self.flush()
        self._closed = True
        if self._broken:
            return
        need = 0 if streams is None else sum(_stream_bytes(s) for s in streams.nodes.values())
        ensure_room(self.path.parent, need, self.path)
        try:
            with h5py_module().File(self.path, "a") as f:
                if streams is not None:
                    write_streams(f, streams)
                self.end_time = utc_now()
                f.attrs["end_time"] = self.end_time
                f.attrs["complete"] = True
            seal(self.path)
        except OSError as exc:
            self._broken = True
            raise write_error(exc, self.path, "cannot close the run file") from exc

    def discard(self) -> None:
        """Close and remove the run file: for a run that never received a frame."""
        self._closed = True
        self._pending = []
        self.path.unlink(missing_ok=True)

    def __enter__(self) -> RunWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _lock_busy(exc: OSError) -> bool:
    """The file could not be opened (another program holds its lock, or has it open):
    nothing was written, so a later flush may try again."""
    text = str(exc).lower()
    return ("lock" in text or "open" in text) and "space" not in text


def _stream_bytes(s: Any) -> int:
    """What a node's decoded stream takes uncompressed [B] (a bound on what it writes)."""
    names = ("index", "segment", "counts", "mark_position", "mark_segment", "mark_rev")
    return sum(int(getattr(s, n).nbytes) for n in names) + 8 * len(s.index)


def write_streams(f: Any, streams: RunStreams) -> None:
    """Write the decoded per-node streams into an open run file (``/nodes``)."""
    if "nodes" in f:
        del f["nodes"]
    nodes = f.create_group("nodes")
    for n, s in streams.nodes.items():
        g = nodes.create_group(str(n))
        for name in ("index", "segment", "counts", "mark_position", "mark_segment", "mark_rev"):
            g.create_dataset(name, data=getattr(s, name), **_COMPRESSED)
        if s.accel_m_s2 is not None:
            g.create_dataset("accel_m_s2", data=s.accel_m_s2, **_COMPRESSED)
        for name in (
            "frames",
            "samples",
            "invalid_samples",
            "lost_frames",
            "duplicate_frames",
            "status_frames",
            "lost_marks",
            "segments",
        ):
            g.attrs[name] = getattr(s, name)
        g.attrs["rate_hz"] = np.nan if s.rate_hz is None else s.rate_hz
        g.attrs["scale_um_s2"] = np.nan if s.scale_um_s2 is None else s.scale_um_s2
        g.attrs["flags"] = json.dumps(list(s.flags))
    f.attrs["unknown_frames"] = streams.unknown_frames
    f.attrs["bad_frames"] = streams.bad_frames
