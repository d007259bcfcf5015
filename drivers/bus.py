"""Live frames from a python-can bus, in blocks.

The driver boundary follows python-can's ``BusABC``: a small primitive
(:meth:`FrameSource.read_block`) behind a base class, context managers and
an idempotent ``close()``.  The bus itself is opened by the caller
(:func:`open_bus`, from the configuration's ``[bus]`` table) and passed in,
as cantools' ``Tester`` takes it; nothing deep inside opens a bus.

:class:`BusReader` runs one thread that only calls ``bus.recv()`` and
appends the message's fields to lists (a few microseconds a frame); the
caller takes whole blocks with :meth:`~BusReader.read_block` and decodes them
with numpy.  What waits between the two is bounded (:data:`MAX_PENDING`
frames); frames beyond it are dropped *and counted* (``overruns``).
"""

from __future__ import annotations

import abc
import re
import threading
import time
from typing import Any

import numpy as np

from stand.drivers.family import FAMILIES
from stand.drivers.frames import (
    FLAG_ERROR,
    FLAG_EXTENDED,
    FLAG_FD,
    FLAG_REMOTE,
    Frames,
    messages_from_frames,
)
from stand.errors import BusError, BusTimeoutError

MAX_PENDING = 1_000_000
"""Frames that may wait for :meth:`BusReader.read_block` (about 6 min of two nodes at 4 kHz)."""
SILENCE_TIMEOUT_S = 2.0
"""No frame at all for this long ends a live run [s]."""
SOCKETCAN_ERR_BUSOFF = 0x40
"""Error class bit of a bus-off error frame (SocketCAN ``CAN_ERR_BUSOFF``)."""


def describe_bus(kwargs: dict[str, Any]) -> str:
    """``interface:channel`` for messages, e.g. ``"socketcan:can0"`` (what python-can's own
    environment or config file names, where the options do not)."""
    fallback = {} if "interface" in kwargs else _python_can_config()
    merged = {**fallback, **kwargs}
    return f"{merged.get('interface', '?')}:{merged.get('channel', '?')}"


PRODUCT_KEYS = ("protocol", *FAMILIES)
"""``[bus]`` keys the product reads itself (the family and its own table:
:mod:`stand.config.bus`); never python-can's."""

URL_CHANNEL = re.compile(r"^\s*[A-Za-z][A-Za-z0-9+.-]*://")
"""A channel like ``spy://``, ``loop://``, ``rfc2217://``, ``socket://``: serial interfaces
hand it to pyserial, whose URL handlers open files and sockets."""
ALLOW_URL = "allow_url_channel"
"""The key by which the command line (``--allow-url-channel``), never a file, allows one."""


def _python_can_config() -> dict[str, Any]:
    """What python-can's own environment (``CAN_INTERFACE``, ``CAN_CHANNEL`` ...) or config
    file (``~/.canrc``, ``can.ini``) says, the environment first: ``can.Bus`` falls back to
    them when no interface is given."""
    import can.util

    for read in (can.util.load_environment_config, can.util.load_file_config):
        try:
            found = dict(read())
        except Exception:  # a malformed file: can.Bus will say what is wrong with it
            found = {}
        if found.get("interface"):
            return found
    return {}


def _configured_interface() -> str | None:
    """The interface python-can's own environment or config file names, if any."""
    found = _python_can_config().get("interface")
    return None if found is None else str(found)


def open_bus(kwargs: dict[str, Any]) -> Any:
    """``can.Bus(**kwargs)``, its failures as one :class:`BusError`.

    Parameters
    ----------
    kwargs
        The ``[bus]`` table with the command-line overrides applied:
        ``interface``, ``channel``, ``bitrate`` and any option the
        python-can interface takes.
    """
    import can

    kwargs = {k: v for k, v in kwargs.items() if k not in PRODUCT_KEYS}
    allow_url = bool(kwargs.pop(ALLOW_URL, False))
    where = describe_bus(kwargs)
    channel = kwargs.get("channel")
    if isinstance(channel, str) and URL_CHANNEL.match(channel) and not allow_url:
        raise BusError(
            f"the channel {channel!r} is a URL: serial interfaces open files and sockets for "
            "such names; refused unless the command line says --allow-url-channel",
            channel=where,
        )
    if "interface" not in kwargs and not _configured_interface():
        raise BusError(
            "no CAN interface given: set [bus] interface in the config, --interface, or "
            "python-can's own config file (~/.canrc) or CAN_INTERFACE",
            channel=where,
        )
    try:
        return can.Bus(**kwargs)
    except Exception as exc:
        # (kvaser without its DLL: NameError); each is "cannot open", said in one line
        raise BusError(
            f"cannot open the bus ({type(exc).__name__}: {exc})", channel=where
        ) from None


KEEPS_STAMPS = ("virtual", "stand_loopback")
"""Interfaces that can keep a sender's timestamp (``preserve_timestamps``): on them a
simulated node's frames carry their wire time (:func:`play`'s ``wire_stamps``)."""


def keep_stamps(bus: Any, kwargs: dict[str, Any]) -> bool:
    """From now on, have ``bus`` (opened with ``kwargs``) send a message's own timestamp
    (its wire time), where its interface can (:data:`KEEPS_STAMPS`); whether it does."""
    keeps = keeps_stamps(kwargs)
    if keeps:
        bus.preserve_timestamps = True
    return keeps


def keeps_stamps(kwargs: dict[str, Any]) -> bool:
    """Whether the interface ``kwargs`` names can send a sender's own stamps."""
    return kwargs.get("interface") in KEEPS_STAMPS


def open_player_bus(kwargs: dict[str, Any]) -> tuple[Any, bool]:
    """The simulated nodes' side of the bus ``kwargs`` names (:func:`open_bus`), and
    whether it keeps the stamps :func:`play` gives (on :data:`KEEPS_STAMPS` interfaces)."""
    keeps = keeps_stamps(kwargs)
    return open_bus({**kwargs, "preserve_timestamps": True} if keeps else kwargs), keeps


class FrameSource(abc.ABC):
    """Blocks of frames from somewhere (a bus, a replay).

    Subclasses implement :meth:`read_block` and :meth:`_close`.
    """

    channel_info: str = "frames"
    _closed = False

    @abc.abstractmethod
    def read_block(self, timeout_s: float = 0.1) -> Frames:
        """The frames that arrived since the last call (waiting up to ``timeout_s``).

        Raises
        ------
        BusError
            The source failed; frames received before are already returned.
        BusTimeoutError
            No frame for the source's silence timeout.
        """

    def close(self) -> None:
        """Stop reading (idempotent).  The bus itself belongs to the caller."""
        if not self._closed:
            self._closed = True
            self._close()

    @abc.abstractmethod
    def _close(self) -> None: ...

    def __enter__(self) -> FrameSource:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class BusReader(FrameSource):
    """Receive a python-can bus on a thread; hand over blocks of frames.

    Parameters
    ----------
    bus
        An open ``can.BusABC`` (closed by its owner, not here).
    silence_timeout_s
        No frame for this long raises :class:`BusTimeoutError` [s].
    first_frame_s
        Before the first frame, the silence allowed instead [s] (None: the same): time for
        a person to start the rotor, or the simulator in another terminal.
    max_pending
        Bound on frames waiting for :meth:`read_block`.
    """

    def __init__(
        self,
        bus: Any,
        *,
        channel_info: str | None = None,
        silence_timeout_s: float = SILENCE_TIMEOUT_S,
        first_frame_s: float | None = None,
        max_pending: int = MAX_PENDING,
        quiet_ids: tuple[int, ...] = (),
    ):
        self.bus = bus
        self.quiet_ids = np.array(quiet_ids, dtype=np.uint32)
        """Ids of the host's own frames (its SYNC): they are recorded but are no sign that
        the nodes live, so frames of these ids alone do not hold off the silence timeout."""
        self.channel_info = channel_info or str(getattr(bus, "channel_info", "bus"))
        self.silence_timeout_s = silence_timeout_s
        self.first_frame_s = silence_timeout_s if first_frame_s is None else first_frame_s
        self.max_pending = max_pending
        self.frames_received = 0
        self.overruns = 0
        self._lock = threading.Lock()
        self._ready = threading.Event()
        self._stop = threading.Event()
        self._error: BaseException | None = None
        self._silent: BusTimeoutError | None = None
        self._last_frame = time.monotonic()
        self._heard = False  # a frame of the nodes (not only the host's own) came
        self._t: list[float] = []
        self._id: list[int] = []
        self._dlc: list[int] = []
        self._flags: list[int] = []
        self._data: list[bytes] = []
        self._thread = threading.Thread(
            target=self._run, name=f"stand rx {self.channel_info}", daemon=True
        )
        self._thread.start()

    def _run(self) -> None:
        recv = self.bus.recv
        stop = self._stop.is_set
        try:
            while not stop():
                m = recv(0.05)
                if m is None:
                    continue
                flags = (
                    (FLAG_EXTENDED if m.is_extended_id else 0)
                    | (FLAG_REMOTE if m.is_remote_frame else 0)
                    | (FLAG_ERROR if m.is_error_frame else 0)
                    | (FLAG_FD if m.is_fd else 0)
                )
                with self._lock:
                    if len(self._t) >= self.max_pending:
                        self.overruns += 1
                        continue
                    self._t.append(m.timestamp)
                    self._id.append(m.arbitration_id)
                    self._dlc.append(m.dlc)
                    self._flags.append(flags)
                    self._data.append(bytes(m.data))
                self._ready.set()
        except BaseException as exc:  # the interface went away: keep it for read_block
            self._error = exc
            self._ready.set()

    def read_block(self, timeout_s: float = 0.1) -> Frames:
        if self._silent is not None:
            raise self._silent
        self._ready.wait(timeout_s)
        with self._lock:
            self._ready.clear()
            t, ids, dlc, flags, data = self._t, self._id, self._dlc, self._flags, self._data
            self._t, self._id, self._dlc, self._flags, self._data = [], [], [], [], []
        now = time.monotonic()
        n = len(t)
        if n:
            self.frames_received += n
            frames = Frames.from_lists(t, ids, dlc, flags, data)
            if not len(self.quiet_ids) or not np.isin(frames.can_id, self.quiet_ids).all():
                self._last_frame, self._heard = now, True
            elif now - self._last_frame > self._allowed():
                self._silent = self._silence(own=True)  # raised once these frames are taken
            if ((frames.flags & FLAG_ERROR) != 0).any():
                err = frames.can_id[(frames.flags & FLAG_ERROR) != 0]
                if (err & SOCKETCAN_ERR_BUSOFF).any():
                    self._error = BusError(
                        "bus-off (error frame)",
                        channel=self.channel_info,
                        frames_received=self.frames_received,
                    )
            return frames
        if self._error is not None:
            exc = self._error
            if isinstance(exc, BusError):
                raise exc
            raise BusError(
                f"the interface failed ({type(exc).__name__}: {exc}); "
                f"{self.frames_received} frames received before",
                channel=self.channel_info,
                frames_received=self.frames_received,
            )
        if now - self._last_frame > self._allowed():
            raise self._silence()
        return Frames.empty()

    def _allowed(self) -> float:
        """The silence allowed now [s]: before the first frame, :attr:`first_frame_s`."""
        return self.silence_timeout_s if self._heard else self.first_frame_s

    def _silence(self, *, own: bool = False) -> BusTimeoutError:
        """The error of a bus silent (``own``: but for the host's own frames) too long."""
        if own:
            what = (f"no frame but the host's own SYNC for {self._allowed():g} s "
                    f"(after {self.frames_received}): the modules stopped answering")  # fmt: skip
        elif self.frames_received == 0:
            what = (
                f"no frames at all for {self.first_frame_s:g} s: is the bus "
                "connected, the bitrate right, are the nodes powered?"
            )
            if self.channel_info.startswith("virtual"):
                what = (
                    f"no frames at all for {self.first_frame_s:g} s: python-can's "
                    "virtual interface joins buses inside one process only; from another "
                    "process (stand simulate --bus) use stand_loopback, e.g. "
                    "-i stand_loopback -c 47001"
                )
        else:
            what = f"no more frames for {self.silence_timeout_s:g} s (after {self.frames_received})"
        return BusTimeoutError(
            what,
            channel=self.channel_info,
            timeout_s=self._allowed(),
            frames_received=self.frames_received,
        )

    def _close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)


def play(
    bus: Any,
    frames: Frames,
    *,
    realtime: bool = True,
    stop: threading.Event | None = None,
    tick_s: float = 0.005,
    wire_stamps: bool = False,
    start_s: float | None = None,
) -> int:
    """Send frames on a bus, paced by their host timestamps (the simulated nodes' side).

    Parameters
    ----------
    bus
        An open ``can.BusABC``.
    frames
        The frames to send, in order.
    realtime
        Pace by ``t_s`` (frames due within each ``tick_s`` go together);
        if False, send as fast as the bus takes them.
    stop
        Set it to stop early.
    wire_stamps
        Stamp each frame with the time it is due on the wire (the start's ``time.time()``
        plus its offset), as an adapter that stamps in hardware or in the kernel would,
        for a bus that keeps a sender's stamp (``preserve_timestamps``): a player late on
        a loaded machine then delivers late frames, not a slower clock.  If False, the
        receiving interface stamps each frame when it is sent.
    start_s
        The ``time.monotonic()`` the first frame is due at (default: now), so that a
        simulated drive and the frames share one clock.

    Returns
    -------
    int
        Frames sent.
    """

    import can

    if len(frames) == 0:
        return 0
    t_rel = frames.t_s - frames.t_s[0]
    now = time.monotonic()
    start = now if start_s is None else start_s
    wall = time.time() + (start - now)
    sent = 0
    for m, due in zip(messages_from_frames(frames), t_rel.tolist(), strict=True):
        if stop is not None and stop.is_set():
            break
        if realtime:
            late = due - (time.monotonic() - start)
            if late > tick_s:
                time.sleep(late)
        m.timestamp = wall + due if wire_stamps else 0.0  # 0: the receiving side stamps it
        try:
            bus.send(m)
        except can.CanError as exc:  # bus-off, unplugged, the other side of a loopback gone
            raise BusError(f"the bus refused a frame after {sent} were sent ({exc})",
                           channel=str(getattr(bus, "channel_info", "bus")),
                           frames_received=0) from exc  # fmt: skip
        sent += 1
    return sent
