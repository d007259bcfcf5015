"""The one seam for acquisition hardware: a family of devices on the bus (the sensor
nodes' protocol v1, a scan-stream module, CANopen modules on SYNC ...), what an
implementation shall do (:class:`Acquisition`), and the one registry of family names to
the modules that implement them (:data:`FAMILIES`), each imported only when chosen.

A family lives in its own wing of ``drivers/`` (``drivers/<name>/``) whose face holds
``FAMILY``, an object that satisfies :class:`Acquisition`.  Adding one: write the wing,
add its name and module here, document it in ``docs/hardware.md``.  Nothing else in the
product names a family: the config checks ``[bus] protocol`` and ``[bus.<name>]``
through :func:`family_of`, and ``stand.solve.acquisition`` is the one place that chooses.
"""

from __future__ import annotations

import hashlib
import importlib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from pydantic import ConfigDict

from stand.drivers.frames import Frames
from stand.drivers.streams import RunStreams
from stand.errors import ConfigError
from stand.files import not_regular

FAMILIES: dict[str, str] = {
    "v1": "stand.drivers.v1",
    "scan": "stand.drivers.scan",
    "canopen": "stand.drivers.canopen",
}
"""``[bus] protocol`` names -> the module whose ``FAMILY`` implements it."""

DEFAULT = "v1"
"""The family of a config without ``[bus] protocol`` (the sensor nodes)."""

STRICT = ConfigDict(extra="forbid", strict=True, frozen=True)
"""Every table of every TOML file, a family's ``[bus.<name>]`` too: unknown keys refused,
no strings for numbers, frozen."""

MAX_DESCRIPTION_BYTES = 1 << 20
"""The largest description file (DBC, EDS) read: 1 MiB.  A large real EDS is about
200 kB; a larger file is refused before it is parsed (a 22 MB file is refused in
milliseconds instead of keeping a parser busy for a minute)."""


@dataclass(frozen=True)
class Description:
    """A description file a layout was read from: its name as the config gives it, and its
    text (stored with every run recorded through it, so the run can be decoded as it was
    recorded)."""

    name: str
    text: str

    @property
    def sha256(self) -> str:
        return hashlib.sha256(self.text.encode("utf-8")).hexdigest()


@dataclass(frozen=True)
class Kept:
    """The description files a run kept (``texts``: file name -> text), and whether the
    run is decoded with its own stored config (``own``) or with one given."""

    texts: Mapping[str, str]
    own: bool = True


class FrameBuilder(Protocol):
    """Frames in, streams out, as a live session or a block reader feeds them."""

    frames: int
    """Frames added so far."""
    last_block: Frames
    """The block added last."""
    read_rows: int | None
    """The block size a file is best read in (None: whole)."""
    keeps_times: bool
    """Whether it keeps the blocks' time arrays as they are (then a file's times are read
    whole first, so that the blocks' are views of one array: no copy of the run's
    length); a builder that keeps only some times says False."""

    def add(self, frames: Frames) -> None:
        """Take a block of frames, in arrival order after those added before."""

    def streams(self, *, strict_status: bool = True, release: bool = False) -> RunStreams:
        """The streams of every frame added so far (``release``: the builder is done)."""

    def tail(self, from_frame: int) -> RunStreams:
        """The streams of the frames from ``from_frame`` on, as a run of their own."""


class Layout(Protocol):
    """What a family read from the config and its description files."""

    family: str
    """The family's name (a key of :data:`FAMILIES`)."""
    rate_hz: float | None
    """The sample rate the config states [Hz], or None where the frames say it (v1)."""
    descriptions: tuple[Description, ...]
    """The description files read, with their texts (none for v1)."""


class BusSetup(Protocol):
    """What a family does on the bus before and after a live recording (CANopen: set-up
    over SDO, NMT start, the SYNC)."""

    attr: str
    """The run file attribute the set-up's dialogue is stored under."""
    clock_ids: tuple[int, ...]
    """Frame ids the host itself sends as the clock: they never hold off the silence
    timeout."""

    def configure(self, bus: Any, channel: str) -> list[dict[str, Any]]:
        """Set the devices up; return the dialogue (JSON-ready) to store with the run."""

    def start(self, *, produce: bool, channel: str) -> None:
        """Start the devices (``produce``: and the host's clock frames)."""

    def stop(self) -> None:
        """Stop them again (idempotent)."""


class Acquisition(Protocol):
    """A family of acquisition hardware on the bus.  An implementation shall:

    - name itself (``name``, its ``[bus] protocol`` value) and give the pydantic model of
      its ``[bus.<name>]`` table (``table``; None: it takes none), checked by
      ``load_config``;
    - read its layout (:meth:`layout`) from that table and its description files, each
      file bounded by :data:`MAX_DESCRIPTION_BYTES` (:func:`read_description`) and every
      fault in it one :class:`~stand.errors.ConfigError` naming the file and the section
      or signal; given the descriptions a run kept (``stored``), decode a run solved
      with its own config with those, and say which copy was used where they differ;
    - refuse what the layout itself shows wrong (two supports on one frame, the clock's
      id on a device's data);
    - turn a run's frames (arrival order) into the two supports' streams
      (:meth:`decode`), on the recording's own clock: a configured rate the recording
      contradicts by more than :data:`stand.drivers.checks.CLOCK_TOLERANCE` is refused
      (:func:`stand.drivers.checks.check_clock`), and so are a mark channel that is no
      pulse train, an accelerometer channel that is one, and two supports fed one
      device's samples (``check_mark``, ``check_accel``, ``check_distinct``);
    - give a builder a live session or a block reader feeds (:meth:`builder`), whose
      streams equal :meth:`decode` of the same frames however they are cut in blocks;
    - give its set-up over the bus, or None (:meth:`setup`).

    Decoding loads neither python-can nor h5py; a description library (cantools,
    canopen) loads only in :meth:`layout`.
    """

    name: str
    table: type[Any] | None

    def layout(self, table: Any, base: Path, source: str,
               stored: Kept | None = None) -> Layout:  # fmt: skip
        """The layout of a checked ``[bus.<name>]`` table, files relative to ``base``
        (``stored``: what a run kept, :func:`read_description`)."""

    def decode(self, layout: Any, frames: Frames) -> RunStreams:
        """A run's frames (arrival order) -> the supports' streams."""

    def builder(self, layout: Any) -> FrameBuilder:
        """A fresh builder for one session or one read."""

    def setup(self, layout: Any) -> BusSetup | None:
        """The set-up a live session performs on the bus, or None."""


def family_of(name: str, source: str = "the config") -> Acquisition:
    """The family registered under ``name`` (its module imported now).

    Raises
    ------
    ConfigError
        No family of that name.
    """
    if name not in FAMILIES:
        raise ConfigError(f"[bus] protocol: {name!r}, expected one of {', '.join(FAMILIES)}",
                          source=source, key="bus.protocol")  # fmt: skip
    found: Acquisition = importlib.import_module(FAMILIES[name]).FAMILY
    return found


def read_description(path: Path, key: str, source: str, stored: Kept | None
                     ) -> tuple[Description, str | None]:  # fmt: skip
    """A description file's text, bounded in size, or the text a run stored for it.

    ``stored``: the descriptions a run kept (by file name), and whether the run is decoded
    with its own stored config (then its kept copy is used: the file may have changed or
    gone since) or with a config given (then the file as it is now).  Returns the
    description used and, where the kept copy and the file differ, a sentence saying
    which was used (else None).

    Raises
    ------
    ConfigError
        The file is missing (and nothing kept), too large, or not text.
    """
    name = path.name
    found = stored.texts.get(name) if stored is not None else None
    kept = Description(name, found) if found is not None else None
    if kept is not None and stored is not None and stored.own:
        try:
            now = _text(path, key, source)
        except ConfigError:
            return kept, f"{name} is not readable now: decoded with the copy the run kept"
        if now != kept.text:
            return kept, (f"{name} changed since the run was recorded: decoded with the copy "
                          "the run kept")  # fmt: skip
        return kept, None
    desc = Description(name, _text(path, key, source))
    if kept is not None and desc.text != kept.text:
        return desc, (f"{name} differs from the copy the run kept: decoded with the given "
                      "config's file as it is now")  # fmt: skip
    return desc, None


def _text(path: Path, key: str, source: str) -> str:
    if (kind := not_regular(path)) is not None:  # a FIFO would wait for a writer forever
        raise ConfigError(f"[{key}]: {path} is {kind}, not a description file", source=source)
    try:
        size = path.stat().st_size
        if size > MAX_DESCRIPTION_BYTES:
            raise ConfigError(f"[{key}]: {path} has {size} bytes, more than a description "
                              f"file's {MAX_DESCRIPTION_BYTES} (1 MiB)", source=source)  # fmt: skip
        raw = path.read_bytes()
    except OSError as exc:
        raise ConfigError(f"[{key}]: cannot read {path} ({exc.strerror or exc})",
                          source=source) from exc  # fmt: skip
    if b"\0" in raw:
        raise ConfigError(f"[{key}]: {path} is not a text file (NUL bytes)", source=source)
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")  # EDS files of older tools are Windows-1252 / Latin-1
