"""python-can logs in and out: any format python-can knows, candump ``.log`` fast.

Runs move to and from other CAN tools as python-can logs (``.log``,
``.asc``, ``.blf``, ``.trc``, ``.csv`` ...): the format follows the file
extension, as in ``can.LogReader`` and ``can.Logger``.  candump ``.log``
files, the common case, are parsed with one regular expression over the
whole text and numpy conversions (about ten times python-can's reader);
every other format goes through python-can message by message.

Only the frame (time, id, flags, payload) is kept; python-can's channel
field is not (a run is one bus).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from stand.drivers.protocol import (
    FLAG_ERROR,
    FLAG_EXTENDED,
    FLAG_FD,
    FLAG_REMOTE,
    FRAME_DLC,
    Frames,
)
from stand.errors import RecordingError

CAN_ERR_FLAG = 0x20000000
CAN_EFF_MASK = 0x1FFFFFFF
_CANDUMP = re.compile(
    rb"^[ \t]*\((-?\d+(?:\.\d*)?)\)[ \t]+(\S+)[ \t]+([0-9A-Fa-f]{1,8})#(#[0-9A-Fa-f])?"
    rb"([Rr]\d*|[0-9A-Fa-f]*)(?:[ \t]+[RrTt])?[ \t]*\r?$",
    re.MULTILINE,
)


def _with_line(path: Path, text: bytes) -> RecordingError:
    """The first line of ``text`` that is not a candump frame, as an error."""
    for number, line in enumerate(text.split(b"\n"), start=1):
        if line.strip() and not _CANDUMP.match(line):
            shown = line.strip()[:60].decode("utf-8", "replace")
            return RecordingError(
                f"not a candump frame line (expected '(TIME) CHANNEL ID#DATA'): {shown!r}",
                path=str(path),
                line=number,
            )
    return RecordingError("not a candump log", path=str(path))  # pragma: no cover


def read_candump(path: Path) -> Frames:
    """Read a candump ``.log`` (``candump -L`` format, as python-can writes it).

    Raises
    ------
    RecordingError
        Naming the file and the first line that is not a frame.
    """
    text = path.read_bytes()
    rows = _CANDUMP.findall(text)
    lines = sum(1 for line in text.split(b"\n") if line.strip())
    if len(rows) != lines:
        raise _with_line(path, text)
    n = len(rows)
    if n == 0:
        return Frames.empty()
    t_str, _channels, id_str, fd_str, data_str = zip(*rows, strict=True)
    t_s = np.array(t_str).astype(np.float64)
    raw_id = np.array([int(s, 16) for s in id_str], dtype=np.int64)
    extended = np.fromiter((len(s) > 3 for s in id_str), dtype=bool, count=n)
    error = (raw_id & CAN_ERR_FLAG) != 0
    fd = np.fromiter((len(s) > 0 for s in fd_str), dtype=bool, count=n)
    remote = np.fromiter((s[:1] in (b"R", b"r") for s in data_str), dtype=bool, count=n)
    lengths = np.fromiter((len(s) for s in data_str), dtype=np.int64, count=n)
    if not remote.any() and (lengths == 2 * FRAME_DLC).all():  # the common case, in one go
        data = np.frombuffer(bytes.fromhex(b"".join(data_str).decode()), np.uint8).reshape(n, 8)
        dlc = np.full(n, FRAME_DLC, np.uint8)
    else:
        width = max(FRAME_DLC, int(lengths.max()) // 2)
        data = np.zeros((n, width), np.uint8)
        dlc = np.zeros(n, np.uint8)
        for i, s in enumerate(data_str):
            if remote[i]:
                dlc[i] = int(s[1:]) if len(s) > 1 else 0
                continue
            if len(s) % 2:
                raise RecordingError(
                    f"odd number of hex digits in the data {s.decode()!r}", path=str(path)
                )
            b = bytes.fromhex(s.decode())
            data[i, : len(b)] = np.frombuffer(b, np.uint8)
            dlc[i] = len(b)
    flags = (
        np.where(extended, FLAG_EXTENDED, 0)
        | np.where(remote, FLAG_REMOTE, 0)
        | np.where(error, FLAG_ERROR, 0)
        | np.where(fd, FLAG_FD, 0)
    ).astype(np.uint8)
    return Frames(
        t_s, (raw_id & CAN_EFF_MASK).astype(np.uint32), dlc, np.ascontiguousarray(data), flags
    )


def frames_from_messages(messages: Iterable[Any]) -> Frames:
    """Frames from python-can ``Message`` objects (any iterable, e.g. a LogReader)."""
    t: list[float] = []
    ids: list[int] = []
    dlcs: list[int] = []
    flags: list[int] = []
    payloads: list[bytes] = []
    for m in messages:
        t.append(m.timestamp)
        ids.append(m.arbitration_id)
        dlcs.append(m.dlc)
        flags.append(
            (FLAG_EXTENDED if m.is_extended_id else 0)
            | (FLAG_REMOTE if m.is_remote_frame else 0)
            | (FLAG_ERROR if m.is_error_frame else 0)
            | (FLAG_FD if m.is_fd else 0)
        )
        payloads.append(bytes(m.data))
    return Frames.from_lists(t, ids, dlcs, flags, payloads)


def messages_from_frames(frames: Frames, channel: str | None = None) -> Iterator[Any]:
    """python-can ``Message`` objects for the frames (the payload cut to each DLC)."""
    import can

    data = frames.data.tobytes()
    width = frames.data.shape[1]
    for i, (t, cid, dlc, fl) in enumerate(
        zip(
            frames.t_s.tolist(),
            frames.can_id.tolist(),
            frames.dlc.tolist(),
            frames.flags.tolist(),
            strict=True,
        )
    ):
        remote = bool(fl & FLAG_REMOTE)
        yield can.Message(
            timestamp=t,
            arbitration_id=cid,
            is_extended_id=bool(fl & FLAG_EXTENDED),
            is_remote_frame=remote,
            is_error_frame=bool(fl & FLAG_ERROR),
            is_fd=bool(fl & FLAG_FD),
            dlc=dlc,
            data=None if remote else data[i * width : i * width + dlc],
            channel=channel,
            check=False,
        )


def read_log(path: str | Path) -> Frames:
    """Read any python-can log (format by extension); candump ``.log`` takes the fast path.

    Raises
    ------
    RecordingError
        The file is missing, of an unknown format, or not a readable log.
    """
    path = Path(path)
    if not path.is_file():
        raise RecordingError("no such file", path=str(path))
    if path.suffix.lower() == ".log":
        return read_candump(path)
    import can

    try:
        with can.LogReader(path) as reader:
            frames = frames_from_messages(reader)
            size = getattr(reader, "file_size", None)  # BLF: the header says how long it is
            if isinstance(size, int) and size > path.stat().st_size:
                raise RecordingError(
                    f"truncated: the BLF header says {size} bytes, the file has "
                    f"{path.stat().st_size} ({len(frames)} frames readable)",
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
    """Write the frames as a python-can log, the format by the extension."""
    import can

    path = Path(path)
    try:
        with can.Logger(path) as logger:
            for m in messages_from_frames(frames):
                logger.on_message_received(m)
    except ValueError as exc:
        raise RecordingError(f"cannot write this log format: {exc}", path=str(path)) from None
    except OSError as exc:
        raise RecordingError(f"cannot write: {exc.strerror or exc}", path=str(path)) from None
