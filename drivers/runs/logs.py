"""python-can logs in and out: any format python-can knows, candump ``.log`` fast.

Runs move to and from other CAN tools as python-can logs (``.log``,
``.asc``, ``.blf``, ``.trc``, ``.csv`` ...): the format follows the file
extension, as in ``can.LogReader`` and ``can.Logger``.  candump ``.log``
files, the common case, are read by :mod:`stand.drivers.runs.candump` (numpy
columns, fast); every other format goes through python-can message by
message.

Only the frame (time, id, flags, payload) is kept; python-can's channel
field is not (a run is one bus).
"""

from __future__ import annotations

import re
import sqlite3
import time
from collections.abc import Iterator
from contextlib import ExitStack
from pathlib import Path
from typing import Any

from stand.core import Diagnostic
from stand.drivers.frames import Frames, frames_from_messages, messages_from_frames
from stand.drivers.runs.candump import iter_candump, iter_candump_fast
from stand.drivers.runs.candump import read_candump as read_candump  # re-exported
from stand.errors import RecordingError
from stand.files import check_input, check_timestamps


def iter_log(
    path: str | Path, *, fast: bool = False, warn: list[Diagnostic] | None = None
) -> Iterator[Frames]:
    """Any python-can log in blocks of frames (candump in blocks; other formats whole).

    ``fast``: a candump log block by block as it is read, raising
    :class:`UnusualLogError` if a block needs the slow path (start again without).
    ``warn`` collects what the reader read around (a cut line, a short BLF, lines that
    are not frames).
    """
    path = Path(path)
    check_input(path)
    if path.suffix.lower() == ".log":
        yield from (iter_candump_fast(path) if fast else iter_candump(path, warn))
    else:
        yield read_log(path, warn)


_TEXT_LOG_LINE = {
    # a line python-can's reader may take: a header or comment, or a timestamped event
    ".asc": re.compile(
        r"^\s*($|//|date |base |internal events|no internal events|// version|"
        r"Begin Triggerblock|End TriggerBlock|\d+(\.\d+)?\s)",
        re.IGNORECASE,
    ),
    ".trc": re.compile(r"^\s*($|;|\d+\)?\s)"),
    ".csv": re.compile(r"^\s*($|timestamp,|-?\d+(\.\d*)?(e-?\d+)?,)", re.IGNORECASE),
}


def _foreign_lines(path: Path) -> Diagnostic | None:
    """Lines of a text log (.asc .trc .csv) that python-can's reader skips without a word:
    counted, with the first one's number."""
    shape = _TEXT_LOG_LINE.get(path.suffix.lower())
    if shape is None:
        return None
    bad = [
        k
        for k, line in enumerate(path.read_text("utf-8", "replace").splitlines(), start=1)
        if not shape.match(line)
    ]
    if not bad:
        return None
    return Diagnostic(
        "skipped_lines",
        f"{path}:{bad[0]}: {len(bad)} line(s) that are not frames were left out",
        float(len(bad)),
    )


def _reader(path: Path, stack: ExitStack) -> Any:
    """python-can's reader of the file, given a file this function opened where the reader
    takes one (binary or text): its constructor may raise on a bad header, and the file it
    opened itself would then be left open until the garbage collector's warning."""
    import locale

    import can
    from can.io.generic import BinaryIOMessageReader, TextIOMessageReader
    from can.io.player import MESSAGE_READERS

    cls = MESSAGE_READERS.get(path.suffix.lower())
    if cls is not None and issubclass(cls, BinaryIOMessageReader):
        return cls(stack.enter_context(path.open("rb")))
    if cls is not None and issubclass(cls, TextIOMessageReader):
        encoding = locale.getpreferredencoding(False)  # as python-can opens it itself
        return cls(stack.enter_context(path.open(encoding=encoding)))
    return can.LogReader(path)


def read_log(path: str | Path, warn: list[Diagnostic] | None = None) -> Frames:
    """Read any python-can log (format by extension); candump ``.log`` takes the fast path.

    Raises
    ------
    RecordingError
        The file is missing, of an unknown format, or not a readable log.
    """
    path = Path(path)
    check_input(path)
    if path.suffix.lower() == ".log":
        return read_candump(path, warn)
    try:
        with ExitStack() as stack:
            reader = stack.enter_context(_reader(path, stack))
            frames = frames_from_messages(reader)
            check_timestamps(frames.t_s, path)
            size = getattr(reader, "file_size", None)  # BLF: the header says how long it is
            if isinstance(size, int) and size > path.stat().st_size and not len(frames):
                raise RecordingError(
                    f"truncated: the BLF header says {size} bytes, the file has "
                    f"{path.stat().st_size} and no frame is readable",
                    path=str(path),
                )
            if isinstance(size, int) and size > path.stat().st_size and warn is not None:
                warn.append(
                    Diagnostic(
                        "truncated_log",
                        f"{path}: the BLF header says {size} bytes, the file has "
                        f"{path.stat().st_size}: read the {len(frames)} frames it holds",
                    )
                )
            skipped = _foreign_lines(path) if warn is not None or not len(frames) else None
            if skipped is not None and warn is not None:
                warn.append(skipped)
            if not len(frames) and path.stat().st_size > 0:
                raise RecordingError(
                    f"no CAN frame in its {path.stat().st_size} bytes (python-can's "
                    f"{path.suffix} reader skips what it cannot read)",
                    path=str(path),
                )
            return frames
    except RecordingError:
        raise
    except ValueError as exc:
        if "unknown" in str(exc).lower() or "no read support" in str(exc).lower():
            raise RecordingError(
                f"unknown log format {path.suffix!r} (expected .h5, or a python-can log: "
                ".log .asc .blf .trc .csv ...)",
                path=str(path),
            ) from None
        raise RecordingError(f"not a readable {path.suffix} log: {exc}", path=str(path)) from None
    except Exception as exc:  # python-can's readers raise whatever their parser hits
        raise RecordingError(
            f"not a readable {path.suffix} log ({type(exc).__name__}: {exc})", path=str(path)
        ) from None


def write_log(frames: Frames, path: str | Path) -> None:
    """Write the frames as a python-can log, the format by the extension.

    python-can's SQLite writer (``.db``) writes from a thread that, once told
    to stop, writes one more batch and drops the rest of its queue (it kept
    2004 of 21588 frames): its queue is let drain before it is stopped, and the
    rows are counted after.
    """
    import can

    path = Path(path)
    try:
        with can.Logger(path) as logger:
            for m in messages_from_frames(frames):
                logger.on_message_received(m)
            queue = getattr(logger, "buffer", None)
            deadline = time.monotonic() + 60.0
            while queue is not None and not queue.empty() and time.monotonic() < deadline:
                time.sleep(0.01)
    except NotImplementedError as exc:  # a format whose optional package is missing
        extra = {".mf4": "mf4"}.get(path.suffix.lower())
        hint = f": pip install 'python-can[{extra}]'" if extra else ""
        raise RecordingError(
            f"cannot write {path.suffix} logs here{hint} ({exc})", path=str(path)
        ) from None
    except ValueError as exc:
        raise RecordingError(f"cannot write this log format: {exc}", path=str(path)) from None
    if path.suffix.lower() == ".db":
        _check_db_rows(path, len(frames))


def _check_db_rows(path: Path, expected: int) -> None:
    """Refuse a ``.db`` log that does not hold every frame written to it."""

    with sqlite3.connect(path) as conn:
        (rows,) = conn.execute("SELECT COUNT(*) FROM messages").fetchone()
    conn.close()
    if rows != expected:
        raise RecordingError(
            f"the SQLite writer kept {rows} of {expected} frames: not written", path=str(path)
        )
