"""Which decoder a live session reads its frames with: protocol v1's
(:class:`stand.drivers.streams.StreamBuilder`) or a scan-stream module's
(:class:`stand.drivers.scan.ScanBuilder`), by the config's ``[bus] protocol``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from stand.config.scan import bus_protocol
from stand.drivers.scan import ScanBuilder, ScanLayout, load_layout
from stand.drivers.streams import StreamBuilder
from stand.errors import UsageError


def layout_of(cfg: Any, config: str | None, *, scene_bus: dict[str, Any] | None = None,
              scene: str | None = None) -> ScanLayout | None:  # fmt: skip
    """The scan module's layout the config reads (its DBC relative to the config file's
    folder), or None for protocol v1.  With a scene, the scene must send what the config
    reads."""
    source = config or scene or "the config"
    protocol, scan = bus_protocol(cfg.bus, source)
    if scene is not None:
        sent = bus_protocol(scene_bus, scene)[0]
        if sent != protocol:
            raise UsageError(f"the scene {scene} sends protocol {sent} frames, but "
                             f"{source} reads {protocol}: give a config of the same [bus] "
                             "protocol")  # fmt: skip
    if scan is None:
        return None
    return load_layout(scan, Path(config).parent if config else Path("."), source)


def builder_for(layout: ScanLayout | None) -> StreamBuilder | ScanBuilder:
    """A fresh decoder for one session."""
    return StreamBuilder() if layout is None else ScanBuilder(layout)
