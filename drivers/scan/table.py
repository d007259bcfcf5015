"""The ``[bus.scan]`` table: a scan-stream DAQ module described by a DBC and a mapping of
its channels (``[bus] protocol = "scan"``; the decoder: :mod:`stand.drivers.scan.codec`).

::

    [bus]
    interface = "socketcan"
    channel = "can0"
    protocol = "scan"              # "v1" (the sensor nodes, default) or "scan"

    [bus.scan]
    dbc = "scan-module.dbc"        # relative to this file's folder
    rate_hz = 2000.0               # the module's scan rate
    counter = "counter"            # the scan counter's signal (optional, strongly advised)
    mark_threshold = 0.5           # the mark channel's threshold (default: mid-range)
    scans_per_frame = 1            # a CAN FD frame of k scans: 8 (default 1)
    scan_bytes = 8                 # the bytes of one scan in it

    [[bus.scan.channels]]
    message = "SCAN"
    signal = "ai1"
    role = "accel"                 # "accel" or "mark"
    support = 1
    scale = 98.1                   # the DBC's physical value -> m/s^2 (10 mV/g: 981 ...)
    delay_s = 0.0                  # the channel's known constant delay [s]

The ``protocol`` and ``scan`` keys are the product's
(:data:`stand.drivers.bus.PRODUCT_KEYS`); every other ``[bus]`` key goes to python-can as
before.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, Field, FiniteFloat, model_validator

from stand.drivers.family import STRICT
from stand.drivers.frames import FD_LENGTHS

Name = Annotated[str, Field(pattern=r"^[A-Za-z_][A-Za-z0-9_]{0,63}$")]


class ScanChannel(BaseModel):
    """``[[bus.scan.channels]]``: one signal of the module and what it measures."""

    model_config = STRICT

    message: Name
    signal: Name
    role: Literal["accel", "mark"]
    support: Literal[1, 2] | None = None
    scale: Annotated[FiniteFloat, Field(gt=-1e9, lt=1e9)] = 1.0
    delay_s: Annotated[FiniteFloat, Field(ge=-0.05, le=0.05)] = 0.0

    @model_validator(mode="after")
    def _support_for_accel(self) -> ScanChannel:
        if self.role == "accel" and self.support is None:
            raise ValueError(f"{self.signal}: an accel channel names its support (1 or 2)")
        if self.role == "mark" and self.support is not None:
            raise ValueError(f"{self.signal}: the mark channel serves both supports")
        if self.scale == 0:
            raise ValueError(f"{self.signal}: scale 0 would make every value 0")
        return self


class ScanTable(BaseModel):
    """``[bus.scan]``: the DBC, the rate, the counter and the channels."""

    model_config = STRICT

    dbc: Annotated[str, Field(min_length=1, max_length=4000)]
    rate_hz: Annotated[FiniteFloat, Field(gt=0.0, le=1e6)]
    counter: Name | None = None
    mark_threshold: FiniteFloat | None = None
    scans_per_frame: Annotated[int, Field(ge=1, le=64)] = 1
    """Scans a frame carries (a CAN FD frame of k scans: scan ``i`` at byte ``i x
    scan_bytes``, each laid out as the DBC's message describes the first)."""
    scan_bytes: Annotated[int, Field(ge=1, le=8)] = 8
    """The bytes one scan takes in such a frame."""
    channels: Annotated[list[ScanChannel], Field(min_length=3, max_length=16)]

    @model_validator(mode="after")
    def _one_of_each(self) -> ScanTable:
        roles: list[tuple[str, int | None]] = [(c.role, c.support) for c in self.channels]
        for want, what in ((("mark", None), "the mark"), (("accel", 1), "support 1's accel"),
                           (("accel", 2), "support 2's accel")):  # fmt: skip
            if roles.count(want) != 1:
                raise ValueError(f"channels: exactly one channel for {what}, "
                                 f"found {roles.count(want)}")  # fmt: skip
        need = self.scans_per_frame * self.scan_bytes
        if self.scans_per_frame > 1 and need not in FD_LENGTHS:
            raise ValueError(f"scans_per_frame x scan_bytes: {self.scans_per_frame} x "
                             f"{self.scan_bytes} = {need} bytes, not a CAN FD payload length "
                             f"({', '.join(map(str, FD_LENGTHS[8:]))})")  # fmt: skip
        return self
