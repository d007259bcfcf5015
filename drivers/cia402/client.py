"""A CiA 402 servo drive on the stand's CANopen bus as a :class:`~stand.drivers.drive.Drive`:
the ``canopen`` library's 402 profile (``BaseNode402``) walks the state machine and
switches the modes, over SDO; profile velocity for the run, profile position for the stop
at the mark.  Every fault of the link is one :class:`~stand.errors.DriveError` naming the
node and the object."""

from __future__ import annotations

import math
from typing import Any

from stand.core.motor import INDEX_DECEL_SHARE
from stand.drivers.bus import open_bus
from stand.drivers.canopen.layout import object_dictionary
from stand.drivers.cia402.table import (
    ESTOP_BIT,
    INTERLOCK_BIT,
    SW_FAULT,
    SW_TARGET_REACHED,
    Cia402Table,
    state_of,
)
from stand.drivers.drive import DriveContext, DriveState, close_link
from stand.drivers.family import read_description
from stand.errors import ConfigError, DriveError

RPM = math.pi / 30.0
STANDSTILL_RAD_S = 0.01
"""Below this [rad/s] the rotor is at rest (0.1 rpm)."""
REQUIRED = (0x603F, 0x6040, 0x6041, 0x6060, 0x6061, 0x6064, 0x606C, 0x607A, 0x60FD, 0x60FF,
            0x6502)  # fmt: skip
"""The objects the cycle reads and writes (CiA 402)."""
READY_STATES = ("OPERATION ENABLED", "SWITCHED ON", "READY TO SWITCH ON", "SWITCH ON DISABLED")
"""The states a drive without a fault is in."""
CW_ENABLED, CW_NEW_SET_POINT, CW_IMMEDIATE = 0x000F, 1 << 4, 1 << 5
"""Controlword: operation enabled; profile position's new set-point and its change at once."""


class Cia402Drive:
    """One servo drive (node ``table.node_id``) on the bus ``ctx.bus``."""

    def __init__(self, table: Cia402Table, ctx: DriveContext) -> None:
        import can
        import canopen

        self.map, self.motor = table, ctx.motor
        self.where = f"cia402 node {table.node_id} on {(ctx.bus or {}).get('channel', 'the bus')}"
        desc, _ = read_description(ctx.base / table.eds, "drive.cia402.eds", ctx.source, None)
        where = f"{ctx.source}: [drive.cia402] eds {table.eds}"
        od = object_dictionary(desc, table.node_id, where)
        missing = [i for i in REQUIRED if i not in od]
        if missing:
            raise ConfigError(f"the EDS has no object 0x{missing[0]:04X}, which a CiA 402 drive "
                              "needs here", source=where)  # fmt: skip
        self._bus = open_bus(dict(ctx.bus or {}))
        self._network = canopen.Network(self._bus)
        self._notifier = can.Notifier(self._bus, self._network.listeners, 0.05)
        self._network.notifier = self._notifier
        make: Any = canopen.BaseNode402  # (the library's is untyped)
        self.node = make(table.node_id, od)
        self._network.add_node(self.node)
        self.node.sdo.RESPONSE_TIMEOUT = ctx.timeout_s
        self.node.sdo.MAX_RETRIES = 1  # one attempt (the library counts the first)
        self._running = False
        setup: Any = self.node.setup_402_state_machine  # (the library's is untyped)
        try:
            self._sdo(lambda: setup(read_pdos=False), "its set-up")
            self._sdo(lambda: self.node.sdo[0x6041].raw, "statusword 0x6041")  # it answers
        except DriveError:
            self.close()  # no thread or bus left behind by a drive that never answered
            raise

    def _sdo(self, fn: Any, what: str) -> Any:
        from canopen.sdo.exceptions import SdoError

        try:
            return fn()
        except SdoError as exc:
            raise DriveError(f"{what}: no answer ({exc})", where=self.where) from exc
        except RuntimeError as exc:  # the 402 profile: a state or mode not confirmed in time
            raise DriveError(f"{what}: {exc}", where=self.where) from exc

    def _raw(self, index: int) -> int:
        return int(self._sdo(lambda: self.node.sdo[index].raw, f"object 0x{index:04X}"))

    def read(self) -> DriveState:
        sw, vel, pos = self._raw(0x6041), self._raw(0x606C), self._raw(0x6064)
        inputs, code = self._raw(0x60FD), self._raw(0x603F)
        speed = vel / self.map.velocity_per_rpm * RPM
        cpr = self.map.counts_per_rev
        state = state_of(sw)
        return DriveState(
            speed_rad_s=speed,
            angle_rad=2 * math.pi * (pos % cpr) / cpr,
            ready=state in READY_STATES,
            at_speed=state == "OPERATION ENABLED" and self._at_speed(speed),
            standstill=abs(speed) < STANDSTILL_RAD_S,
            in_position=bool(sw & SW_TARGET_REACHED) and self._mode == "PROFILED POSITION",
            guard_closed=not inputs >> INTERLOCK_BIT & 1,
            estop_clear=not inputs >> ESTOP_BIT & 1,
            fault_code=(code or 1) if sw & SW_FAULT else 0,
        )

    _mode = "NO MODE"
    _set_point = 0.0

    def _at_speed(self, speed: float) -> bool:
        return self._mode == "PROFILED VELOCITY" and abs(speed - self._set_point) <= max(
            0.005 * self._set_point, 1 / self.map.velocity_per_rpm * RPM
        )

    def _enable(self, mode: str) -> None:
        node = self.node
        self._sdo(lambda: setattr(node, "op_mode", mode), f"mode {mode} (0x6060)")
        self._mode = mode
        if self._sdo(lambda: node.state, "statusword 0x6041") != "OPERATION ENABLED":
            try:
                self._sdo(lambda: setattr(node, "state", "OPERATION ENABLED"), "the state machine")
            except DriveError as exc:
                now = self._sdo(lambda: node.state, "statusword 0x6041")
                raise DriveError(f"never reached Operation enabled (it is in {now}): {exc}",
                                 where=self.where) from exc  # fmt: skip

    def run(self, omega_rad_s: float) -> None:
        counts = round(omega_rad_s / RPM * self.map.velocity_per_rpm)
        if not 0 <= counts < 1 << 31:
            raise DriveError(f"{omega_rad_s / RPM:.1f} rpm does not fit 0x60FF", where=self.where)
        self._set_point = omega_rad_s
        self._sdo(lambda: setattr(self.node.sdo[0x60FF], "raw", counts), "target velocity 0x60FF")
        self._running = True
        self._enable("PROFILED VELOCITY")

    def stop_at(self, angle_rad: float) -> None:
        """Profile position to the first position at ``angle_rad`` (mod a revolution) the
        rotor can stop at, braking at the share of its torque the index plans with."""
        cpr = self.map.counts_per_rev
        pos, speed = self._raw(0x6064), max(self.read().speed_rad_s, 0.0)
        braking = speed * speed / (2 * INDEX_DECEL_SHARE * self.motor.decel_rad_s2)
        ahead = pos + math.ceil(braking / (2 * math.pi) * cpr)
        want = round(angle_rad % (2 * math.pi) / (2 * math.pi) * cpr) % cpr
        target = ahead + (want - ahead) % cpr
        self._sdo(lambda: setattr(self.node.sdo[0x607A], "raw", target), "target position 0x607A")
        self._enable("PROFILED POSITION")
        for word in (CW_ENABLED | CW_NEW_SET_POINT | CW_IMMEDIATE, CW_ENABLED):
            self._sdo(lambda w=word: setattr(self.node, "controlword", w), "controlword 0x6040")

    def quick_stop(self) -> None:
        self._sdo(lambda: setattr(self.node, "controlword", 0x0002), "controlword 0x6040")
        self._running = False

    def disable(self) -> None:
        self._sdo(lambda: setattr(self.node, "controlword", 0x0000), "controlword 0x6040")
        self._running = False

    def close(self) -> None:
        def release() -> None:
            self._notifier.stop(1.0)
            self._bus.shutdown()

        close_link(self.quick_stop, self._running, release)
