"""The one place outside ``drivers/`` that chooses a family of acquisition hardware: a
config's ``[bus]`` (checked by :func:`stand.config.bus.bus_choice`) read into the
family's layout (:class:`Acquired`), for a recording solved, a run inspected, a live
session.  A run that stored its description files (DBC, EDS) is decoded with those."""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stand.config import Config
from stand.config.bus import bus_choice
from stand.drivers.family import (
    DEFAULT,
    Acquisition,
    BusSetup,
    FrameBuilder,
    Kept,
    Layout,
    family_of,
)
from stand.drivers.frames import Frames
from stand.drivers.runs.run_format import DESCRIPTIONS_ATTR
from stand.drivers.streams import RunStreams
from stand.errors import RecordingError, UsageError


@dataclass(frozen=True)
class Acquired:
    """A family and the layout it read: what decodes a run's frames."""

    family: Acquisition
    layout: Layout

    @property
    def name(self) -> str:
        return self.family.name

    def decode(self, frames: Frames) -> RunStreams:
        """A whole run's frames -> the supports' streams."""
        return self.family.decode(self.layout, frames)

    def builder(self) -> FrameBuilder:
        """A fresh builder (one session, one read)."""
        return self.family.builder(self.layout)

    def streams(self, frames: Frames, *, strict_status: bool = True) -> RunStreams:
        """The streams of frames already in memory (``strict_status``: protocol v1's rule
        on a node without STATUS)."""
        builder = self.builder()
        builder.add(frames)
        return builder.streams(strict_status=strict_status, release=True)

    def setup(self) -> BusSetup | None:
        """What a live session does on the bus first (CANopen's SDO set-up), or None."""
        return self.family.setup(self.layout)

    def descriptions_attr(self) -> dict[str, str]:
        """The run file attribute that keeps the description files read (none: empty)."""
        texts = {d.name: d.text for d in self.layout.descriptions}
        return {DESCRIPTIONS_ATTR: json.dumps(texts)} if texts else {}


def acquisition_of(cfg: Config, config: str | None, *, scene_bus: dict[str, Any] | None = None,
                   scene: str | None = None, stored: Kept | None = None
                   ) -> Acquired:  # fmt: skip
    """The family the config reads, with its layout (description files relative to the
    config file's folder; ``config`` may end in " (stored)": the run file's own; ``stored``:
    the descriptions a run kept).  With a scene, the scene must send what the config
    reads."""
    source = config or scene or "the config"
    choice = bus_choice(cfg.bus, source)
    if scene is not None:
        sent = bus_choice(scene_bus, scene).name
        if sent != choice.name:
            raise UsageError(f"the scene {scene} sends protocol {sent} frames, but "
                             f"{source} reads {choice.name}: give a config of the same [bus] "
                             "protocol")  # fmt: skip
    base = Path(config.removesuffix(" (stored)")).parent if config else Path(".")
    return Acquired(choice.family, choice.family.layout(choice.table, base, source, stored))


def default_acquisition() -> Acquired:
    """The family of a config without ``[bus] protocol`` (a log or run with no config)."""
    fam = family_of(DEFAULT)
    return Acquired(fam, fam.layout(None, Path("."), "the default"))


def stored_descriptions(meta: Mapping[str, Any], path: str, *, own: bool = True) -> Kept | None:
    """The description files a run file kept (None: it kept none); ``own``: the run is
    decoded with its own stored config (its copies are used), else with a config given
    (the files as they are now, a difference said)."""
    text = meta.get(DESCRIPTIONS_ATTR)
    if not text:
        return None
    try:
        found = json.loads(str(text))
        if not isinstance(found, dict) or not all(
            isinstance(k, str) and isinstance(v, str) for k, v in found.items()
        ):
            raise ValueError("not a table of file names and texts")
    except ValueError as exc:
        raise RecordingError(f"the attribute {DESCRIPTIONS_ATTR!r} is damaged ({exc})",
                             path=path) from None  # fmt: skip
    return Kept(found, own)
