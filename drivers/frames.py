"""A block of raw CAN frames as numpy columns (:class:`Frames`), whatever family of
hardware sent them: the one currency between the bus, the run files and the families'
decoders.  Our own per-frame flags, and CAN's payload lengths, live here too."""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

FRAME_DLC = 8
"""A classic CAN frame's data bytes."""
MAX_PAYLOAD = 64
"""The most data bytes any CAN frame carries (CAN FD)."""
READ_ROWS = 1 << 20
"""Frames a block holds where a file is read block by block (about 22 MB as frames):
memory bounded, few blocks."""
FD_LENGTHS = (0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64)
"""The payload lengths a CAN FD frame can have (ISO 11898-1: DLC 9..15 are 12..64 bytes)."""

# Frame flags (our own bit set, kept per frame in recordings).
FLAG_EXTENDED = 1
FLAG_REMOTE = 2
FLAG_ERROR = 4
FLAG_FD = 8


def _u8(a: ArrayLike, n: int) -> NDArray[np.uint8]:
    return np.broadcast_to(np.asarray(a, dtype=np.uint8), (n,)).copy()


@dataclass(frozen=True)
class Frames:
    """A block of raw CAN frames, in arrival order.

    Attributes
    ----------
    t_s : ndarray of float64, shape (n,)
        Host receive timestamps [s] (informational: timing comes from the
        nodes' sample indices).
    can_id : ndarray of uint32, shape (n,)
        Arbitration id (11 or 29 bits, see ``flags``).
    dlc : ndarray of uint8, shape (n,)
        Data length in bytes (0..8, up to 64 for CAN FD).
    data : ndarray of uint8, shape (n, w)
        Payload, zero-padded to the width ``w`` (8, or 64 once a CAN FD
        frame longer than 8 bytes is present): nothing is truncated.
    flags : ndarray of uint8, shape (n,)
        :data:`FLAG_EXTENDED`, :data:`FLAG_REMOTE`, :data:`FLAG_ERROR`,
        :data:`FLAG_FD` bits.
    """

    t_s: NDArray[np.float64]
    can_id: NDArray[np.uint32]
    dlc: NDArray[np.uint8]
    data: NDArray[np.uint8]
    flags: NDArray[np.uint8]

    def __post_init__(self) -> None:
        n = len(self.t_s)
        if not (len(self.can_id) == len(self.dlc) == len(self.flags) == len(self.data) == n):
            raise ValueError("Frames: arrays of different lengths")
        if self.data.ndim != 2 or self.data.shape[1] < FRAME_DLC:
            raise ValueError(f"Frames: data must be (n, >=8) bytes, got {self.data.shape}")

    @classmethod
    def build(
        cls,
        t_s: ArrayLike,
        can_id: ArrayLike,
        data: ArrayLike,
        dlc: ArrayLike | None = None,
        flags: ArrayLike = 0,
    ) -> Frames:
        """Frames from array-likes; ``data`` is (n, 8) bytes, ``dlc`` defaults to 8."""
        t = np.asarray(t_s, dtype=np.float64).reshape(-1)
        n = len(t)
        raw = np.asarray(data, dtype=np.uint8)
        raw = raw.reshape(n, raw.shape[-1] if raw.ndim == 2 else FRAME_DLC)
        if raw.shape[1] < FRAME_DLC:
            raw = np.pad(raw, ((0, 0), (0, FRAME_DLC - raw.shape[1])))
        return cls(
            t_s=t,
            can_id=np.broadcast_to(np.asarray(can_id, dtype=np.uint32), (n,)).copy(),
            dlc=_u8(FRAME_DLC if dlc is None else dlc, n),
            data=np.ascontiguousarray(raw),
            flags=_u8(flags, n),
        )

    @classmethod
    def empty(cls) -> Frames:
        """No frames."""
        return cls.build(np.empty(0), np.empty(0), np.empty((0, FRAME_DLC)))

    @classmethod
    def from_lists(
        cls,
        t_s: Sequence[float],
        can_id: Sequence[int],
        dlc: Sequence[int],
        flags: Sequence[int],
        payloads: Sequence[bytes],
    ) -> Frames:
        """Frames from per-frame Python lists (a block just received, a log just read)."""
        n = len(t_s)
        if n == 0:
            return cls.empty()
        lengths = np.fromiter(map(len, payloads), np.int64, count=n)
        if (lengths == FRAME_DLC).all():  # the protocol's case: one join, one view
            data = np.frombuffer(b"".join(payloads), np.uint8).reshape(n, FRAME_DLC).copy()
        else:
            data = np.zeros((n, max(FRAME_DLC, int(lengths.max()))), np.uint8)
            for i, p in enumerate(payloads):
                data[i, : len(p)] = np.frombuffer(p, np.uint8)
        return cls(
            np.asarray(t_s, np.float64),
            np.asarray(can_id, np.uint32),
            np.asarray(dlc, np.uint8),
            data,
            np.asarray(flags, np.uint8),
        )

    def __len__(self) -> int:
        return len(self.t_s)

    def take(self, index: ArrayLike) -> Frames:
        """The frames at ``index`` (an integer array, a boolean mask or a slice).

        A slice gives views of these arrays (numpy's rule); the others copy.
        """
        i = index if isinstance(index, slice) else np.asarray(index)
        return Frames(self.t_s[i], self.can_id[i], self.dlc[i], self.data[i], self.flags[i])

    @staticmethod
    def concat(blocks: Sequence[Frames]) -> Frames:
        """The blocks one after the other (data widened to the widest block)."""
        blocks = [b for b in blocks if len(b)]
        if not blocks:
            return Frames.empty()
        if len(blocks) == 1:
            return blocks[0]  # nothing to join: no copy
        width = max(b.data.shape[1] for b in blocks)
        data = [
            b.data
            if b.data.shape[1] == width
            else np.pad(b.data, ((0, 0), (0, width - b.data.shape[1])))
            for b in blocks
        ]
        return Frames(
            np.concatenate([b.t_s for b in blocks]),
            np.concatenate([b.can_id for b in blocks]),
            np.concatenate([b.dlc for b in blocks]),
            np.concatenate(data),
            np.concatenate([b.flags for b in blocks]),
        )

    def sorted_by_time(self) -> Frames:
        """The frames in timestamp order (stable: equal times keep their order)."""
        return self.take(np.argsort(self.t_s, kind="stable"))


@dataclass(frozen=True)
class BadFrame:
    """A frame of a family's id that cannot be decoded (counted, never fatal)."""

    frame: int
    can_id: int
    reason: str


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
