"""candump ``.log`` files read fast: numpy columns, a regular expression for the rest.

Lines of one length and layout are columns of one 2-D byte array, so every
field is a slice (:func:`_fast_candump`, in blocks of :data:`CANDUMP_BLOCK`
bytes); epoch time stamps (candump -l, python-can's logger) are parsed as
two integers, no precision lost.  A file with anything unusual (remote or
CAN FD frames, odd spacing, a bad line) goes through one regular expression,
which also names the first bad line.  Part of :mod:`stand.drivers.runs.logs`.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from stand.core import Diagnostic
from stand.drivers.frames import (
    FLAG_ERROR,
    FLAG_EXTENDED,
    FLAG_FD,
    FLAG_REMOTE,
    FRAME_DLC,
    MAX_PAYLOAD,
    Frames,
)
from stand.drivers.runs.budget import log_budget, slow_text_budget
from stand.errors import RecordingError, UnusualLogError

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


EXACT_TICKS = 1 << 53
"""A stamp's integer count of its last digit below this is an exact double."""
CANDUMP_BLOCK = 1 << 23
"""Bytes of a candump log parsed at a time (whole lines): bounds the parser's memory."""
_HEX = np.full(256, 255, np.uint8)
for _k, _c in enumerate(b"0123456789abcdef"):
    _HEX[_c] = _k
    _HEX[bytes([_c]).upper()[0]] = _k
_DIGIT = np.full(256, 255, np.uint8)
_DIGIT[48:58] = np.arange(10, dtype=np.uint8)


def _hex_value(cols: np.ndarray) -> np.ndarray | None:
    """The hex digits of each row as one integer (None if any is not a hex digit)."""
    nib = _HEX[cols]
    if (nib == 255).any():
        return None
    out = np.zeros(len(cols), np.int64)
    for k in range(cols.shape[1]):
        out = out * 16 + nib[:, k]
    return out


def _group(block: np.ndarray) -> tuple[np.ndarray, ...] | None:
    """Parse lines of one length and layout (rows of ``block``); None if any differs."""
    first = block[0].tobytes()
    close, h = first.find(b")"), first.find(b"#")
    sp1 = close + 1
    sp2 = first.rfind(b" ", 0, h)
    end = first.find(b" ", h)
    end = len(first) if end < 0 else end
    dot = first.find(b".", 0, close)
    if first[:1] != b"(" or not 0 < dot < close or sp2 <= sp1 or first[sp1 : sp1 + 1] != b" ":
        return None
    if (end - h - 1) % 2 or end - h - 1 > 2 * FRAME_DLC or not 3 <= h - sp2 - 1 <= 8:
        return None
    for at, char in ((0, b"("), (close, b")"), (sp1, b" "), (sp2, b" "), (h, b"#")):
        if (block[:, at] != char[0]).any():
            return None
    if end < len(first) and not (
        (block[:, end] == 32).all() and np.isin(block[:, end + 1 :], list(b"RrTt")).all()
    ):
        return None
    channel = block[:, sp1 + 1 : sp2]
    if (channel == 32).any():
        return None
    whole, frac = _DIGIT[block[:, 1:dot]], _DIGIT[block[:, dot + 1 : close]]
    if (whole == 255).any() or (frac == 255).any() or whole.shape[1] + frac.shape[1] > 18:
        return None  # a sign, or more digits than an int64 holds: the slow path
    ticks = np.zeros(len(block), np.int64)  # the stamp as an integer count of its last digit
    for k in range(whole.shape[1]):
        ticks = ticks * 10 + whole[:, k]
    for k in range(frac.shape[1]):
        ticks = ticks * 10 + frac[:, k]
    if int(ticks.max()) >= EXACT_TICKS:
        return None  # the count itself would round as a double: the slow path
    # the count and the power of ten are exact doubles, so this is one correctly rounded
    # division: the double nearest the decimal, exactly what float() of the text gives
    # (epoch stamps with microseconds, 16 digits, are below 2**53)
    t_s = ticks.astype(np.float64) / float(10 ** frac.shape[1])
    can_id = _hex_value(block[:, sp2 + 1 : h])
    nib = _HEX[block[:, h + 1 : end]]
    if can_id is None or (nib == 255).any():
        return None
    data = np.zeros((len(block), FRAME_DLC), np.uint8)
    nbytes = nib.shape[1] // 2
    data[:, :nbytes] = nib[:, 0::2] * 16 + nib[:, 1::2]
    extended = np.full(len(block), h - sp2 - 1 > 3)
    return t_s, can_id, data, np.full(len(block), nbytes, np.uint8), extended


def _fast_candump(raw: np.ndarray) -> Frames | None:
    """The common candump log, parsed as byte columns; None if anything is unusual."""
    if raw.size == 0 or (raw == 13).any():
        return None
    if raw[-1] != 10:
        raw = np.append(raw, np.uint8(10))  # a last line without its newline
    nl = np.flatnonzero(raw == 10)
    starts = np.concatenate(([0], nl[:-1] + 1))
    lens = nl - starts
    if (lens == 0).any():
        return None
    parts: list[tuple[np.ndarray, tuple[np.ndarray, ...]]] = []
    for length in np.flatnonzero(np.bincount(lens)).tolist():  # the lengths there are
        rows = np.flatnonzero(lens == length)
        block = raw[starts[rows].astype(np.int64)[:, None] + np.arange(length)]
        # lines of one length may still differ in layout: sort them by where '.', ')', '#'
        # and the last space are
        layout = np.argmax(block == 41, axis=1) * 4096 + np.argmax(block == 35, axis=1)
        layout = layout * 4096 + np.argmax(block == 46, axis=1)
        layout = layout * 4096 + np.argmax(block[:, ::-1] == 32, axis=1)
        if (layout == layout[0]).all():  # the common case: one layout, no copy
            groups = [(rows, block)]
        else:
            groups = [(rows[layout == k], block[layout == k]) for k in np.unique(layout).tolist()]
        for at, lines in groups:
            got = _group(lines)
            if got is None:
                return None
            parts.append((at, got))
    order = np.argsort(np.concatenate([r for r, _ in parts]), kind="stable")
    t_s, raw_id, data, dlc, ext = (
        np.concatenate([g[i] for _, g in parts])[order] for i in range(5)
    )
    error = (raw_id & CAN_ERR_FLAG) != 0
    flags = (np.where(ext, FLAG_EXTENDED, 0) | np.where(error, FLAG_ERROR, 0)).astype(np.uint8)
    return Frames(t_s, (raw_id & CAN_EFF_MASK).astype(np.uint32), dlc, data, flags)


def iter_candump_fast(path: Path) -> Iterator[Frames]:
    """A candump log in blocks of frames, read :data:`CANDUMP_BLOCK` bytes at a time.

    Each block of whole lines goes through :func:`_fast_candump`.  Raises
    :class:`UnusualLogError` (perhaps after some blocks) when one holds anything
    unusual: the caller then reads the file with :func:`_read_candump_text`.
    """
    try:
        with path.open("rb") as f:
            carry = b""
            while True:
                chunk = f.read(CANDUMP_BLOCK)
                text = carry + chunk
                if not text:
                    return
                cut = text.rfind(b"\n") + 1 if chunk else len(text)
                if cut == 0:  # no line end in a whole block
                    raise UnusualLogError(str(path))
                carry = text[cut:]
                got = _fast_candump(np.frombuffer(text[:cut], np.uint8))
                if got is None:
                    raise UnusualLogError(str(path))
                yield got
                if not chunk:
                    return
    except OSError as exc:
        raise RecordingError(f"cannot read ({exc.strerror or exc})", path=str(path)) from exc


def iter_candump(path: Path, warn: list[Diagnostic] | None = None) -> Iterator[Frames]:
    """A candump log in blocks (all at once, through the regular expression, if unusual)."""
    blocks: list[Frames] = []
    try:
        blocks.extend(iter_candump_fast(path))
    except UnusualLogError:
        blocks = [_read_candump_text(path, warn)]
    yield from blocks


def read_candump(path: Path, warn: list[Diagnostic] | None = None) -> Frames:
    """Read a candump ``.log`` (``candump -L`` format, as python-can writes it).

    The common case in blocks of whole lines, as byte columns
    (:func:`_fast_candump`); anything unusual through the regular expression
    (:func:`_read_candump_text`).

    Raises
    ------
    RecordingError
        Naming the file and the first line that is not a frame.
    TooLargeError
        More frames than this machine has memory for (by the file's size).
    """

    log_budget(path)
    return Frames.concat(list(iter_candump(path, warn)))


def _read_candump_text(path: Path, warn: list[Diagnostic] | None = None) -> Frames:
    """A candump log read whole by the regular expression (refused first when this machine
    has no memory for it: :func:`stand.drivers.runs.budget.slow_text_budget`)."""

    slow_text_budget(path)
    return _read_candump_whole(path, warn)


def _whole_lines(path: Path, text: bytes, warn: list[Diagnostic] | None) -> tuple[bytes, int]:
    """The text without a last line cut short (no newline after it, as a killed candump
    leaves it; said in ``warn``), and its count of non-empty lines."""
    lines = sum(1 for line in text.split(b"\n") if line.strip())
    cut = text.rfind(b"\n") + 1
    last = text[cut:]
    if last.strip() and text[:cut].strip():
        match = _CANDUMP.match(last)
        data = b"" if match is None else match.group(5)
        if match is None or (data[:1] not in (b"R", b"r") and len(data) % 2):
            if warn is not None:
                where = f"{path}:{lines}"
                warn.append(
                    Diagnostic("partial_line", f"{where}: the last line is cut short: left out")
                )
            return text[:cut], lines - 1
    return text, lines


def _payloads(
    path: Path, data_str: tuple[bytes, ...], remote: np.ndarray, lengths: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Each frame's data bytes and length from its hex column: all 8-byte frames in one go
    (the common case), else frame by frame (remote frames, short frames, CAN FD)."""
    n = len(data_str)
    if not remote.any() and (lengths == 2 * FRAME_DLC).all():
        data = np.frombuffer(bytes.fromhex(b"".join(data_str).decode()), np.uint8).reshape(n, 8)
        return data, np.full(n, FRAME_DLC, np.uint8)
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
    return data, dlc


def _read_candump_whole(path: Path, warn: list[Diagnostic] | None = None) -> Frames:
    """Read a candump ``.log`` (``candump -L`` format, as python-can writes it).

    A last line cut short (no newline after it, as a killed candump leaves it)
    is left out with a warning; any other line that is not a frame is refused.

    Raises
    ------
    RecordingError
        Naming the file and the first line that is not a frame.
    """
    text, lines = _whole_lines(path, path.read_bytes(), warn)
    rows = _CANDUMP.findall(text)
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
    dlcs = lengths // 2
    for r in np.flatnonzero(remote):  # a remote frame says its length: R<dlc>
        dlcs[r] = int(data_str[r][1:] or 0)
    if dlcs.max() > MAX_PAYLOAD:
        bad = int(np.argmax(dlcs > MAX_PAYLOAD))
        line = [k for k, ln in enumerate(text.split(b"\n"), 1) if ln.strip()][bad]
        raise RecordingError(
            f"a frame of {int(dlcs[bad])} data bytes: CAN carries at most {MAX_PAYLOAD}",
            path=str(path),
            line=line,
        )
    data, dlc = _payloads(path, data_str, remote, lengths)
    flags = (
        np.where(extended, FLAG_EXTENDED, 0)
        | np.where(remote, FLAG_REMOTE, 0)
        | np.where(error, FLAG_ERROR, 0)
        | np.where(fd, FLAG_FD, 0)
    ).astype(np.uint8)
    return Frames(
        t_s, (raw_id & CAN_EFF_MASK).astype(np.uint32), dlc, np.ascontiguousarray(data), flags
    )
