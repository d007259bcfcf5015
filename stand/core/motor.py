"""The drive's shaft: run-up within a torque limit, braking, a stop at a given angle.

A rigid shaft of polar inertia ``J`` (rotor and drive) driven by a torque at most
``T``, braked by at most ``T_b``, against a constant drag ``T_f`` (bearings, air):
every motion is a chain of constant-acceleration pieces (:class:`Trajectory`), so
angle and speed are exact at any time, with no integration step.

- run-up to a set point at ``a_up = (T - T_f) / J``, braking at ``a_dn = (T_b + T_f) / J``
  (:func:`ramp_to`, :func:`quick_stop`);
- the **index**: from speed ``w`` the shaft turns ``w^2 / (2 a)`` while it brakes at ``a``;
  it holds its speed for the extra angle ``e`` in ``[0, 2 pi)`` that makes it come to
  rest at the target (the rule of the automatic-positioning patents: the stop computed
  from the measured phase and the deceleration), braking at
  :data:`INDEX_DECEL_SHARE` of ``a_dn`` so that a drive replanning each control cycle
  keeps a reserve (:func:`stop_at`); from rest, a move to the target in the direction of
  rotation (:func:`turn_to`);
- the **floors** of a cycle (:func:`floors`): run-up ``J w / T``, braking ``J w / T_b``
  (the drag only helps the brake and only hinders the run-up: the floors leave it out).

Angles in rad from the reference mark in the direction of rotation, speeds in rad/s,
times in s.  Arrays in, arrays out; no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stand.errors import ModelError, ParameterError

FloatArray = NDArray[np.float64]

TWO_PI = 2.0 * math.pi

INDEX_DECEL_SHARE = 0.9
"""The share of the full braking a stop at an angle plans with: the drive's position loop
keeps 10 % of its torque to correct the last control cycle's error (a stop that started
one cycle late needs ``w dt`` more angle than it has; at 1500 rpm and a 1 ms cycle that
is 9 deg, recovered with under 2 % more deceleration from 13 revolutions of braking)."""


@dataclass(frozen=True)
class Motor:
    """The shaft and its drive (SI): inertia, torque limit, brake torque, drag."""

    inertia_kg_m2: float
    torque_n_m: float
    brake_torque_n_m: float
    friction_n_m: float = 0.0

    def __post_init__(self) -> None:
        for name in ("inertia_kg_m2", "torque_n_m", "brake_torque_n_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ParameterError(name, f"{value!r}, expected a positive number")
        if not (math.isfinite(self.friction_n_m) and 0 <= self.friction_n_m < self.torque_n_m):
            raise ParameterError(
                "friction_n_m",
                f"{self.friction_n_m!r}, expected at least 0 and below the torque limit "
                f"{self.torque_n_m:g} N m (else the drive never turns the rotor)",
            )

    @property
    def accel_rad_s2(self) -> float:
        """The run-up's acceleration at the torque limit [rad/s^2]."""
        return (self.torque_n_m - self.friction_n_m) / self.inertia_kg_m2

    @property
    def decel_rad_s2(self) -> float:
        """The full braking deceleration, brake and drag together [rad/s^2]."""
        return (self.brake_torque_n_m + self.friction_n_m) / self.inertia_kg_m2


@dataclass(frozen=True)
class Floors:
    """The shortest times physics allows a cycle's moving phases [s]."""

    runup_s: float
    brake_s: float
    index_s: float
    """One revolution at the measuring speed: the most a stop at an angle waits."""


def floors(motor: Motor, omega_rad_s: float) -> Floors:
    """Run-up ``J w / T``, braking ``J w / T_b``, one revolution ``2 pi / w``."""
    J, w = motor.inertia_kg_m2, omega_rad_s
    return Floors(J * w / motor.torque_n_m, J * w / motor.brake_torque_n_m, TWO_PI / w)


@dataclass(frozen=True)
class Trajectory:
    """Constant-acceleration pieces: piece ``k`` starts at ``t_s[k]`` with angle
    ``theta_rad[k]`` and speed ``omega_rad_s[k]``, accelerating at ``alpha_rad_s2[k]``;
    the last piece lasts forever (its acceleration is 0 once it is a hold or at rest)."""

    t_s: tuple[float, ...]
    theta_rad: tuple[float, ...]
    omega_rad_s: tuple[float, ...]
    alpha_rad_s2: tuple[float, ...]

    def _piece(self, t: FloatArray) -> tuple[NDArray[np.intp], FloatArray]:
        k = np.clip(np.searchsorted(np.asarray(self.t_s), t, side="right") - 1, 0, None)
        return k, t - np.asarray(self.t_s)[k]

    def theta(self, t: ArrayLike) -> FloatArray:
        """The angle at ``t`` [rad] (unwrapped)."""
        k, dt = self._piece(np.asarray(t, dtype=float))
        th, w, a = (np.asarray(x)[k] for x in (self.theta_rad, self.omega_rad_s, self.alpha_rad_s2))
        result: FloatArray = th + w * dt + 0.5 * a * dt * dt
        return result

    def omega(self, t: ArrayLike) -> FloatArray:
        """The speed at ``t`` [rad/s]."""
        k, dt = self._piece(np.asarray(t, dtype=float))
        result: FloatArray = np.asarray(self.omega_rad_s)[k] + np.asarray(self.alpha_rad_s2)[k] * dt
        return result

    @property
    def end_s(self) -> float:
        """When the last piece starts: the motion is settled (at speed or at rest)."""
        return self.t_s[-1]

    def then(self, t_s: float, alpha_rad_s2: float, omega_rad_s: float | None = None
             ) -> Trajectory:  # fmt: skip
        """This trajectory up to ``t_s``, then a piece accelerating at ``alpha_rad_s2``
        (from ``omega_rad_s`` where the caller knows it exactly: a set point, rest)."""
        n = sum(1 for t in self.t_s if t < t_s)
        th = float(self.theta(t_s))
        w = float(self.omega(t_s)) if omega_rad_s is None else omega_rad_s
        return Trajectory(
            (*self.t_s[:n], t_s),
            (*self.theta_rad[:n], th),
            (*self.omega_rad_s[:n], w),
            (*self.alpha_rad_s2[:n], alpha_rad_s2),
        )


def at_rest(theta_rad: float = 0.0, t_s: float = 0.0) -> Trajectory:
    """A shaft at rest at ``theta_rad``."""
    return Trajectory((t_s,), (theta_rad,), (0.0,), (0.0,))


def ramp_to(path: Trajectory, t_s: float, motor: Motor, omega_set_rad_s: float) -> Trajectory:
    """From ``t_s`` on, to the set point at the full torque (or brake), then hold it."""
    w = float(path.omega(t_s))
    if omega_set_rad_s == w:
        return path.then(t_s, 0.0)
    a = motor.accel_rad_s2 if omega_set_rad_s > w else -motor.decel_rad_s2
    reach = t_s + (omega_set_rad_s - w) / a
    return path.then(t_s, a).then(reach, 0.0, omega_set_rad_s)


def quick_stop(path: Trajectory, t_s: float, motor: Motor) -> Trajectory:
    """From ``t_s`` on, full braking to rest."""
    return ramp_to(path, t_s, motor, 0.0)


def stop_at(path: Trajectory, t_s: float, motor: Motor, target_rad: float,
            share: float = INDEX_DECEL_SHARE) -> Trajectory:  # fmt: skip
    """From ``t_s`` on, hold the speed, then brake at ``share`` of the full braking so as
    to come to rest with the angle at ``target_rad`` (mod ``2 pi``); from rest,
    :func:`turn_to`."""
    return stop_at_position(path, t_s, motor, nearest_stop(path, t_s, motor, target_rad, share),
                            share)  # fmt: skip


def nearest_stop(path: Trajectory, t_s: float, motor: Motor, target_rad: float,
                 share: float = INDEX_DECEL_SHARE) -> float:  # fmt: skip
    """The first unwrapped angle ``= target_rad (mod 2 pi)`` the shaft can stop at from its
    state at ``t_s``, braking at ``share`` of the full figure [rad]: what a host asks a
    drive's profile position for."""
    w = max(float(path.omega(t_s)), 0.0)
    ahead = float(path.theta(t_s)) + w * w / (2 * share * motor.decel_rad_s2)
    return ahead + (target_rad - ahead) % TWO_PI


def stop_at_position(path: Trajectory, t_s: float, motor: Motor, position_rad: float,
                     share: float = INDEX_DECEL_SHARE) -> Trajectory:  # fmt: skip
    """From ``t_s`` on, come to rest at the unwrapped angle ``position_rad``: at speed, hold
    it, then brake at ``share`` of the full braking (harder, up to the full, when the
    position is nearer); from rest, :func:`turn_to`.

    Raises
    ------
    ModelError
        The position lies behind, or nearer than the full braking allows.
    """
    w, d = float(path.omega(t_s)), position_rad - float(path.theta(t_s))
    if w <= 0.0:
        if d < 0.0:
            raise ModelError(f"a stop {-d:.3g} rad behind the shaft: it turns forward only")
        return turn_to(path, t_s, motor, position_rad, share)
    if d < w * w / (2 * motor.decel_rad_s2):
        raise ModelError(f"a stop {d:.3g} rad ahead at {w:.3g} rad/s: nearer than braking allows")
    a = max(share * motor.decel_rad_s2, w * w / (2 * d))
    begin = t_s + (d - w * w / (2 * a)) / w
    return path.then(t_s, 0.0).then(begin, -a).then(begin + w / a, 0.0, 0.0)


def turn_to(path: Trajectory, t_s: float, motor: Motor, target_rad: float,
            share: float = INDEX_DECEL_SHARE) -> Trajectory:  # fmt: skip
    """From rest at ``t_s``, turn in the direction of rotation to ``target_rad``: an
    unwrapped angle ahead, or (mod ``2 pi``) the next one: accelerate, then brake, each
    at ``share`` of the full figure (the shortest move the torques allow, with the
    position loop's reserve)."""
    d = target_rad - float(path.theta(t_s))
    if not 0.0 <= d < 2 * TWO_PI:
        d %= TWO_PI
    if d == 0.0:
        return path.then(t_s, 0.0)
    a1, a2 = share * motor.accel_rad_s2, share * motor.decel_rad_s2
    peak = math.sqrt(2 * d * a1 * a2 / (a1 + a2))
    t1 = t_s + peak / a1
    return path.then(t_s, a1).then(t1, -a2).then(t1 + peak / a2, 0.0, 0.0)


def wrap_deg(angle_deg: float) -> float:
    """An angle difference in ``(-180, 180]`` deg."""
    return -((-angle_deg + 180.0) % 360.0 - 180.0)
