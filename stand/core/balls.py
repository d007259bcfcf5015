"""Balls of a ball balancer free on their race in one correction plane, coupled to the
stand's supports: the equations of motion in time (seeds 000/004's balls, on the stand).

The stand's supports move along x only (the planar model of :mod:`stand.core.model`); a
ball of mass ``m`` runs on a race of radius ``R`` in plane ``P`` (axial position ``z_P``
from support 1).  Its absolute angle ``psi = theta + phi`` (``theta`` the shaft's,
``phi`` its place on the rotor, both in the direction of rotation) puts it at
``x_P + R cos(psi)``, ``y = R sin(psi)``; its unbalance is ``m R e^{i phi}`` in the
product's convention (``U = q R e^{-i phi_seed}``: ``phi = -phi_seed``).  Lagrange's
equations, with the supports' coordinates ``x = (x1, x2)``, ``x_P = N x``,
``N = (1 - z_P / L, z_P / L)``:

* supports: ``M_b x'' + H x' + K x = N^T (F_U . lever) + N^T sum_j m R (psi_j'' sin psi_j
  + psi_j'^2 cos psi_j)``, ``M_b`` the stand's mass matrix with the balls' mass at ``P``
  (:func:`stand.core.autobalance.with_balls`), ``F_U`` the rotor's own unbalance forces;
* each ball: ``m R^2 psi'' = m R x_P'' sin psi - beta R^2 phi' - m g R cos psi``, the
  drag ``beta`` [N s/m] on its motion relative to the race (the seeds' viscous model),
  gravity ``g`` along ``-y`` (``x`` horizontal).

Eliminating ``psi''`` leaves a 2 x 2 system for ``x''`` at each instant (``(M_b - m
sum sin^2 psi_j N^T N) x'' = ...``), so a step costs no more than the stand's own.  The
state is ``(x1, x2, v1, v2, phi_1..n, phi'_1..n)``: the balls' places on the rotor,
which move slowly, not their absolute angles.

Pure numerics: arrays in, arrays out (scipy's integrator imported where it is used).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from stand.core.autobalance import plane_positions, with_balls
from stand.core.model import FloatArray, StandParameters, mass_matrix, natural_frequencies
from stand.core.transient import Speed
from stand.errors import ModelError

G_M_S2 = 9.80665
"""Standard gravity [m/s^2]."""


@dataclass(frozen=True)
class Balls:
    """The balls: their plane (1 or 2), number, each one's mass [kg], the race's radius
    [m], the viscous drag on their motion relative to the race [N s/m] and gravity along
    ``-y`` [m/s^2] (0: none)."""

    plane: int
    n: int
    mass_kg: float
    radius_m: float
    drag_n_s_m: float
    gravity_m_s2: float = 0.0

    @property
    def capacity_kg_m(self) -> float:
        """``n m R`` [kg m]."""
        return self.n * self.mass_kg * self.radius_m


@dataclass(frozen=True)
class BallsRun:
    """An integrated run: at each output time the supports' displacements [m] and
    accelerations [m/s^2] (k, 2), the balls' places on the rotor ``phi`` [rad] (k, n) and
    their rates [rad/s], the shaft angle and speed, the drive's power [W], the power
    dissipated [W] and the energy [J] (for the energy balance), and the evaluations."""

    t_s: FloatArray
    x_m: FloatArray
    a_m_s2: FloatArray
    phi_rad: FloatArray
    phi_rate_rad_s: FloatArray
    theta_rad: FloatArray
    omega_rad_s: FloatArray
    drive_w: FloatArray
    dissipated_w: FloatArray
    energy_j: FloatArray
    nfev: int

    def balls_kg_m(self, balls: Balls) -> np.ndarray:
        """The balls' unbalance at each output time [kg m] (product convention)."""
        out: np.ndarray = balls.mass_kg * balls.radius_m * np.exp(1j * self.phi_rad).sum(axis=1)
        return out


class _System:
    """The stand with the balls: their matrices and the accelerations of a state."""

    def __init__(self, p: StandParameters, balls: Balls, U_kg_m: np.ndarray, speed: Speed,
                 locked: bool = False):  # fmt: skip
        self.locked = locked
        if balls.n < 1 or balls.mass_kg <= 0 or balls.radius_m <= 0:
            raise ModelError("balls: a number >= 1, a mass > 0 and a radius > 0 are needed")
        self.p, self.b, self.U, self.speed = p, balls, U_kg_m, speed
        self.M = mass_matrix(with_balls(p, balls.plane, balls.n * balls.mass_kg))
        self.K = np.array([p.C1, p.C2])
        self.H = np.array([p.H1, p.H2])
        z = plane_positions(p)[balls.plane - 1]
        self.N = np.array([1.0 - z / p.L, z / p.L])
        self.lever = np.array([[p.b + p.c + p.d, p.d], [p.a, p.a + p.b + p.c]]) / p.L
        self.zs = plane_positions(p)

    def accel(self, t: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``x''`` (2, k) and ``phi''`` (n, k) at times ``t`` (k,) and states ``y`` (., k)."""
        n, m, R, beta, g = self.b.n, self.b.mass_kg, self.b.radius_m, self.b.drag_n_s_m, \
            self.b.gravity_m_s2  # fmt: skip
        x, v = y[:2], y[2:4]
        phi, dphi = y[4 : 4 + n], y[4 + n :]
        theta, w, al = self.speed.theta(t), self.speed.omega(t), self.speed.alpha(t)
        psi = theta + phi
        s, c = np.sin(psi), np.cos(psi)
        dpsi = w + dphi
        e = self.U[:, None] * np.exp(1j * theta)
        rhs = self.lever @ (w**2 * e.real + al * e.imag) - self.H[:, None] * v - self.K[:, None] * x
        if self.locked:  # held on the rotor: psi'' = alpha, no share of x_P''
            r, S2 = np.broadcast_to(al, psi.shape), np.zeros_like(t)
        else:
            r = -(beta / m) * dphi - (g / R) * c  # psi'' less its share of x_P''
            S2 = m * np.sum(s * s, axis=0)
        G = m * R * np.sum(r * s + dpsi**2 * c, axis=0)
        rhs = rhs + self.N[:, None] * G
        # (M - S2 N N^T) x'' = rhs, 2 x 2 for every instant
        NN = np.outer(self.N, self.N)
        a11 = self.M[0, 0] - S2 * NN[0, 0]
        a12 = self.M[0, 1] - S2 * NN[0, 1]
        a22 = self.M[1, 1] - S2 * NN[1, 1]
        det = a11 * a22 - a12 * a12
        xdd = np.array([(a22 * rhs[0] - a12 * rhs[1]) / det, (a11 * rhs[1] - a12 * rhs[0]) / det])
        if self.locked:
            return xdd, np.zeros_like(phi)
        aP = self.N @ xdd
        phidd = aP * s / R + r - al
        return xdd, phidd

    def power(self, t: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The drive's power, the power dissipated [W] and the energy [J] at ``(t, y)``.

        The drive holds ``theta(t)``: its torque is what the rotor's unbalance and the
        balls' drag ask, ``-sum_i x_i'' Im(U_i e^{i theta}) + |U_i| R_i theta'' + beta R^2
        sum_j (theta' - psi_j')`` (``x_i`` the motion at plane ``i``).  The energy counts
        the supports, the rotor's translation and tilt, the unbalance's spin (its masses at
        the correction radii) and its coupling to the translation, the balls' motion and
        their height."""
        n, m, R, beta, g = self.b.n, self.b.mass_kg, self.b.radius_m, self.b.drag_n_s_m, \
            self.b.gravity_m_s2  # fmt: skip
        xdd, _ = self.accel(t, y)
        v, x = y[2:4], y[:2]
        phi, dphi = y[4 : 4 + n], y[4 + n :]
        theta, w, al = self.speed.theta(t), self.speed.omega(t), self.speed.alpha(t)
        Npl = np.array([[1.0 - z / self.p.L, z / self.p.L] for z in self.zs])  # planes
        radii = np.array([self.p.R1, self.p.R2])
        e = self.U[:, None] * np.exp(1j * theta)
        xdd_pl, v_pl = Npl @ xdd, Npl @ v
        torque = -np.sum(xdd_pl * e.imag, axis=0) + np.sum(np.abs(self.U) * radii) * al
        torque = torque + beta * R**2 * np.sum(-dphi, axis=0)
        drive = torque * w
        lost = np.sum(self.H[:, None] * v * v, axis=0) + beta * R**2 * np.sum(dphi**2, axis=0)
        psi = theta + phi
        dpsi = w + dphi
        vP = self.N @ v
        energy = 0.5 * np.einsum("ik,ij,jk->k", v, self.M, v)
        energy += 0.5 * np.sum(self.K[:, None] * x * x, axis=0)
        energy += 0.5 * np.sum(np.abs(self.U) * radii) * w**2 - np.sum(v_pl * e.imag, axis=0) * w
        energy += np.sum(-m * R * vP * dpsi * np.sin(psi) + 0.5 * m * R**2 * dpsi**2, axis=0)
        energy += np.sum(m * g * R * np.sin(psi), axis=0)
        return drive, lost, energy


def integrate_balls(
    p: StandParameters,
    speed: Speed,
    U_kg_m: ArrayLike,
    balls: Balls,
    t_eval_s: ArrayLike,
    phi0_rad: ArrayLike,
    *,
    y0: ArrayLike | None = None,
    rtol: float = 1e-9,
    method: str = "DOP853",
    locked: bool = False,
) -> BallsRun:
    """Integrate the stand and the balls with :func:`scipy.integrate.solve_ivp`.

    Parameters
    ----------
    p
        Stand and rotor (without the balls: their mass is added here).
    speed
        The shaft speed over time (:class:`stand.core.transient.Speed`).
    U_kg_m
        The rotor's own unbalances per plane [kg m], shape (2,).
    balls
        The balls.
    t_eval_s
        Output times [s], increasing, from 0.
    phi0_rad
        The balls' places on the rotor at ``t = 0`` [rad] (direction of rotation), (n,);
        they start at rest on the rotor.
    y0
        The supports' ``(x1, x2, v1, v2)`` at ``t = 0`` [m, m/s]; default at rest.
    rtol
        Relative tolerance (absolute: ``rtol`` times the steady displacement scale, and
        ``rtol`` rad for the balls).
    locked
        Hold the balls where they start (the balancer locked): the stand model with their
        unbalance and mass added, the reference the tests hold the free balls to.
    """
    from scipy.integrate import solve_ivp

    U = np.asarray(U_kg_m, dtype=np.complex128)
    t_eval = np.asarray(t_eval_s, dtype=float)
    phi0 = np.asarray(phi0_rad, dtype=float).reshape(-1)
    if U.shape != (2,) or phi0.shape != (balls.n,):
        raise ModelError(f"expected 2 unbalances and {balls.n} ball angles")
    if t_eval.ndim != 1 or t_eval.size == 0 or t_eval[0] < 0 or np.any(np.diff(t_eval) < 0):
        raise ModelError("output times must be a non-empty increasing array from t >= 0")
    sys = _System(p, balls, U, speed, locked)
    w_top = max(speed.max_omega_rad_s, float(natural_frequencies(p)[-1]))
    scale = (np.abs(U).sum() + balls.capacity_kg_m) / max(p.M3, 1e-9)
    atol = np.concatenate((
        rtol * np.array([scale, scale, w_top * scale, w_top * scale]),
        np.full(balls.n, rtol), np.full(balls.n, rtol * w_top),
    ))  # fmt: skip

    def rhs(t: float, y: FloatArray) -> FloatArray:
        xdd, phidd = sys.accel(np.array([t]), y[:, None])
        return np.concatenate((y[2:4], xdd[:, 0], y[4 + balls.n :], phidd[:, 0]))

    start = np.concatenate((np.zeros(4) if y0 is None else np.asarray(y0, float), phi0,
                            np.zeros(balls.n)))  # fmt: skip
    sol = solve_ivp(rhs, (0.0, float(t_eval[-1])), start, method=method, t_eval=t_eval,
                    rtol=rtol, atol=atol, max_step=0.25 * 2 * math.pi / w_top)  # fmt: skip
    if not sol.success:
        raise ModelError(f"time integration failed: {sol.message}")
    y = sol.y
    xdd, _ = sys.accel(t_eval, y)
    drive, lost, energy = sys.power(t_eval, y)
    return BallsRun(
        t_s=t_eval, x_m=y[:2].T.copy(), a_m_s2=xdd.T.copy(), phi_rad=y[4 : 4 + balls.n].T.copy(),
        phi_rate_rad_s=y[4 + balls.n :].T.copy(), theta_rad=speed.theta(t_eval),
        omega_rad_s=speed.omega(t_eval), drive_w=drive, dissipated_w=lost, energy_j=energy,
        nfev=int(sol.nfev),
    )  # fmt: skip
