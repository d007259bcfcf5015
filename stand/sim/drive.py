"""A simulated frequency inverter on Modbus TCP, served on 127.0.0.1 as a real one would
be: the register map of :mod:`stand.drivers.modbus.table`, a motor
(:mod:`stand.core.motor`) that turns the simulated rotor.

The scene's shaft and the drive's are one: the scene is simulated with the run-up the
motor gives (a ramp at the torque limit, :func:`drive_scene`), and the drive's clock starts
when the scene's player sends its first frame (:meth:`SimDrive.start_clock`), so the angle
the drive reports is the angle the sensors' frames come from.  After the measurement the
drive's own commands (brake, stop at an angle, quick stop) move the shaft from where the
scene left it.

Faults for the tests and the demo come from the scene's ``[effects.drive]``: a guard open
from the start or opening at a time, a fault code, a drive that never answers, a speed
reported with a wrong scaling, a speed running over the set point.
"""

from __future__ import annotations

import asyncio
import math
import threading
import time
from typing import Any

from stand.core.motor import Motor, Trajectory, at_rest, quick_stop, ramp_to, stop_at
from stand.drivers.modbus.table import (
    CONTROL_INDEX,
    CONTROL_QUICK_STOP,
    CONTROL_RUN,
    ModbusTable,
    status_word,
)
from stand.errors import DriveError

RPM = math.pi / 30.0
AT_SPEED = 0.005
"""The drive's at-speed window: within 0.5 % of the set point."""
STANDSTILL_RAD_S = 0.01
"""Below this the drive says standstill (0.1 rpm)."""


class SimDrive:
    """The inverter's behaviour: commands in, state out, on the monotonic clock.

    ``gamma_rad``: where the reference sensor sees the mark (the scene's), so that the
    reported angle counts from the mark passing the sensor.  ``effects``: the scene's
    ``[effects.drive]`` (None: a healthy drive, guard closed).
    """

    def __init__(self, motor: Motor, table: ModbusTable, gamma_rad: float,
                 effects: Any = None) -> None:  # fmt: skip
        self.motor, self.map, self.gamma = motor, table, gamma_rad
        self.fx = effects
        self.path: Trajectory = at_rest()
        self.t0: float | None = None
        self.pending: float | None = None
        self.set_point = 0.0
        self.mode = "off"
        self.lock = threading.Lock()

    def start_clock(self, t0_monotonic: float) -> None:
        """The scene's physics time 0 is this instant: a run asked for starts now."""
        with self.lock:
            self.t0 = t0_monotonic
            if self.pending is not None:
                self._run(0.0, self.pending)

    def now(self) -> float:
        """The drive's time [s] since the scene started (0 before)."""
        return 0.0 if self.t0 is None else time.monotonic() - self.t0

    def _run(self, t: float, omega: float) -> None:
        over = 1.0 + (getattr(self.fx, "overspeed_pct", 0.0) or 0.0) / 100
        stall = getattr(self.fx, "stall_rpm", None)
        self.set_point, self.mode = omega, "run"
        top = omega * over if stall is None else min(omega * over, stall * RPM)
        self.path = ramp_to(self.path, t, self.motor, top)

    def command(self, word: int, set_point_counts: int, target_counts: int) -> None:
        """A control word written, with the set point and target registers as they are."""
        with self.lock:
            t = self.now()
            if word & CONTROL_QUICK_STOP:
                self.path, self.mode = quick_stop(self.path, t, self.motor), "stop"
                self.pending = None
            elif word & CONTROL_INDEX:
                angle = 2 * math.pi * target_counts / self.map.counts_per_rev + self.gamma
                self.path, self.mode = stop_at(self.path, t, self.motor, angle), "index"
            elif word & CONTROL_RUN:
                if self.fault_code() or not self.guard_closed(t):
                    return  # the hardware interlock: a drive in fault or behind an open guard
                omega = (set_point_counts - 0x10000 if set_point_counts & 0x8000
                         else set_point_counts) / self.map.speed_per_rpm * RPM  # fmt: skip
                if self.t0 is None:
                    self.pending, self.set_point, self.mode = omega, omega, "run"
                else:
                    self._run(t, omega)
            elif self.mode != "off":
                self.path, self.mode = quick_stop(self.path, t, self.motor), "off"

    def guard_closed(self, t: float) -> bool:
        fx = self.fx
        if fx is None:
            return True
        if fx.guard_open:
            return False
        return fx.guard_opens_at_s is None or self.t0 is None or t < fx.guard_opens_at_s

    def fault_code(self) -> int:
        return int(getattr(self.fx, "fault_code", 0) or 0)

    def registers(self) -> dict[int, int]:
        """The read registers' values now."""
        with self.lock:
            t = self.now()
            guard = self.guard_closed(t)
            if not guard and self.mode == "run":  # the interlock cuts the drive's power
                self.path, self.mode = quick_stop(self.path, t, self.motor), "stop"
            w = float(self.path.omega(t))
            theta = float(self.path.theta(t)) - self.gamma
        m, fault = self.map, self.fault_code()
        scale = getattr(self.fx, "speed_scale", 1.0) or 1.0
        still = abs(w) < STANDSTILL_RAD_S
        status = status_word(
            estop_clear=True, guard_closed=guard, fault=bool(fault), ready=not fault,
            standstill=still, in_position=still and self.mode == "index" and t >= self.path.end_s,
            at_speed=self.mode == "run" and abs(w - self.set_point) <= AT_SPEED * self.set_point,
        )  # fmt: skip
        speed = round(w * scale / RPM * m.speed_per_rpm) & 0xFFFF
        counts = round(theta % (2 * math.pi) / (2 * math.pi) * m.counts_per_rev) % m.counts_per_rev
        return {m.status: status, m.speed: speed, m.angle: counts, m.fault: fault}

    def true_angle_rad(self) -> float:
        """The shaft's angle from the mark now, exactly (for the tests' truth) [rad]."""
        with self.lock:
            return (float(self.path.theta(self.now())) - self.gamma) % (2 * math.pi)


class SimInverter:
    """:class:`SimDrive` served by pymodbus on 127.0.0.1 (a port of its own), in a thread.

    ``port``: the port it listens on once started.  Close it with :meth:`close`.
    """

    def __init__(self, drive: SimDrive) -> None:
        self.drive = drive
        self.port = 0
        self._loop = asyncio.new_event_loop()
        self._ready = threading.Event()
        self._stop: asyncio.Event | None = None
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._serve, daemon=True, name="sim-inverter")

    def __enter__(self) -> SimInverter:
        self._thread.start()
        if not self._ready.wait(10.0) or self._error is not None:
            raise DriveError(f"the simulated inverter did not start ({self._error})",
                             where="simulated inverter on 127.0.0.1") from self._error  # fmt: skip
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        if self._stop is not None and self._thread.is_alive():
            self._loop.call_soon_threadsafe(self._stop.set)
            self._thread.join(5.0)

    async def _action(self, function_code: int, start_address: int, address: int, count: int,
                      current_registers: list[int], set_values: Any) -> None:  # fmt: skip
        if getattr(self.drive.fx, "silent", False):
            await asyncio.sleep(3600.0)  # a drive that never answers
        m = self.drive.map
        for register, value in self.drive.registers().items():
            current_registers[register - start_address] = value
        if set_values is not None and address == m.control:
            regs = current_registers
            self.drive.command(int(set_values[0]), regs[m.set_point - start_address],
                               regs[m.target - start_address])  # fmt: skip

    def _serve(self) -> None:
        asyncio.set_event_loop(self._loop)
        try:
            self._loop.run_until_complete(self._main())
        except BaseException as exc:  # reported by __enter__
            self._error = exc
            self._ready.set()
        finally:
            self._loop.close()

    async def _main(self) -> None:
        from pymodbus.server import ModbusTcpServer
        from pymodbus.simulator import DataType, SimData, SimDevice

        m = self.drive.map
        size = max(m.control, m.set_point, m.target, m.status, m.speed, m.angle, m.fault) + 1
        device = SimDevice(id=m.unit, action=self._action,
                           simdata=[SimData(0, count=size, values=0,
                                            datatype=DataType.REGISTERS)])  # fmt: skip
        server: Any = ModbusTcpServer(device, address=("127.0.0.1", 0))
        await server.serve_forever(background=True)
        self.port = int(server.transport.sockets[0].getsockname()[1])
        self._stop = asyncio.Event()
        self._ready.set()
        await self._stop.wait()
        await server.shutdown()


def drive_scene(scene: Any, motor: Motor, rpm: float) -> Any:
    """The scene run by the drive: at ``rpm``, from standstill on the ramp the motor's torque
    gives (``[effects.run_up] ramp_s = w / a_up``), so that the frames come from the shaft
    the simulated drive turns."""
    from stand.sim.tables import RunUp

    ramp = rpm * RPM / motor.accel_rad_s2
    effects = scene.effects.model_copy(update={"run_up": RunUp(ramp_s=ramp)})
    run = scene.run.model_copy(update={"rpm": rpm})
    return scene.model_copy(update={"run": run, "effects": effects})


def sim_drive(scene: Any, motor: Motor, table: ModbusTable) -> SimDrive:
    """The drive a scene's stand has: its motor, the config's register map, the scene's
    reference sensor and its ``[effects.drive]``."""
    return SimDrive(motor, table, math.radians(scene.stand.reference_angle_deg),
                    scene.effects.drive)  # fmt: skip
