"""The seed's equations integrated in time: run-up, speed changes, settling.

Pure numerics: arrays in, arrays out, SI units, no I/O.

In the support coordinates ``x = (x1, x2)`` the four equations of seed 002
with the rigid-rotor constraints become (see :mod:`stand.core.model`)::

    M x'' + H x' + K x = Q(t)

with ``M`` the symmetric mass matrix, ``K = diag(C1, C2)``,
``H = diag(H1, H2)`` and the generalised unbalance forces (lever rule)::

    Q1 = ((b + c + d) F1 + d F2) / L,    Q2 = (a F1 + (a + b + c) F2) / L

    F_i = q_i R_i (w^2 cos(theta - phi_i) + alpha sin(theta - phi_i))
        = w^2 Re(U_i e^{i theta}) + alpha Im(U_i e^{i theta})

The ``alpha`` term (angular acceleration) is the tangential inertia of the
unbalance mass; at constant speed it vanishes and ``F_i`` is the seed's
force term.

A nonlinear support (dry friction, a clearance) adds a force ``S(x, x')``
on the supports' side: ``M x'' + H x' + K x = Q(t) + S(x, x')``.  Its
discontinuities are smoothed as seed 003 does, ``sign(v) ~ (2/pi)
arctan(beta v)``, so one ODE system covers every regime
(:func:`smooth_sign`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stand.core.model import (
    ComplexArray,
    FloatArray,
    StandParameters,
    forward,
    mass_matrix,
    natural_frequencies,
)
from stand.errors import ModelError


@dataclass(frozen=True)
class SpeedProfile:
    """Shaft speed as a piecewise-linear function of time.

    ``omega`` is linear between the knots ``(t_s[k], omega_rad_s[k])`` and
    constant after the last one; ``theta`` is its exact integral.

    Parameters
    ----------
    t_s : array of float
        Knot times [s], strictly increasing, the first one 0.
    omega_rad_s : array of float
        Speed at the knots [rad/s], >= 0.
    theta0_rad : float
        Shaft angle at t = 0 [rad].

    Examples
    --------
    >>> sp = SpeedProfile.run_up(omega_rad_s=10.0, ramp_s=2.0)
    >>> float(sp.theta(2.0)), float(sp.omega(1.0)), float(sp.alpha(1.0)), float(sp.alpha(3.0))
    (10.0, 5.0, 5.0, 0.0)
    """

    t_s: tuple[float, ...]
    omega_rad_s: tuple[float, ...]
    theta0_rad: float = 0.0

    def __post_init__(self) -> None:
        t = np.asarray(self.t_s, dtype=float)
        w = np.asarray(self.omega_rad_s, dtype=float)
        if t.ndim != 1 or t.shape != w.shape or t.size == 0:
            raise ModelError("speed profile needs as many knot times as speeds, at least one")
        if t[0] != 0 or np.any(np.diff(t) <= 0):
            raise ModelError(f"speed profile knot times must start at 0 and increase, got {t}")
        if not np.all(np.isfinite(w)) or np.any(w < 0):
            raise ModelError(f"speed profile speeds must be finite and >= 0 rad/s, got {w}")

    @classmethod
    def constant(cls, omega_rad_s: float, theta0_rad: float = 0.0) -> SpeedProfile:
        """Constant speed from t = 0."""
        return cls((0.0,), (float(omega_rad_s),), theta0_rad)

    @classmethod
    def run_up(
        cls, omega_rad_s: float, ramp_s: float, omega_start_rad_s: float = 0.0
    ) -> SpeedProfile:
        """Linear run-up from ``omega_start_rad_s`` to ``omega_rad_s`` in ``ramp_s``, then steady.

        Examples
        --------
        >>> SpeedProfile.run_up(100.0, ramp_s=5.0).omega_rad_s
        (0.0, 100.0)
        """
        return cls((0.0, float(ramp_s)), (float(omega_start_rad_s), float(omega_rad_s)))

    def _segments(self, t: ArrayLike) -> tuple[FloatArray, NDArray[np.intp]]:
        tt = np.asarray(t, dtype=float)
        k = np.searchsorted(np.asarray(self.t_s), tt, side="right") - 1
        return tt, np.clip(k, 0, len(self.t_s) - 1)

    def _slopes(self) -> FloatArray:
        w = np.asarray(self.omega_rad_s)
        t = np.asarray(self.t_s)
        return np.append(np.diff(w) / np.diff(t), 0.0)

    def omega(self, t: ArrayLike) -> FloatArray:
        """Speed [rad/s] at times ``t`` [s]."""
        tt, k = self._segments(t)
        result: FloatArray = np.asarray(self.omega_rad_s)[k] + self._slopes()[k] * (
            tt - np.asarray(self.t_s)[k]
        )
        return result

    def alpha(self, t: ArrayLike) -> FloatArray:
        """Angular acceleration [rad/s^2] at times ``t`` [s]."""
        _, k = self._segments(t)
        result: FloatArray = self._slopes()[k]
        return result

    def theta(self, t: ArrayLike) -> FloatArray:
        """Shaft angle of the reference mark [rad] at times ``t`` [s]."""
        tk = np.asarray(self.t_s)
        wk = np.asarray(self.omega_rad_s)
        al = self._slopes()
        dt = np.diff(tk)
        theta_k = self.theta0_rad + np.concatenate(
            ([0.0], np.cumsum(wk[:-1] * dt + 0.5 * al[:-1] * dt**2))
        )
        tt, k = self._segments(t)
        tau = tt - tk[k]
        result: FloatArray = theta_k[k] + wk[k] * tau + 0.5 * al[k] * tau**2
        return result

    @property
    def max_omega_rad_s(self) -> float:
        """Largest speed of the profile [rad/s]."""
        return float(max(self.omega_rad_s))


class Speed(Protocol):
    """A shaft speed law: what :func:`integrate` needs (``SpeedProfile`` is one)."""

    def omega(self, t: ArrayLike) -> FloatArray: ...  # [rad/s]

    def alpha(self, t: ArrayLike) -> FloatArray: ...  # [rad/s^2]

    def theta(self, t: ArrayLike) -> FloatArray: ...  # [rad]

    @property
    def max_omega_rad_s(self) -> float: ...


SupportForce = Callable[[FloatArray, FloatArray], FloatArray]
"""``S(x, v)``: extra force on the supports [N], shape (2, n), from displacements and
velocities of shape (2, n)."""


def smooth_sign(x: ArrayLike, beta: float) -> FloatArray:
    """``(2/pi) arctan(beta x)``: seed 003's smooth stand-in for ``sign(x)``.

    >>> [round(float(s), 6) for s in smooth_sign([-1.0, 0.0, 1e-6, 1.0], 1e6)]
    [-0.999999, 0.0, 0.5, 0.999999]
    """
    result: FloatArray = (2.0 / math.pi) * np.arctan(beta * np.asarray(x, dtype=float))
    return result


@dataclass(frozen=True)
class TransientResult:
    """Time history of the supports.

    Attributes
    ----------
    t_s : ndarray, shape (n,)
    x_m : ndarray, shape (n, 2)
        Support displacements [m].
    a_m_s2 : ndarray, shape (n, 2)
        Support accelerations [m/s^2] (what the accelerometers read).
    theta_rad, omega_rad_s : ndarray, shape (n,)
        Shaft angle of the reference mark and speed.
    nfev : int
        Right-hand-side evaluations the solver used.
    """

    t_s: FloatArray
    x_m: FloatArray
    a_m_s2: FloatArray
    theta_rad: FloatArray
    omega_rad_s: FloatArray
    nfev: int


def steady_state_initial(
    p: StandParameters, omega_rad_s: float, U_kg_m: ArrayLike, theta0_rad: float = 0.0
) -> FloatArray:
    """State ``[x1, x2, v1, v2]`` that starts exactly on the steady-state orbit."""
    w = float(omega_rad_s)
    X = -forward(p, w, U_kg_m) / (w * w)
    e = np.exp(1j * theta0_rad)
    return np.concatenate(((X * e).real, (1j * w * X * e).real))


Progress = Callable[[float], None]
"""Told now and then how far an integration has come: the simulated time reached [s]
(every :data:`PROGRESS_EVERY` evaluations of the equations); for a progress line."""
PROGRESS_EVERY = 4096
"""Evaluations between two calls of a :data:`Progress`."""


def telling(
    rhs: Callable[[float, FloatArray], FloatArray], progress: Progress | None
) -> Callable[[float, FloatArray], FloatArray]:
    """``rhs`` telling ``progress`` the time every :data:`PROGRESS_EVERY` evaluations
    (``rhs`` itself where there is no one to tell)."""
    if progress is None:
        return rhs
    count = [0]

    def told(t: float, y: FloatArray) -> FloatArray:
        count[0] += 1
        if count[0] % PROGRESS_EVERY == 0:
            progress(t)
        return rhs(t, y)

    return told


def _atol(p: StandParameters, speed: Speed, U: ComplexArray, rtol: float,
          atol_scale: float | None, w_top: float) -> FloatArray:  # fmt: skip
    """The absolute tolerances of ``x1, x2, v1, v2``: ``rtol`` times the displacement scale
    (default the steady displacement at the top speed), velocities by the top speed."""
    if atol_scale is None:
        atol_scale = 1e-300  # a rotor that never turns: nothing moves
        if speed.max_omega_rad_s > 0:
            x_ss = np.abs(forward(p, speed.max_omega_rad_s, U)) / speed.max_omega_rad_s**2
            atol_scale = max(float(np.max(x_ss)), atol_scale)
    out: FloatArray = rtol * np.array([atol_scale, atol_scale, w_top * atol_scale,
                                       w_top * atol_scale])  # fmt: skip
    return out


def integrate(
    p: StandParameters,
    speed: Speed,
    U_kg_m: ArrayLike,
    t_eval_s: ArrayLike,
    *,
    y0: ArrayLike | None = None,
    support_force: SupportForce | None = None,
    method: str = "DOP853",
    rtol: float = 1e-9,
    atol_scale: float | None = None,
    max_step_s: float | None = None,
    progress: Progress | None = None,
) -> TransientResult:
    """Integrate the stand in time with :func:`scipy.integrate.solve_ivp`.

    Parameters
    ----------
    p
        Stand and rotor.
    speed
        The shaft speed over time.
    U_kg_m
        Complex unbalances ``U_i = q_i R_i e^{-i phi_i}`` [kg m], shape (2,).
    t_eval_s
        Output times [s], increasing, from 0.
    y0
        Initial ``[x1, x2, v1, v2]`` [m, m/s]; default at rest.
    support_force
        Nonlinear force on the supports ``S(x, v)`` [N] (friction,
        clearance); default none.
    method
        Any :func:`~scipy.integrate.solve_ivp` method (``"Radau"`` or
        ``"LSODA"`` for stiff cases).
    rtol
        Relative tolerance.
    atol_scale
        Displacement scale [m] for the absolute tolerance
        ``rtol * atol_scale`` (velocities scaled by the top speed); default
        the steady-state displacement at the top speed.
    max_step_s
        Largest step [s]; default a quarter of the shortest of the forcing
        period at the top speed and the stand's shortest natural period.
    progress
        Told the simulated time reached now and then (:data:`Progress`); default none.

    Returns
    -------
    TransientResult
    """
    from scipy.integrate import solve_ivp

    U = np.asarray(U_kg_m, dtype=np.complex128)
    t_eval = np.asarray(t_eval_s, dtype=float)
    if U.shape != (2,):
        raise ModelError(f"expected 2 unbalances, got shape {U.shape}")
    if t_eval.ndim != 1 or t_eval.size == 0 or t_eval[0] < 0 or np.any(np.diff(t_eval) < 0):
        raise ModelError("output times must be a non-empty increasing array from t >= 0")
    w_top = max(speed.max_omega_rad_s, float(natural_frequencies(p)[-1]))
    if max_step_s is None:
        max_step_s = 0.25 * 2 * math.pi / w_top
    atol = _atol(p, speed, U, rtol, atol_scale, w_top)

    Minv = np.linalg.inv(mass_matrix(p))
    K = np.array([p.C1, p.C2])
    H = np.array([p.H1, p.H2])
    L = p.L
    lever = np.array([[p.b + p.c + p.d, p.d], [p.a, p.a + p.b + p.c]]) / L

    def accel(t: FloatArray, y: FloatArray) -> FloatArray:
        x, v = y[:2], y[2:]
        e = U[:, None] * np.exp(1j * speed.theta(t))
        F = speed.omega(t) ** 2 * e.real + speed.alpha(t) * e.imag
        Q = lever @ F
        if support_force is not None:
            Q = Q + support_force(x, v)
        result: FloatArray = Minv @ (Q - H[:, None] * v - K[:, None] * x)
        return result

    def rhs(t: float, y: FloatArray) -> FloatArray:
        return np.concatenate((y[2:], accel(np.array([t]), y[:, None])[:, 0]))

    y_start = np.zeros(4) if y0 is None else np.asarray(y0, dtype=float)
    sol = solve_ivp(
        telling(rhs, progress),
        (0.0, float(t_eval[-1])),
        y_start,
        method=method,
        t_eval=t_eval,
        rtol=rtol,
        atol=atol,
        max_step=max_step_s,
    )
    if not sol.success:
        raise ModelError(f"time integration failed: {sol.message}")
    y = sol.y
    return TransientResult(
        t_s=t_eval,
        x_m=y[:2].T.copy(),
        a_m_s2=accel(t_eval, y).T.copy(),
        theta_rad=speed.theta(t_eval),
        omega_rad_s=speed.omega(t_eval),
        nfev=int(sol.nfev),
    )


def fit_1x(theta_rad: ArrayLike, a: ArrayLike) -> ComplexArray:
    """Least-squares 1x phasor ``A`` of ``a(theta) ~ Re(A e^{i theta}) + const``.

    A plain fit for checking the time path against the steady state; the
    measurement's estimator (with 2x/3x terms, gating and uncertainty)
    belongs to the DSP layer.

    Parameters
    ----------
    theta_rad : array, shape (n,)
    a : array, shape (n,) or (n, k)

    Returns
    -------
    complex ndarray, shape () or (k,)
    """
    th = np.asarray(theta_rad, dtype=float)
    X = np.column_stack((np.cos(th), -np.sin(th), np.ones_like(th)))
    coef, *_ = np.linalg.lstsq(X, np.asarray(a, dtype=float), rcond=None)
    result: ComplexArray = coef[0] + 1j * coef[1]
    return result
