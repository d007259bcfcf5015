"""HDF5 run files, written as frames arrive, readable after any crash.

A run file holds everything needed to reprocess a run::

    bytes 0..511     the seal (:mod:`stand.drivers.runs.seal`): the SHA-256 of every
                     byte after it, written when the run is closed
    /                attrs: format = "rotor-stand-run", format_version = 1,
                     software, start_time (ISO 8601, UTC), source (the bus),
                     config_toml (the configuration text used, or ""),
                     config_sha256 (its digest, checked on every read),
                     frames_committed, complete, end_time; optional
                     job_json (serial, order, operator, note) and
                     influence_matrix_json (the matrix the run was solved with)
    /frames/...      every dataset chunked, with HDF5's Fletcher32 checksum
    /frames/t_s      float64 (n,)     host receive time [s]
    /frames/can_id   uint32  (n,)
    /frames/dlc      uint8   (n,)
    /frames/flags    uint8   (n,)     1 extended, 2 remote, 4 error, 8 CAN FD
    /frames/data     uint8   (n, 8)   (n, 64) once a long CAN FD frame came
    /warnings/code, /warnings/message  (variable-length UTF-8 strings)
    /nodes/<n>/...   the decoded stream of node n (written at the end):
                     index, segment, accel_m_s2, counts, mark_position,
                     mark_segment, mark_rev; attrs rate_hz, scale_um_s2, ...

**Crash safety.**  The writer keeps the file *closed* between flushes: every
``flush_interval_s`` (0.5 s) it opens the file, appends the frames that
came, flushes, then raises ``frames_committed`` and closes it.  A kill at
any moment leaves a file that plain ``h5py.File(path)`` opens, and
``frames_committed`` rows of every ``/frames`` dataset are complete: at
most the last interval is lost.  (HDF5's SWMR mode was tried and refused:
after a crash the file only opens in SWMR-read mode or after ``h5clear``.)
The file is created under a temporary name and renamed, so a half-made
header never sits under the run's name.  ``tests/drivers/test_recording.py`` kills a
recording process at random times and reopens the file.

**The seal.**  A run the writer closed is read only if its bytes still have
the SHA-256 sealed at closing; a run without one (cut short by a crash) is
read by a child process with a time limit first, so that a damaged file
HDF5 would never finish reading is refused instead of hanging the command.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.core import Diagnostic
from stand.drivers.family import FrameBuilder
from stand.drivers.frames import Frames
from stand.drivers.runs.budget import frames_budget, log_budget
from stand.drivers.runs.logs import iter_log, read_log, write_log
from stand.drivers.runs.run_format import (
    CARRIED_ATTRS,
    FRAME_FIELDS,
    JOB_ATTR,
    MATRIX_ATTR,
    RUN_FORMAT,
    RUN_FORMAT_VERSION,
    RUN_SUFFIXES,
    STAND_ATTR,
    Recording,
    config_digest,
    h5py_module,
)
from stand.drivers.runs.run_writer import RunWriter
from stand.drivers.runs.seal import read_in_child, seal_state
from stand.drivers.streams import RunStreams
from stand.errors import RecordingError, StandError, UnusualLogError
from stand.files import check_input, check_timestamps, output

__all__ = [  # the run file's names (stand.drivers.runs.run_format) are read here too
    "CARRIED_ATTRS",
    "JOB_ATTR",
    "MATRIX_ATTR",
    "RUN_FORMAT",
    "RUN_FORMAT_VERSION",
    "RUN_SUFFIXES",
    "STAND_ATTR",
    "Recording",
    "config_digest",
    "is_run_file",
    "read_recording",
    "read_run",
    "read_streams",
    "write_recording",
]


def _attr(f: Any, name: str, kind: type, path: Path, default: Any = None) -> Any:
    """A root attribute of the expected kind (int: a whole number; str: text), else refused."""
    if name not in f.attrs:
        if default is not None:
            return default
        raise RecordingError(f"the attribute {name!r} is missing", path=str(path))
    v = f.attrs[name]
    if isinstance(v, np.generic) and np.ndim(v) == 0:
        v = v.item()
    if kind is int and isinstance(v, int) and not isinstance(v, bool):
        return v
    if kind is str and isinstance(v, str):
        return v
    want = "a whole number" if kind is int else "text"
    raise RecordingError(f"the attribute {name!r} is {str(v)[:40]!r}, not {want}", path=str(path))


def _member(group: Any, name: str, path: Path, where: str) -> Any:
    """A member stored in this file: links (soft, external) and external storage refused."""
    h5py = h5py_module()
    link = group.get(name, getlink=True)
    if link is None:
        raise RecordingError(f"{where}/{name} is missing", path=str(path))
    if not isinstance(link, h5py.HardLink):
        raise RecordingError(
            f"{where}/{name} is an HDF5 {type(link).__name__}: links (soft, external) are "
            "refused, a run file holds its own data",
            path=str(path),
        )
    obj = group[name]
    if isinstance(obj, h5py.Dataset) and obj.external:
        raise RecordingError(
            f"{where}/{name} keeps its data in external storage ({obj.external[0][0]}): refused",
            path=str(path),
        )
    return obj


def _frame_dataset(g: Any, name: str, rows: int, path: Path) -> Any:
    """One /frames dataset, checked: its shape, its kind, and that it holds its rows."""
    h5py = h5py_module()
    d = _member(g, name, path, "/frames")
    ndim = 2 if name == "data" else 1
    if not isinstance(d, h5py.Dataset) or d.ndim != ndim:
        raise RecordingError(f"/frames/{name} is not a {ndim}-D dataset", path=str(path))
    kind = "f" if name == "t_s" else "u"
    if d.dtype.kind != kind and not (kind == "u" and d.dtype.kind == "i"):
        raise RecordingError(f"/frames/{name} holds {d.dtype}, not the run file's", path=str(path))
    n = min(rows, d.shape[0])
    need = n * d.dtype.itemsize * (d.shape[1] if ndim == 2 else 1)
    if d.id.get_storage_size() < need:  # unwritten chunks would read as zeros
        raise RecordingError(
            f"/frames/{name} declares {d.shape[0]} rows but holds "
            f"{d.id.get_storage_size()} bytes of the {need} they need: truncated or crafted",
            path=str(path),
        )
    return d


def _open_run(f: Any, path: Path) -> tuple[int, dict[str, Any], tuple[Diagnostic, ...]]:
    """Check an open run file; its committed frame count, attributes and warnings."""
    h5py = h5py_module()
    if f.attrs.get("format") != RUN_FORMAT:
        raise RecordingError(
            f"an HDF5 file but not a run file (format attribute "
            f"{str(f.attrs.get('format'))[:40]!r}, expected {RUN_FORMAT!r})",
            path=str(path),
        )
    version = _attr(f, "format_version", int, path)
    if version > RUN_FORMAT_VERSION:
        raise RecordingError(
            f"run file format {version} is newer than this software reads ({RUN_FORMAT_VERSION})",
            path=str(path),
        )
    config = _attr(f, "config_toml", str, path, "")
    stored = _attr(f, "config_sha256", str, path, "") if "config_sha256" in f.attrs else None
    if stored is not None and stored != config_digest(config):
        raise RecordingError(
            "the stored configuration does not match its SHA-256 digest: the file was "
            "altered or damaged (solve it with --config CFG)",
            path=str(path),
        )
    committed = _attr(f, "frames_committed", int, path)
    if committed < 0:
        raise RecordingError(f"the attribute 'frames_committed' is {committed}", path=str(path))
    g = _member(f, "frames", path, "")
    if not isinstance(g, h5py.Group):
        raise RecordingError("/frames is not a group", path=str(path))
    shapes = [_frame_dataset(g, k, committed, path).shape[0] for k in (*FRAME_FIELDS, "data")]
    n = min([committed, *shapes])
    meta = {k: (v.item() if isinstance(v, np.generic) else v) for k, v in f.attrs.items()}
    w = _member(f, "warnings", path, "")
    codes_d, msgs_d = (_member(w, k, path, "/warnings") for k in ("code", "message"))
    if any(not h5py.check_string_dtype(d.dtype) for d in (codes_d, msgs_d)):
        raise RecordingError("/warnings holds something other than text", path=str(path))
    m = min(codes_d.shape[0], msgs_d.shape[0])
    codes, msgs = codes_d.asstr()[:m], msgs_d.asstr()[:m]
    warnings = tuple(Diagnostic(str(c), str(s)) for c, s in zip(codes, msgs, strict=True))
    return n, meta, warnings


def _unreadable(exc: Exception, path: Path) -> RecordingError:
    """A run file HDF5 cannot read, in one line (a failed checksum said as such)."""
    if "filter" in str(exc).lower():
        return RecordingError(
            "a block of frames fails its Fletcher32 checksum: the file was altered or damaged",
            path=str(path),
        )
    return RecordingError(f"not a readable run file ({exc})", path=str(path))


def _frame_rows(f: Any, lo: int, hi: int, t_s: NDArray[np.float64] | None = None) -> Frames:
    """Frames ``lo:hi`` of the file (their times cut from ``t_s`` if given: all of them)."""
    g = f["frames"]
    cols = {k: g[k][lo:hi] for k in FRAME_FIELDS if k != "t_s" or t_s is None}
    times = t_s[lo:hi] if t_s is not None else cols["t_s"].astype(np.float64, copy=False)
    return Frames(  # each column as stored: a copy only where the file's type differs
        times,
        cols["can_id"].astype(np.uint32, copy=False),
        cols["dlc"].astype(np.uint8, copy=False),
        np.ascontiguousarray(g["data"][lo:hi], dtype=np.uint8),
        cols["flags"].astype(np.uint8, copy=False),
    )


def _read_run_blocks(
    path: str | Path,
    take: Callable[[Frames], None],
    rows: int | None = None,
    *,
    guard: bool = True,
    start: Callable[[dict[str, Any]], None] | None = None,
    rows_of: Callable[[], tuple[int | None, bool]] | None = None,
) -> tuple[dict[str, Any], tuple[Diagnostic, ...]]:
    """Hand a run file's committed frames to ``take``, ``rows`` at a time (None: all at once);
    return its attributes and warnings.  A file without an intact seal is read by a child
    process with a time limit first (``guard``; :mod:`stand.drivers.runs.seal`).  ``start``
    is handed the attributes before the first block (a decoder chosen by the run's config),
    and ``rows_of`` then says the block size (it overrides ``rows``) and whether the times
    are read whole first (so that the blocks' times are views of one array, for a builder
    that keeps them as they are).

    Raises
    ------
    RecordingError
        Not an HDF5 file, truncated beyond use, not a run file, a failed checksum, a
        broken seal, or a file HDF5 does not finish reading.
    """
    p = Path(path)
    check_input(p)
    try:
        state = seal_state(p) if guard else "intact"
    except OSError as exc:
        raise _unreadable(exc, p) from exc
    if state != "intact":
        read_in_child(p)
    meta, warnings = _read_checked(p, take, rows, start, rows_of)
    if state == "broken":
        raise RecordingError(
            "its bytes no longer match the SHA-256 sealed when the run was closed: the "
            "file was altered or damaged since",
            path=str(p),
        )
    return meta, warnings


def _read_checked(
    p: Path, take: Callable[[Frames], None], rows: int | None,
    start: Callable[[dict[str, Any]], None] | None = None,
    rows_of: Callable[[], tuple[int | None, bool]] | None = None,
) -> tuple[dict[str, Any], tuple[Diagnostic, ...]]:  # fmt: skip
    try:
        # without HDF5's lock, so that reading a run being recorded never blocks its writer
        with h5py_module().File(p, "r", locking=False) as f:
            n, meta, warnings = _open_run(f, p)
            if start is not None:
                start(meta)
            whole = True
            if rows_of is not None:
                rows, whole = rows_of()
            frames_budget(n, str(p))
            step = max(n, 1) if rows is None else rows
            # in blocks: the times read whole, once, so that the blocks' times are views of
            # one array, which the streams then take as it is (no copy of the run's length)
            t_s = None
            if n > step and whole:
                t_s = f["frames"]["t_s"][:n].astype(np.float64, copy=False)
            for lo in range(0, n, step):
                block = _frame_rows(f, lo, min(lo + step, n), t_s)
                check_timestamps(block.t_s, p, lo)
                take(block)
    except StandError:  # the file's own refusal, or the config the run carries refused
        raise
    except (
        OSError,
        KeyError,
        ValueError,
        RuntimeError,
        TypeError,
    ) as exc:  # h5py's, whatever the file holds
        raise _unreadable(exc, p) from exc
    return meta, warnings


def read_run(path: str | Path, *, guard: bool = True) -> Recording:
    """Read an HDF5 run file (complete, or cut short by a crash); ``guard=False`` skips the
    seal and the child's read (the child itself uses it)."""
    blocks: list[Frames] = []
    meta, warnings = _read_run_blocks(path, blocks.append, guard=guard)
    return Recording(str(path), Frames.concat(blocks), meta, warnings)


def read_streams(
    path: str | Path,
    choose: Callable[[dict[str, Any]], FrameBuilder],
    *,
    strict_status: bool = True,
) -> tuple[Recording, RunStreams]:
    """A recording's streams, read once and decoded once in blocks (bounded memory).

    ``choose`` is handed the run file's attributes (a log: none) before its first block
    and returns the builder that decodes it (its family's, by the config the run carries
    or the one given: ``stand.solve.acquisition``).  The returned :class:`Recording` has
    the file's attributes and warnings but no frames: they went into the streams block by
    block and were let go.
    """

    chosen: list[FrameBuilder] = []

    def start(meta: dict[str, Any]) -> None:
        chosen[:] = [choose(meta)]

    if is_run_file(path):
        meta, warnings = _read_run_blocks(
            path, lambda b: chosen[0].add(b), None, start=start,
            rows_of=lambda: (chosen[0].read_rows, chosen[0].keeps_times),
        )  # fmt: skip
        rec = Recording(str(path), Frames.empty(), meta, warnings)
    else:
        warn: list[Diagnostic] = []
        if Path(path).suffix.lower() == ".log" and Path(path).is_file():
            log_budget(Path(path))
        try:  # a candump log streams block by block; anything unusual: again, the slow way
            _take_log(iter_log(path, fast=True, warn=warn), start, chosen)
        except UnusualLogError:
            chosen.clear()
            _take_log(iter_log(path, warn=warn), start, chosen)
        rec = Recording(str(path), Frames.empty(), warnings=tuple(warn))
    return rec, chosen[0].streams(strict_status=strict_status, release=True)


def _take_log(blocks: Iterable[Frames], start: Callable[[dict[str, Any]], None],
              chosen: list[FrameBuilder]) -> None:  # fmt: skip
    """A log's blocks into the builder ``start`` chooses (a log has no attributes) when the
    first block is read: the log's own faults are named before the config's."""
    for block in blocks:
        if not chosen:
            start({})
        chosen[0].add(block)
    if not chosen:
        start({})


def is_run_file(path: str | Path) -> bool:
    """Whether ``path`` names an HDF5 run file (by extension)."""
    return Path(path).suffix.lower() in RUN_SUFFIXES


def read_recording(path: str | Path) -> Recording:
    """A run file or any python-can log, by extension.

    Raises
    ------
    RecordingError
        Naming the file and what is wrong with it.
    """
    if is_run_file(path):
        return read_run(path)

    warnings: list[Diagnostic] = []
    frames = read_log(path, warnings)
    return Recording(str(path), frames, warnings=tuple(warnings))


def write_recording(
    recording: Recording,
    path: str | Path,
    streams: RunStreams | None = None,
    *,
    force: bool = False,
    inputs: Iterable[str | Path] = (),
) -> None:
    """Write frames as a run file (.h5) or a python-can log (by extension), whole: under a
    temporary name, published at ``path`` when complete (:func:`stand.files.output`).
    """

    need = len(recording.frames) * (2 * (14 + recording.frames.data.shape[1]) + 16)
    with output(path, force=force, inputs=inputs, need_bytes=need) as tmp:
        if not is_run_file(path):
            write_log(recording.frames, tmp)
            return
        meta = recording.meta
        with RunWriter(
            tmp,
            source=str(meta.get("source", f"converted from {recording.path}")),
            config_toml=str(meta.get("config_toml", "")),
            software=str(meta.get("software", "")),
            force=True,  # its own temporary file
            attrs={k: str(meta[k]) for k in CARRIED_ATTRS if meta.get(k)},
        ) as w:
            w.append(recording.frames)
            w.warn(recording.warnings)
            w.close(streams)
