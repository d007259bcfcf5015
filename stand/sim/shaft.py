"""The simulated drive's shaft: the motor (:mod:`stand.core.motor`) that turns the scene's
rotor, on the scene's clock, with the faults of the scene's ``[effects.drive]``; each
simulated drive family (:mod:`stand.sim.drive`, :mod:`stand.sim.servo`) speaks its own
protocol on top of it.

The scene's shaft and the drive's are one: the scene is simulated with the run-up the
motor gives (:func:`drive_scene`), and the shaft's clock starts when the scene's player
sends its first frame (:meth:`SimShaft.start_clock`), so the angle the drive reports is
the angle the sensors' frames come from.  After the measurement the drive's own commands
(brake, stop at an angle, quick stop) move the shaft from where the scene left it.
"""

from __future__ import annotations

import math
import threading
import time
from typing import Any

from stand.core.motor import (
    Motor,
    Trajectory,
    at_rest,
    quick_stop,
    ramp_to,
    stop_at,
    stop_at_position,
)

RPM = math.pi / 30.0
AT_SPEED = 0.005
"""The drive's at-speed window: within 0.5 % of the set point."""
STANDSTILL_RAD_S = 0.01
"""Below this the drive says standstill (0.1 rpm)."""


class SimShaft:
    """Commands in, motion out, on the monotonic clock.  Call its methods with ``lock``
    held (a server's threads read and write it at once).

    ``gamma_rad``: where the reference sensor sees the mark (the scene's), so that the
    reported angle counts from the mark passing the sensor.  ``effects``: the scene's
    ``[effects.drive]`` (None: a healthy drive, guard closed).
    """

    def __init__(self, motor: Motor, gamma_rad: float, effects: Any = None) -> None:
        self.motor, self.gamma, self.fx = motor, gamma_rad, effects
        self.path: Trajectory = at_rest()
        self.t0: float | None = None
        self.pending: float | None = None
        self.set_point = 0.0
        self.mode = "off"
        self.lock = threading.RLock()

    def start_clock(self, t0_monotonic: float) -> None:
        """The scene's physics time 0 is this instant: a run asked for starts now."""
        with self.lock:
            self.t0 = t0_monotonic
            if self.pending is not None:
                self._ramp(0.0, self.pending)

    def now(self) -> float:
        """The drive's time [s] since the scene started (0 before)."""
        return 0.0 if self.t0 is None else time.monotonic() - self.t0

    def _ramp(self, t: float, omega: float) -> None:
        over = 1.0 + (getattr(self.fx, "overspeed_pct", 0.0) or 0.0) / 100
        stall = getattr(self.fx, "stall_rpm", None)
        self.set_point, self.mode = omega, "run"
        top = omega * over if stall is None else min(omega * over, stall * RPM)
        self.path = ramp_to(self.path, t, self.motor, top)

    def run(self, omega: float) -> bool:
        """Run at ``omega`` [rad/s] (from the scene's start, if it has not started); False:
        the hardware interlock refuses (a fault, the guard open)."""
        t = self.now()
        if self.fault_code() or not self.guard_closed(t):
            return False
        if self.t0 is None:
            self.pending, self.set_point, self.mode = omega, omega, "run"
        else:
            self._ramp(t, omega)
        return True

    def stop(self, mode: str = "stop") -> None:
        """Full braking to rest."""
        self.path = quick_stop(self.path, self.now(), self.motor)
        self.mode, self.pending = mode, None

    def stop_at_angle(self, angle_from_mark_rad: float) -> None:
        """Brake (or turn) to rest at this angle from the mark (mod a revolution)."""
        target = angle_from_mark_rad + self.gamma
        self.path, self.mode = stop_at(self.path, self.now(), self.motor, target), "index"

    def stop_at_position(self, position_from_mark_rad: float) -> None:
        """Brake (or turn) to rest at this unwrapped angle from the mark."""
        target = position_from_mark_rad + self.gamma
        self.path = stop_at_position(self.path, self.now(), self.motor, target)
        self.mode = "index"

    def guard_closed(self, t: float) -> bool:
        fx = self.fx
        if fx is None:
            return True
        if fx.guard_open:
            return False
        return fx.guard_opens_at_s is None or self.t0 is None or t < fx.guard_opens_at_s

    def fault_code(self) -> int:
        return int(getattr(self.fx, "fault_code", 0) or 0)

    def state(self) -> tuple[float, float, float, bool]:
        """``(t, speed as reported, unwrapped angle from the mark, guard closed)`` now; an
        open guard cuts the drive's power (the shaft brakes)."""
        t = self.now()
        guard = self.guard_closed(t)
        if not guard and self.mode == "run":
            self.stop()
        scale = getattr(self.fx, "speed_scale", 1.0) or 1.0
        return (t, float(self.path.omega(t)) * scale, float(self.path.theta(t)) - self.gamma,
                guard)  # fmt: skip

    def at_speed(self, t: float) -> bool:
        w = float(self.path.omega(t))
        return self.mode == "run" and abs(w - self.set_point) <= AT_SPEED * self.set_point

    def in_position(self, t: float) -> bool:
        return self.mode == "index" and t >= self.path.end_s

    def true_angle_rad(self) -> float:
        """The shaft's angle from the mark now, exactly (for the tests' truth) [rad]."""
        with self.lock:
            return (float(self.path.theta(self.now())) - self.gamma) % (2 * math.pi)


def drive_scene(scene: Any, motor: Motor, rpm: float) -> Any:
    """The scene run by the drive: at ``rpm``, from standstill on the ramp the motor's torque
    gives (``[effects.run_up] ramp_s = w / a_up``), so that the frames come from the shaft
    the simulated drive turns."""
    from stand.sim.tables import RunUp

    ramp = rpm * RPM / motor.accel_rad_s2
    effects = scene.effects.model_copy(update={"run_up": RunUp(ramp_s=ramp)})
    run = scene.run.model_copy(update={"rpm": rpm})
    return scene.model_copy(update={"run": run, "effects": effects})
