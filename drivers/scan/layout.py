"""A scan-stream module's layout read from its DBC (with cantools): where each mapped
channel's signal lies in the frame, the counter, the rate, the scans a frame carries."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stand.drivers.family import Description, Kept, read_description
from stand.drivers.one_clock import Signal
from stand.errors import ConfigError

MAX_BITS = 16
"""The widest acceleration signal taken (its raw value is the stream's count)."""


@dataclass(frozen=True)
class Channel:
    """One mapped channel: an acceleration of a support, or the mark."""

    signal: Signal
    role: str
    support: int | None
    scale: float
    delay_s: float


@dataclass(frozen=True)
class ScanLayout:
    """The module: its rate, its counter (if any), its channels."""

    rate_hz: float
    counter: Signal | None
    channels: tuple[Channel, ...]
    mark_threshold: float | None = None
    per_frame: int = 1
    """Scans a frame carries (a CAN FD frame of k scans), ``scan_bytes`` each."""
    scan_bytes: int = 8
    descriptions: tuple[Description, ...] = ()
    """The DBC read, with its text (stored with each run recorded through it)."""
    notes: tuple[str, ...] = ()
    """What the reading says (the run's stored DBC used instead of a changed file)."""
    source: str = ""
    """The config the layout came from, for the decoder's refusals."""
    family: str = "scan"

    def accel(self, support: int) -> Channel:
        return next(c for c in self.channels if c.role == "accel" and c.support == support)

    @property
    def mark(self) -> Channel:
        return next(c for c in self.channels if c.role == "mark")


def _signal(db: Any, message: str, name: str, source: str) -> Signal:
    try:
        msg = db.get_message_by_name(message)
    except KeyError:
        raise ConfigError(f"the DBC has no message {message!r}", source=source) from None
    if msg.is_multiplexed():
        raise ConfigError(f"message {message} is multiplexed: a scan is one plain frame",
                          source=source)  # fmt: skip
    sig = next((s for s in msg.signals if s.name == name), None)
    if sig is None:
        raise ConfigError(f"the DBC's message {message} has no signal {name!r}", source=source)
    if sig.byte_order != "little_endian" or sig.start + sig.length > 64:
        raise ConfigError(f"signal {message}.{name}: only little-endian signals within the "
                          "first 8 bytes are read", source=source)  # fmt: skip
    if sig.is_float or sig.length < 2:
        kind = "a float" if sig.is_float else f"{sig.length} bit"
        raise ConfigError(f"signal {message}.{name}: {kind} signal; integer signals of 2 bits "
                          "or more are read", source=source)  # fmt: skip
    return Signal(f"{message}.{name}", int(msg.frame_id), bool(msg.is_extended_frame),
                  int(sig.start), int(sig.length), bool(sig.is_signed), float(sig.scale),
                  float(sig.offset))  # fmt: skip


def _database(text: str, path: Path, source: str) -> Any:
    """The DBC parsed (cantools, strict: overlapping signals refused), every fault one
    line; two messages on one frame id refused."""
    import cantools

    try:
        db: Any = cantools.database.load_string(text, database_format="dbc", strict=True)
    except (ValueError, TypeError, KeyError, IndexError, RecursionError,
            cantools.database.errors.Error) as exc:  # fmt: skip
        detail = " ".join(str(exc).split())[:300] or type(exc).__name__
        raise ConfigError(f"[bus.scan] dbc: cannot read {path} as a DBC ({detail})",
                          source=source) from None  # fmt: skip
    seen: dict[tuple[int, bool], str] = {}
    for msg in db.messages:
        key = (int(msg.frame_id), bool(msg.is_extended_frame))
        if key in seen:
            raise ConfigError(f"{path.name}: messages {seen[key]} and {msg.name} share the "
                              f"frame id 0x{key[0]:X}", source=source)  # fmt: skip
        seen[key] = msg.name
    if _declared_messages(text) > len(db.messages):
        raise ConfigError(f"{path.name}: {_declared_messages(text)} messages declared, "
                          f"{len(db.messages)} read: two share a name or a frame id",
                          source=source)  # fmt: skip
    return db


def _declared_messages(text: str) -> int:
    return sum(1 for line in text.splitlines() if line.startswith("BO_ "))


def load_layout(table: Any, base: Path, source: str,
                stored: Kept | None = None) -> ScanLayout:  # fmt: skip
    """The layout of a ``[bus.scan]`` table (:class:`stand.drivers.scan.table.ScanTable`),
    its DBC read relative to ``base`` (or the copy a run ``stored``); a DBC without a named
    message or signal, a signal it cannot use, or channels in more than one message, is
    one :class:`ConfigError`."""
    path = Path(table.dbc) if Path(table.dbc).is_absolute() else base / table.dbc
    desc, note = read_description(path, "bus.scan", source, stored)
    db = _database(desc.text, path, source)
    where = f"{source}, {path.name}"
    channels = []
    for ch in table.channels:
        sig = _signal(db, ch.message, ch.signal, where)
        if ch.role == "accel" and sig.length > MAX_BITS:
            raise ConfigError(f"{sig.name}: {sig.length} bits; acceleration signals of up to "
                              f"{MAX_BITS} bits are read", source=source)  # fmt: skip
        channels.append(Channel(sig, ch.role, ch.support, ch.scale, ch.delay_s))
    counter = None
    if table.counter is not None:
        counter = _signal(db, channels[0].signal.name.split(".")[0], table.counter, where)
    _check_places(channels, counter, table, source)
    return ScanLayout(float(table.rate_hz), counter, tuple(channels), table.mark_threshold,
                      table.scans_per_frame, table.scan_bytes, (desc,),
                      () if note is None else (note,), source)  # fmt: skip


def _check_places(channels: list[Channel], counter: Signal | None, table: Any, source: str
                  ) -> None:  # fmt: skip
    """One message for all; no two channels on one signal; every signal inside a scan."""
    ids = {c.signal.frame_id for c in channels} | ({counter.frame_id} if counter else set())
    if len(ids) != 1:
        raise ConfigError("[bus.scan] channels: every channel (and the counter) must be in one "
                          "message: one frame is one scan", source=source)  # fmt: skip
    names = [c.signal.name for c in channels] + ([counter.name] if counter else [])
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ConfigError(f"[bus.scan] channels: signal {twice[0]} is mapped twice: each "
                          "support and the mark need their own input", source=source)  # fmt: skip
    bits = 8 * table.scan_bytes
    for s in (*(c.signal for c in channels), *([counter] if counter else [])):
        if s.start + s.length > bits:
            last = s.start + s.length - 1
            raise ConfigError(f"signal {s.name}: bits {s.start}..{last} lie beyond a scan's "
                              f"{table.scan_bytes} bytes", source=source)  # fmt: skip
