"""A simulated CiA 402 servo drive: a ``canopen`` ``LocalNode`` built from
``drivers/cia402/cia402_servo.eds`` that answers SDO from its object dictionary as a real
drive would, its state machine and profile modes on the simulated shaft
(:class:`stand.sim.shaft.SimShaft`, which turns the scene's rotor).

The controlword (0x6040) walks CiA 402's states; in Operation enabled, profile velocity
(mode 3) runs to the target velocity (0x60FF), profile position (mode 1) stops the shaft
at the target position (0x607A) on a new set-point (bit 4); leaving Operation enabled
brakes the shaft (quick stop).  The statusword (0x6041), the actual velocity (0x606C) and
position (0x6064), the error code (0x603F) and the digital inputs (0x60FD: bit 3 the
guard's interlock) are read from the shaft when asked.  ``[effects.drive]``: a fault (the
drive in Fault with that code), a guard open, a drive that never answers (it is not on
the bus), a wrong velocity scaling.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from stand.core.motor import Motor
from stand.drivers.cia402.table import INTERLOCK_BIT, STATES, Cia402Table
from stand.sim.shaft import RPM, STANDSTILL_RAD_S, SimShaft

PROFILE_POSITION, PROFILE_VELOCITY = 1, 3
"""CiA 402's modes of operation (0x6060)."""


def eds_path() -> Path:
    """The simulated servo's EDS, where the package installs it."""
    import stand.drivers.cia402 as wing

    return Path(wing.__file__).with_name("cia402_servo.eds")


class SimServo(SimShaft):
    """CiA 402's state machine and profile modes on the simulated shaft."""

    def __init__(self, motor: Motor, table: Cia402Table, gamma_rad: float,
                 effects: Any = None) -> None:  # fmt: skip
        super().__init__(motor, gamma_rad, effects)
        self.map = table
        self.state_name = "FAULT" if self.fault_code() else "SWITCH ON DISABLED"
        self.op_mode, self.target_velocity, self.target_position, self.controlword = 0, 0, 0, 0

    def _statusword(self, t: float, w: float) -> int:
        value = STATES[self.state_name][1] | (1 << 9)  # remote
        if self.state_name == "OPERATION ENABLED":
            if (
                self.op_mode == PROFILE_POSITION
                and self.in_position(t)
                and abs(w) < STANDSTILL_RAD_S
            ):
                value |= 1 << 10
            if self.op_mode == PROFILE_VELOCITY and self.at_speed(t):
                value |= 1 << 10
        return value

    def read(self, index: int) -> int | None:
        """An object's value now (None: the dictionary's own)."""
        with self.lock:
            t, w, theta, guard = self.state()
            if not guard and self.state_name == "OPERATION ENABLED":
                self.state_name = "SWITCH ON DISABLED"  # safe torque off
            cpr, scale = self.map.counts_per_rev, self.map.velocity_per_rpm
            return {
                0x6041: lambda: self._statusword(t, w),
                0x606C: lambda: round(w / RPM * scale),
                0x6064: lambda: round(theta / (2 * math.pi) * cpr),
                0x603F: lambda: self.fault_code(),
                0x60FD: lambda: 0 if guard else 1 << INTERLOCK_BIT,
                0x6061: lambda: self.op_mode,
                0x6040: lambda: self.controlword,
            }.get(index, lambda: None)()

    def write(self, index: int, value: int) -> None:
        """An object written: the state machine and the profiles act."""
        with self.lock:
            if index == 0x6060:
                self.op_mode = value
            elif index == 0x60FF:
                self.target_velocity = value
                self._act()
            elif index == 0x607A:
                self.target_position = value
            elif index == 0x6040:
                rising = value & ~self.controlword
                self.controlword = value
                self._transition(value)
                if self.state_name == "OPERATION ENABLED" and rising & (1 << 4):
                    if self.op_mode == PROFILE_POSITION:
                        cpr = self.map.counts_per_rev
                        self.stop_at_position(2 * math.pi * self.target_position / cpr)

    def _transition(self, cw: int) -> None:
        """CiA 402's transitions by the controlword's command bits."""
        before, s = self.state_name, self.state_name
        if s == "FAULT":
            if cw & 0x80 and not self.fault_code():
                s = "SWITCH ON DISABLED"
        elif not cw & 0x02:
            s = "SWITCH ON DISABLED"  # disable voltage
        elif not cw & 0x04:
            s = "QUICK STOP ACTIVE" if s == "OPERATION ENABLED" else "SWITCH ON DISABLED"
        elif not cw & 0x01:
            s = "READY TO SWITCH ON" if s != "NOT READY TO SWITCH ON" else s  # shutdown
        elif not cw & 0x08:
            s = (
                "SWITCHED ON"
                if s in ("READY TO SWITCH ON", "OPERATION ENABLED", "SWITCHED ON")
                else s
            )
        elif s in ("SWITCHED ON", "QUICK STOP ACTIVE", "OPERATION ENABLED"):
            s = "OPERATION ENABLED" if self.guard_closed(self.now()) else s
        self.state_name = s
        if before == "OPERATION ENABLED" and s != before:
            self.stop()  # power off the profile: the drive brakes the shaft to rest
        elif s == "OPERATION ENABLED" and before != s:
            self._act()

    def _act(self) -> None:
        if self.state_name == "OPERATION ENABLED" and self.op_mode == PROFILE_VELOCITY:
            self.run(self.target_velocity / self.map.velocity_per_rpm * RPM)

    @contextmanager
    def serve(self, table: Cia402Table, bus: Any) -> Iterator[tuple[Cia402Table, Any]]:
        """On a private virtual CAN bus while inside: the table as given, and that bus."""
        import can
        import canopen

        channel = f"stand-servo-{os.getpid()}-{time.monotonic_ns()}"
        kwargs: dict[str, Any] = {"interface": "virtual", "channel": channel}
        if getattr(self.fx, "silent", False):  # nobody on the bus answers
            yield table, kwargs
            return
        sim_bus = can.Bus(**kwargs)
        network = canopen.Network(sim_bus)
        node = canopen.LocalNode(table.node_id, str(eds_path()))
        node.add_read_callback(lambda index, subindex, od: self.read(index))  # type: ignore[no-untyped-call]
        node.add_write_callback(  # type: ignore[no-untyped-call]
            lambda index, subindex, od, data: self.write(index, int(od.decode_raw(data)))
        )
        network.add_node(node)
        notifier = can.Notifier(sim_bus, network.listeners, 0.05)
        network.notifier = notifier
        try:
            yield table, kwargs
        finally:
            notifier.stop(1.0)
            sim_bus.shutdown()


def sim_servo(scene: Any, motor: Motor, table: Cia402Table) -> SimServo:
    """The servo a scene's stand has: its motor, the config's table, the scene's reference
    sensor and its ``[effects.drive]``."""
    return SimServo(motor, table, math.radians(scene.stand.reference_angle_deg),
                    scene.effects.drive)  # fmt: skip
