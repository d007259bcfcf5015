"""The sensor nodes' protocol v1 (``[bus] protocol = "v1"``, the default): per node
SAMPLES, STATUS and MARK frames (:mod:`~stand.drivers.v1.protocol`, their codec
:mod:`~stand.drivers.v1.codec`), each node's stream rebuilt by its own clock and STATUS
(:mod:`~stand.drivers.v1.build`, :mod:`~stand.drivers.v1.node_build`), and the frames a
node sends (:mod:`~stand.drivers.v1.nodes`, for the simulator and the tests).  No
description file: the layout is the protocol's (``sensor_node_v1.dbc`` documents it)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stand.drivers.family import Description, Kept
from stand.drivers.frames import Frames
from stand.drivers.streams import RunStreams
from stand.drivers.v1.build import StreamBuilder, rebuild


@dataclass(frozen=True)
class V1Layout:
    """Protocol v1 needs nothing from the config: the nodes say their rate and scale."""

    family: str = "v1"
    rate_hz: float | None = None
    descriptions: tuple[Description, ...] = ()


class V1:
    """The sensor nodes' protocol v1 as an :class:`~stand.drivers.family.Acquisition`."""

    name = "v1"
    table = None

    def layout(self, table: Any, base: Path, source: str,
               stored: Kept | None = None) -> V1Layout:  # fmt: skip
        return V1Layout()

    def decode(self, layout: Any, frames: Frames) -> RunStreams:
        return rebuild(frames)

    def builder(self, layout: Any) -> StreamBuilder:
        return StreamBuilder(merge=False)

    def setup(self, layout: Any) -> None:
        return None


FAMILY = V1()
