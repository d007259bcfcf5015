"""A simulated frequency inverter on Modbus TCP or RTU, served on 127.0.0.1 as a real one
would be (RTU: its frames, CRC and all, carried over TCP as a serial device server carries
them, or on a serial line the tests give): the register map of
:mod:`stand.drivers.modbus.table` on the simulated shaft (:class:`stand.sim.shaft.SimShaft`,
which turns the scene's rotor).

Faults for the tests and the demo come from the scene's ``[effects.drive]``: a guard open
from the start or opening at a time, a fault code, a drive that never answers (its
requests are never answered), a speed reported with a wrong scaling, a speed running over
the set point, a drive that stalls.
"""

from __future__ import annotations

import asyncio
import math
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from stand.core.motor import Motor
from stand.drivers.modbus.table import (
    CONTROL_INDEX,
    CONTROL_QUICK_STOP,
    CONTROL_RUN,
    ModbusTable,
    status_word,
)
from stand.errors import DriveError
from stand.sim.shaft import RPM, STANDSTILL_RAD_S, SimShaft


class SimDrive(SimShaft):
    """The inverter's registers on :class:`~stand.sim.shaft.SimShaft`: commands written,
    state read, as :mod:`stand.drivers.modbus.table` maps them."""

    def __init__(self, motor: Motor, table: ModbusTable, gamma_rad: float,
                 effects: Any = None) -> None:  # fmt: skip
        super().__init__(motor, gamma_rad, effects)
        self.map = table

    def command(self, word: int, set_point_counts: int, target_counts: int) -> None:
        """A control word written, with the set point and target registers as they are."""
        with self.lock:
            if word & CONTROL_QUICK_STOP:
                self.stop()
            elif word & CONTROL_INDEX:
                self.stop_at_angle(2 * math.pi * target_counts / self.map.counts_per_rev)
            elif word & CONTROL_RUN:
                self.run((set_point_counts - 0x10000 if set_point_counts & 0x8000
                          else set_point_counts) / self.map.speed_per_rpm * RPM)  # fmt: skip
            elif self.mode != "off":
                self.stop("off")

    def registers(self) -> dict[int, int]:
        """The read registers' values now."""
        with self.lock:
            t, w, theta, guard = self.state()
            at_speed, in_position = self.at_speed(t), self.in_position(t)
        m, fault = self.map, self.fault_code()
        still = abs(w) < STANDSTILL_RAD_S
        status = status_word(
            estop_clear=True, guard_closed=guard, fault=bool(fault), ready=not fault,
            standstill=still, in_position=still and in_position, at_speed=at_speed,
        )  # fmt: skip
        speed = round(w / RPM * m.speed_per_rpm) & 0xFFFF
        counts = round(theta % (2 * math.pi) / (2 * math.pi) * m.counts_per_rev) % m.counts_per_rev
        return {m.status: status, m.speed: speed, m.angle: counts, m.fault: fault}

    @contextmanager
    def serve(self, table: ModbusTable, bus: Any) -> Iterator[tuple[ModbusTable, Any]]:
        """Served on 127.0.0.1 while inside: the table pointing at it, and the bus as given."""
        with SimInverter(self) as server:
            if table.transport == "rtu":
                yield table.model_copy(update={"device": f"socket://127.0.0.1:{server.port}"}), bus
            else:
                yield table.model_copy(update={"host": "127.0.0.1", "port": server.port}), bus


class SimInverter:
    """:class:`SimDrive` served by pymodbus on 127.0.0.1 (a port of its own), in a thread:
    Modbus TCP, or RTU framing as the drive's map says; RTU on the serial line ``device``
    when one is given.

    ``port``: the port it listens on once started.  Close it with :meth:`close`.
    """

    def __init__(self, drive: SimDrive, device: str | None = None) -> None:
        self.drive = drive
        self.device = device
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
        from pymodbus.server import ModbusSerialServer, ModbusTcpServer
        from pymodbus.simulator import DataType, SimData, SimDevice

        m = self.drive.map
        size = max(m.control, m.set_point, m.target, m.status, m.speed, m.angle, m.fault) + 1
        device = SimDevice(id=m.unit, action=self._action,
                           simdata=[SimData(0, count=size, values=0,
                                            datatype=DataType.REGISTERS)])  # fmt: skip
        server: Any
        if m.transport == "rtu":
            server = ModbusSerialServer(device, port=self.device or "socket://127.0.0.1:0",
                                        baudrate=m.baudrate, parity=m.parity,
                                        stopbits=m.stopbits)  # fmt: skip
        else:
            server = ModbusTcpServer(device, address=("127.0.0.1", 0))
        await server.serve_forever(background=True)
        if self.device is None:
            self.port = int(server.transport.sockets[0].getsockname()[1])
        self._stop = asyncio.Event()
        self._ready.set()
        await self._stop.wait()
        await server.shutdown()


def sim_drive(scene: Any, motor: Motor, table: ModbusTable) -> SimDrive:
    """The inverter a scene's stand has: its motor, the config's register map, the scene's
    reference sensor and its ``[effects.drive]``."""
    return SimDrive(motor, table, math.radians(scene.stand.reference_angle_deg),
                    scene.effects.drive)  # fmt: skip
