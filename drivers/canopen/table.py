"""``[bus] protocol = "canopen"`` and the ``[bus.canopen]`` table: one CANopen analog input
module per support sampling on SYNC (the decoder: :mod:`stand.drivers.canopen.codec`).

::

    [bus]
    interface = "socketcan"
    channel = "can0"
    protocol = "canopen"

    [bus.canopen]
    rate_hz = 2000.0               # the SYNC rate: the sample rate
    sync_id = 0x80                 # the SYNC's COB-ID (CiA 301's default)
    mark_threshold = 2.5           # the mark input's threshold [V] (default: mid-range)
    configure = true               # record, balance, measure set the modules up over SDO
    window_s = 0.00025             # the synchronous window 0x1007 (default: half a period)

    [[bus.canopen.nodes]]
    support = 1
    node_id = 5
    eds = "module.eds"             # relative to this file's folder
    accel = "0x7130:1"             # the accelerometer's input (CiA 404 AI input PV), in TPDO1
    mark = "0x7130:2"              # the reference sensor's input, mapped in TPDO1
    accel_status = "0x6150:1"      # the inputs' AI status, mapped in TPDO1 (optional)
    mark_status = "0x6150:2"
    vendor_id = 0x00000F5A         # the identity 0x1018 must show (default: the EDS's)
    product_code = 0x00000404
    scale = 0.0299                 # a count -> m/s^2
    mark_scale = 0.000305          # a count -> the threshold's unit (V)
    delay_s = 0.0                  # the input's known constant delay [s]
    mark_delay_s = 0.0
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, Field, FiniteFloat, model_validator

from stand.drivers.family import STRICT

Object = Annotated[str, Field(pattern=r"^0x[0-9A-Fa-f]{4}:(0x[0-9A-Fa-f]{1,2}|[0-9]{1,3})$")]
"""``0xIIII:S``: an object's index and sub-index."""
Delay = Annotated[FiniteFloat, Field(ge=-0.05, le=0.05)]
Scale = Annotated[FiniteFloat, Field(gt=0.0, lt=1e9)]


class CanopenNode(BaseModel):
    """``[[bus.canopen.nodes]]``: one support's module."""

    model_config = STRICT

    support: Literal[1, 2]
    node_id: Annotated[int, Field(ge=1, le=127)]
    eds: Annotated[str, Field(min_length=1, max_length=4000)]
    accel: Object
    mark: Object
    scale: Scale
    mark_scale: Scale = 1.0
    delay_s: Delay = 0.0
    mark_delay_s: Delay = 0.0
    accel_status: Object | None = None
    """The accelerometer input's AI status (CiA 404 0x6150), mapped in TPDO1: bit 0 (not
    valid) drops the sample, bits 1 and 2 (overload) flag the run ``overrange``."""
    mark_status: Object | None = None
    vendor_id: Annotated[int, Field(ge=0, le=0xFFFFFFFF)] | None = None
    """The vendor id 0x1018 sub 1 must read (default: the EDS's)."""
    product_code: Annotated[int, Field(ge=0, le=0xFFFFFFFF)] | None = None
    """The product code 0x1018 sub 2 must read (default: the EDS's)."""


class CanopenTable(BaseModel):
    """``[bus.canopen]``: the SYNC, the two modules."""

    model_config = STRICT

    rate_hz: Annotated[FiniteFloat, Field(gt=0.0, le=1e5)]
    sync_id: Annotated[int, Field(ge=1, le=0x7FF)] = 0x80
    mark_threshold: FiniteFloat | None = None
    configure: bool = True
    """Whether ``stand record`` (``balance``, ``measure``, the station) sets the modules up
    over SDO before recording and produces the SYNC (:mod:`stand.drivers.canopen.setup`);
    false: the modules are set up and the SYNC produced by something else."""
    window_s: Annotated[FiniteFloat, Field(gt=0.0, le=1.0)] | None = None
    """The synchronous window written to 0x1007 [s] (default: half a SYNC period)."""
    nodes: Annotated[list[CanopenNode], Field(min_length=2, max_length=2)]

    @model_validator(mode="after")
    def _one_per_support(self) -> CanopenTable:
        if sorted(n.support for n in self.nodes) != [1, 2]:
            raise ValueError("nodes: one module for support 1 and one for support 2")
        if self.nodes[0].node_id == self.nodes[1].node_id:
            raise ValueError("nodes: two modules cannot share a node id")
        if self.window_s is not None and self.window_s >= 1.0 / self.rate_hz:
            raise ValueError(
                f"window_s: {self.window_s:g} s is not within a SYNC period "
                f"({1.0 / self.rate_hz:g} s): a TPDO must come before the next SYNC"
            )
        return self
