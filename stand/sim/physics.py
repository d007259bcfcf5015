"""The physics of a scene: shaft speed, support accelerations, reference edges.

Pure numerics on top of :mod:`stand.core` (no I/O, no frames).  Two paths:

* **closed form** when every effect named is linear and steady: the support
  acceleration is ``Re(A(w(t)) e^{i theta(t)})`` with ``A`` from
  :func:`stand.core.forward`.  Speed ripple and drift are taken
  quasi-steadily (``A`` follows the momentary speed; a bending rotor's through
  :func:`beam_phasors`); that is exact for a
  constant speed and good while the speed changes slowly against the
  supports' settling time.
* **time integration** (:func:`stand.core.transient.integrate`) when the
  scene calls for a run-up from standstill or a nonlinear support (dry
  friction, clearance), or asks for it (``physics = "integrate"``).

Time ``t`` is the physics' own; the recording covers
``[t_start, t_start + seconds]`` (``t_start`` is a settling time on the
integration path without run-up, else 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from stand.core import forward
from stand.core.beam import forward_beam
from stand.core.model import FloatArray, StandParameters
from stand.core.transient import (
    Progress,
    SupportForce,
    integrate,
    smooth_sign,
    steady_state_initial,
)
from stand.errors import ModelError


@dataclass(frozen=True)
class SceneSpeed:
    """Shaft speed: linear ramp from standstill, a hold, then ripple and drift; then,
    where ``coast_s`` is given, a linear coast-down to standstill.

    ``w(t) = w0 t / ramp_s`` for ``t < ramp_s`` (or the torque-limited profile above
    ``base_omega_rad_s``: :meth:`_ramp`); ``w0`` until
    ``ramp_s + hold_s``; then ``w0 (1 + ripple sin(2 pi f tau) + drift tau)``
    with ``tau`` the time since.  From ``coast_at_s`` on, ``w_c (1 - s / coast_s)``
    with ``w_c`` the speed then and ``s`` the time since, zero once it stands.
    ``theta`` is its exact integral from ``theta0_rad``.  Implements
    :class:`stand.core.transient.Speed`.
    """

    omega0_rad_s: float
    end_s: float
    ramp_s: float = 0.0
    hold_s: float = 0.0
    ripple: float = 0.0
    ripple_hz: float = 1.0
    drift_per_s: float = 0.0
    theta0_rad: float = 0.0
    coast_at_s: float = 0.0
    coast_s: float = 0.0
    base_omega_rad_s: float = 0.0

    @property
    def _t1(self) -> float:
        return self.ramp_s + self.hold_s

    def _omega(self, t: FloatArray) -> FloatArray:
        tau = np.maximum(t - self._t1, 0.0)
        steady = self.omega0_rad_s * (1 + self.drift_per_s * tau)
        if self.ripple:  # (a term left out where it is zero: the integrators call these often)
            steady = steady + self.omega0_rad_s * self.ripple * np.sin(
                2 * math.pi * self.ripple_hz * tau
            )
        if self.ramp_s > 0:
            ramp = (self._ramp(t)[0] if self._torque_limited
                    else self.omega0_rad_s * np.clip(t, 0.0, None) / self.ramp_s)  # fmt: skip
            steady = np.where(t < self.ramp_s, ramp, steady)
        result: FloatArray = steady
        return result

    @property
    def _torque_limited(self) -> bool:
        return 0 < self.base_omega_rad_s < self.omega0_rad_s

    def _ramp(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Speed [rad/s], acceleration [rad/s^2] and angle turned [rad] at ``t`` (clipped to
        the ramp) on the run-up: linear; or, with ``base_omega_rad_s`` below the top, the
        torque-limited profile an inverter gives: a constant acceleration ``a`` to the base
        speed ``w_b``, then constant power (``w w' = a w_b``: ``w^2`` grows linearly),
        ``a = (w_b^2 + w0^2) / (2 w_b ramp_s)`` so that ``w0`` is reached at ``ramp_s``."""
        w0, tr, wb = self.omega0_rad_s, self.ramp_s, self.base_omega_rad_s
        t = np.clip(t, 0.0, tr)
        if not 0 < wb < w0:
            a = w0 / tr
            return a * t, np.full_like(t, a), 0.5 * a * t * t
        a = (wb * wb + w0 * w0) / (2 * wb * tr)
        tb = wb / a
        w = np.where(t < tb, a * t, np.sqrt(wb * wb + 2 * a * wb * np.maximum(t - tb, 0.0)))
        th = np.where(t < tb, 0.5 * a * t * t, 0.5 * a * tb * tb + (w**3 - wb**3) / (3 * a * wb))
        return w, np.where(t < tb, a, a * wb / np.maximum(w, 1e-300)), th

    def _alpha(self, t: FloatArray) -> FloatArray:
        tau = t - self._t1
        f = 2 * math.pi * self.ripple_hz
        steady: FloatArray | float = self.omega0_rad_s * self.drift_per_s
        if self.ripple:
            steady = steady + self.omega0_rad_s * self.ripple * f * np.cos(f * tau)
        result: FloatArray = np.where(tau >= 0, steady, 0.0)
        if self.ramp_s > 0:
            ramp = self._ramp(t)[1] if self._torque_limited else self.omega0_rad_s / self.ramp_s
            result = np.where(t < self.ramp_s, ramp, result)
        return result

    def _theta(self, t: FloatArray) -> FloatArray:
        w0 = self.omega0_rad_s
        f = 2 * math.pi * self.ripple_hz
        tau = np.maximum(t - self._t1, 0.0)
        up = self._ramp_turned
        at_t1 = self.theta0_rad + up + w0 * self.hold_s
        steady = at_t1 + w0 * (tau + 0.5 * self.drift_per_s * tau * tau)
        if self.ripple:
            steady = steady + w0 * self.ripple * (1 - np.cos(f * tau)) / f
        hold = self.theta0_rad + up + w0 * (t - self.ramp_s)
        result: FloatArray = np.where(t < self._t1, hold, steady)
        if self.ramp_s > 0:
            ramp = (self._ramp(t)[2] if self._torque_limited
                    else 0.5 * w0 * np.clip(t, 0.0, None) ** 2 / self.ramp_s)  # fmt: skip
            result = np.where(t < self.ramp_s, self.theta0_rad + ramp, result)
        return result

    @cached_property
    def _ramp_turned(self) -> float:
        """The angle the run-up turned [rad] (once: the integrators call the law often)."""
        if self.ramp_s <= 0:
            return 0.0
        if not self._torque_limited:
            return 0.5 * self.omega0_rad_s * self.ramp_s
        return float(self._ramp(np.array(self.ramp_s))[2])

    @cached_property
    def _coast_start(self) -> tuple[float, float]:
        """The speed [rad/s] and angle [rad] where the coast-down begins (once)."""
        tc = np.array(self.coast_at_s)
        return float(self._omega(tc)), float(self._theta(tc))

    def _coasting(self, t: FloatArray) -> tuple[FloatArray, float, float]:
        """The time into the coast-down at ``t`` (clipped to it: negative before, at most
        ``coast_s``), and the speed [rad/s] and angle [rad] where it began."""
        return np.minimum(t - self.coast_at_s, self.coast_s), *self._coast_start

    def omega(self, t: ArrayLike) -> FloatArray:
        t = np.asarray(t, dtype=float)
        if self.coast_s <= 0:
            return self._omega(t)
        s, wc, _ = self._coasting(t)
        out: FloatArray = np.where(s >= 0, wc * (1 - s / self.coast_s), self._omega(t))
        return out

    def alpha(self, t: ArrayLike) -> FloatArray:
        t = np.asarray(t, dtype=float)
        if self.coast_s <= 0:
            return self._alpha(t)
        s, wc, _ = self._coasting(t)
        braking = (s >= 0) & (t - self.coast_at_s < self.coast_s)
        out: FloatArray = np.where(
            braking, -wc / self.coast_s, np.where(s >= 0, 0.0, self._alpha(t))
        )
        return out

    def theta(self, t: ArrayLike) -> FloatArray:
        t = np.asarray(t, dtype=float)
        if self.coast_s <= 0:
            return self._theta(t)
        s, wc, thc = self._coasting(t)
        coast = thc + wc * (s - 0.5 * s * s / self.coast_s)
        out: FloatArray = np.where(s >= 0, coast, self._theta(t))
        return out

    @property
    def max_omega_rad_s(self) -> float:
        tau = max(self.end_s - self._t1, 0.0)
        return self.omega0_rad_s * (1 + self.ripple + max(self.drift_per_s * tau, 0.0))


def edge_times(speed: SceneSpeed, gamma_rad: float, t0_s: float, t1_s: float) -> FloatArray:
    """Times in ``[t0_s, t1_s]`` when the mark passes the reference sensor.

    The mark is at ``theta`` from the accelerometer axis and the sensor at
    ``gamma``: an edge is ``theta(t) = gamma + 2 pi k``.  Found by
    interpolation on a fine grid, then polished by Newton steps (to ~1e-12 s).
    """
    n = max(2000, int(40 * speed.max_omega_rad_s * (t1_s - t0_s) / (2 * math.pi)))
    tg = np.linspace(t0_s, t1_s, n)
    th = speed.theta(tg)
    k = np.arange(
        math.ceil((th[0] - gamma_rad) / (2 * math.pi)),
        math.floor((th[-1] - gamma_rad) / (2 * math.pi)) + 1,
    )
    target = gamma_rad + 2 * math.pi * k
    t = np.interp(target, th, tg)
    for _ in range(4):
        w = speed.omega(t)
        step = np.where(w > 1e-12, (speed.theta(t) - target) / np.maximum(w, 1e-12), 0.0)
        t = np.clip(t - step, t0_s, t1_s)
    result: FloatArray = t
    return result


def closed_form(
    p: StandParameters,
    speed: SceneSpeed,
    U_kg_m: np.ndarray,
    t_s: FloatArray,
    beam: Any = None,
    U_nodes_kg_m: Any = None,
) -> FloatArray:
    """Support accelerations ``Re(A(w(t)) e^{i theta(t)})`` [m/s^2], shape (n, 2); with
    ``beam`` (:class:`stand.core.beam.BeamRotor`) the rotor bends, with
    ``U_nodes_kg_m`` an unbalance spread along it too; a changing speed is followed
    quasi-steadily, as for the rigid rotor (:func:`beam_phasors`)."""
    w = speed.omega(t_s)
    if speed.ripple == 0 and speed.drift_per_s == 0:  # one speed: one forward
        A = np.broadcast_to(
            steady_forward(p, beam, float(w[0]), U_kg_m, U_nodes_kg_m), (len(t_s), 2)
        )
    elif beam is None:
        A = forward(p, w, U_kg_m)
    else:
        A = beam_phasors(lambda x: steady_forward(p, beam, x, U_kg_m, U_nodes_kg_m), w)
    result: FloatArray = (A * np.exp(1j * speed.theta(t_s))[:, None]).real
    return result


def steady_forward(
    p: StandParameters, beam: Any, omega_rad_s: float, U_kg_m: Any, U_nodes_kg_m: Any = None
) -> Any:
    """The support phasors at one speed: the rigid rotor's, or the bending one's (with its
    distributed unbalance, if any)."""
    if beam is None:
        return forward(p, omega_rad_s, U_kg_m)

    return forward_beam(beam, p, omega_rad_s, U_kg_m, U_nodes_kg_m)


#: error allowed in :func:`beam_phasors`, relative to the largest phasor: ten times the
#: scatter of the beam solves themselves near a rigid-body mode (about 1e-7: roundoff in
#: a dynamic stiffness whose condition number is 4e9 on the auger; 3e-9 away from the
#: modes), 200 times below what the 16-bit counts resolve of a 0.5 m/s^2 phasor at the
#: demo's 1e-4 m/s^2 per count
BEAM_INTERPOLATION_RTOL = 1e-6


def beam_phasors(exact: Any, omega_rad_s: FloatArray, rtol: float = BEAM_INTERPOLATION_RTOL) -> Any:
    """The bending stand's phasors followed quasi-steadily over a changing speed.

    One beam solve per sample is too slow, so the phasors are computed on a grid over
    the speeds that occur and interpolated (cubic spline, complex, per support).  The
    grid is halved until the spline's error at the midpoints of the grid, where it
    is largest, is below ``rtol`` of the largest phasor: the error is measured, not
    assumed.

    Parameters
    ----------
    exact : callable
        ``exact(omega_rad_s: float) -> (2,) complex``, the phasors [m/s^2] at one speed.
    omega_rad_s : ndarray
        The momentary speed of every sample [rad/s].

    Returns
    -------
    ndarray, shape (n, 2), complex
        The phasors at every sample [m/s^2].
    """
    from scipy.interpolate import CubicSpline

    lo, hi = float(np.min(omega_rad_s)), float(np.max(omega_rad_s))
    if hi - lo <= 1e-12 * hi:
        return np.broadcast_to(exact(hi), (len(omega_rad_s), 2))
    grid = np.linspace(lo, hi, 17)
    values = np.array([exact(float(x)) for x in grid])
    while True:
        mids = 0.5 * (grid[:-1] + grid[1:])
        at_mids = np.array([exact(float(x)) for x in mids])
        err = np.max(np.abs(CubicSpline(grid, values)(mids) - at_mids))
        grid = np.insert(grid, np.arange(1, len(grid)), mids)  # now includes the midpoints
        values = np.insert(values, np.arange(1, len(values)), at_mids, axis=0)
        if err <= rtol * np.max(np.abs(values)):
            return CubicSpline(grid, values)(omega_rad_s)
        if len(grid) > 4096:
            raise ModelError(
                f"the bending stand's phasors could not be interpolated to {rtol:g} over "
                f"{lo:.6g}..{hi:.6g} rad/s (error {err:.3g} m/s^2 with {len(grid)} speeds): "
                "the speed sweeps too close to a natural frequency of the stand"
            )


def support_force(
    p: StandParameters,
    friction_n: list[float] | None,
    friction_beta_s_m: list[float] | None,
    gap_m: list[float] | None,
    gap_beta_per_m: list[float] | None,
) -> SupportForce:
    """The nonlinear support force: dry friction and clearance, smoothed (seed 003).

    Friction: ``-F_i (2/pi) arctan(beta v_i)``.  Clearance: the spring acts on
    the dead-band displacement ``dz(x) = (x - g)(1 + s(x - g))/2 + (x + g)(1 - s(x + g))/2``
    (``s`` the smooth sign) instead of ``x``, i.e. the force ``C_i (x - dz(x))``
    is added back.
    """
    K = np.array([p.C1, p.C2])[:, None]

    def force(x: FloatArray, v: FloatArray) -> FloatArray:
        S = np.zeros_like(x)
        if friction_n is not None and friction_beta_s_m is not None:
            for i in range(2):
                S[i] -= friction_n[i] * smooth_sign(v[i], friction_beta_s_m[i])
        if gap_m is not None and gap_beta_per_m is not None:
            for i in range(2):
                g, beta = gap_m[i], gap_beta_per_m[i]
                dz = 0.5 * (x[i] - g) * (1 + smooth_sign(x[i] - g, beta)) + 0.5 * (x[i] + g) * (
                    1 - smooth_sign(x[i] + g, beta)
                )
                S[i] += K[i, 0] * (x[i] - dz)
        return S

    return force


def integrated(
    p: StandParameters,
    speed: SceneSpeed,
    U_kg_m: np.ndarray,
    t_s: FloatArray,
    *,
    force: SupportForce | None,
    rtol: float,
    from_steady: bool,
    progress: Progress | None = None,
) -> tuple[FloatArray, int]:
    """Support accelerations by time integration at times ``t_s`` (any order), and ``nfev``.

    ``from_steady`` starts on the linear steady orbit (no run-up), else at rest.
    """

    t_unique, back = np.unique(np.maximum(t_s, 0.0), return_inverse=True)  # solve_ivp: increasing
    method = "LSODA" if force is not None else "DOP853"
    y0 = (
        steady_state_initial(p, speed.omega0_rad_s, U_kg_m, speed.theta0_rad)
        if from_steady
        else None
    )
    res = integrate(
        p,
        speed,
        U_kg_m,
        t_unique,
        y0=y0,
        method=method,
        rtol=rtol,
        support_force=force,
        progress=progress,
    )
    a: FloatArray = res.a_m_s2[back]
    return a, res.nfev
