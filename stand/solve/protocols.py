"""Which decoder a run's frames are read with, by the config's ``[bus] protocol`` (a
recording solved, a live session): protocol v1's
(:class:`stand.drivers.streams.StreamBuilder`), a scan-stream module's
(:mod:`stand.drivers.scan`) or CANopen modules' on SYNC
(:mod:`stand.drivers.canopen_stream`), the last two live through
:class:`stand.drivers.scan.WholeBuilder`."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from stand.config.scan import bus_protocol
from stand.drivers.canopen_stream import PdoLayout, load_pdo_layout, pdo_streams
from stand.drivers.protocol import Frames
from stand.drivers.scan import ScanLayout, WholeBuilder, load_layout, scan_streams
from stand.drivers.streams import RunStreams, StreamBuilder
from stand.errors import UsageError


def layout_of(cfg: Any, config: str | None, *, scene_bus: dict[str, Any] | None = None,
              scene: str | None = None) -> ScanLayout | PdoLayout | None:  # fmt: skip
    """The layout the config reads (its DBC or EDS relative to the config file's folder;
    ``config`` may end in " (stored)": the run file's own), or None for protocol v1.  With
    a scene, the scene must send what the config reads."""
    source = config or scene or "the config"
    protocol, table = bus_protocol(cfg.bus, source)
    if scene is not None:
        sent = bus_protocol(scene_bus, scene)[0]
        if sent != protocol:
            raise UsageError(f"the scene {scene} sends protocol {sent} frames, but "
                             f"{source} reads {protocol}: give a config of the same [bus] "
                             "protocol")  # fmt: skip
    base = Path(config.removesuffix(" (stored)")).parent if config else Path(".")
    if protocol == "scan":
        return load_layout(table, base, source)
    if protocol == "canopen":
        return load_pdo_layout(table, base, source)
    return None


def decoder(layout: ScanLayout | PdoLayout) -> Callable[[Frames], RunStreams]:
    """The frames -> streams function of a layout."""
    if isinstance(layout, ScanLayout):
        return lambda frames: scan_streams(frames, layout)
    return lambda frames: pdo_streams(frames, layout)


def canopen_of(layout: ScanLayout | PdoLayout | None) -> PdoLayout | None:
    """The CANopen modules a live session sets up over SDO and clocks with its SYNC (their
    ``configure`` is true), or None."""
    return layout if isinstance(layout, PdoLayout) and layout.configure else None


def builder_for(layout: ScanLayout | PdoLayout | None) -> StreamBuilder | WholeBuilder:
    """A fresh decoder for one session."""
    return StreamBuilder() if layout is None else WholeBuilder(decoder(layout))
