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
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stand.core.autobalance import plane_positions, with_balls
from stand.core.model import FloatArray, StandParameters, mass_matrix, natural_frequencies
from stand.core.stickslip import MAX_SWITCHES, events_of, modes_at, switch
from stand.core.transient import PROGRESS_EVERY, Progress, Speed
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
    rolling: float = 0.0
    """Rolling resistance as a coefficient on the force pressing a ball onto its race
    (``m R psi'^2``): a ball sticks on the race while the force that holds it there stays
    within ``rolling m R psi'^2``, and rolls against that force otherwise."""

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
        # what accel takes per call, made once: (2, 1) columns and M - S2 N N^T's parts
        LU = self.lever @ U_kg_m.real, self.lever @ U_kg_m.imag
        self._HK = {1: (self.H, self.K), 2: (self.H[:, None], self.K[:, None])}
        self._LU = {1: LU, 2: (LU[0][:, None], LU[1][:, None])}
        NN = np.outer(self.N, self.N)
        self._MN = (self.M[0, 0], NN[0, 0]), (self.M[0, 1], NN[0, 1]), (self.M[1, 1], NN[1, 1])

    def modes(self, held: NDArray[np.bool_] | None, slip: FloatArray | None
              ) -> tuple[NDArray[np.bool_], FloatArray]:  # fmt: skip
        """Which balls are held on the race, and the direction each other one rolls in
        (the sign of ``phi'``: its rolling resistance opposes it)."""
        n = self.b.n
        h = np.full(n, self.locked) if held is None else held
        return h, np.zeros(n) if slip is None else slip

    def accel(self, t: FloatArray | float, y: FloatArray, held: NDArray[np.bool_] | None = None,
              slip: FloatArray | None = None) -> tuple[FloatArray, FloatArray]:  # fmt: skip
        """``x''`` (2, k) and ``phi''`` (n, k) at times ``t`` (k,) and states ``y`` (., k),
        the balls ``held`` on the race (all when locked) and the others rolling in the
        directions ``slip``; or, for one instant, ``x''`` (2,) and ``phi''`` (n,) at a time
        ``t`` (float) and a state ``y`` (.,): the integrator's call, on scalars, where
        (2, 1) arrays cost it twice as much."""
        n, m, R, beta, g = self.b.n, self.b.mass_kg, self.b.radius_m, self.b.drag_n_s_m, \
            self.b.gravity_m_s2  # fmt: skip
        h, sl = self.modes(held, slip)
        anyheld = bool(h.any())
        x, v = y[:2], y[2:4]
        phi, dphi = y[4 : 4 + n], y[4 + n :]
        theta, w, al = self.speed.theta(t), self.speed.omega(t), self.speed.alpha(t)
        psi = theta + phi
        s, c = np.sin(psi), np.cos(psi)
        dpsi = w + dphi
        # lever (w^2 Re e + alpha Im e), e = U exp(i theta), by U's real and imaginary parts
        ct, st, w2 = np.cos(theta), np.sin(theta), w * w
        (H, K), (LUr, LUi) = self._HK[y.ndim], self._LU[y.ndim]
        rhs = LUr * (w2 * ct + al * st) + LUi * (al * ct - w2 * st) - H * v - K * x
        # psi'' less its share of x_P'': held, alpha; else drag, gravity, rolling resistance
        r = -(beta / m) * dphi - (g / R) * c
        if y.ndim == 2:
            h, sl = h[:, None], sl[:, None]
        if self.b.rolling:
            r = r - self.b.rolling * dpsi**2 * sl
        ss = s * s
        if anyheld:
            r, ss = np.where(h, al, r), np.where(h, 0.0, ss)
        S2 = m * ss.sum(axis=0)
        G = m * R * (r * s + dpsi**2 * c).sum(axis=0)
        N0, N1 = self.N
        rhs0, rhs1 = rhs[0] + N0 * G, rhs[1] + N1 * G
        # (M - S2 N N^T) x'' = rhs, 2 x 2 for every instant
        (m11, n11), (m12, n12), (m22, n22) = self._MN
        a11, a12, a22 = m11 - S2 * n11, m12 - S2 * n12, m22 - S2 * n22
        det = a11 * a22 - a12 * a12
        x0, x1 = (a22 * rhs0 - a12 * rhs1) / det, (a11 * rhs1 - a12 * rhs0) / det
        xdd = np.array((x0, x1))
        phidd = (N0 * x0 + N1 * x1) * s / R + r - al
        if anyheld:
            phidd = np.where(h, 0.0, phidd)
        return xdd, phidd

    def holding(self, t: FloatArray, y: FloatArray, held: NDArray[np.bool_]
                ) -> tuple[FloatArray, FloatArray]:  # fmt: skip
        """The tangential force the race must give each ball to hold it [N] (what it would
        need, for a rolling ball), and the most its rolling resistance gives [N]: ``m R
        alpha - m x_P'' sin psi + m g cos psi`` against ``rolling m R psi'^2``."""
        n, m, R = self.b.n, self.b.mass_kg, self.b.radius_m
        xdd, _ = self.accel(t, y, held, np.zeros(n))
        theta, w, al = self.speed.theta(t), self.speed.omega(t), self.speed.alpha(t)
        psi = theta + y[4 : 4 + n]
        need = m * R * al - m * (self.N @ xdd) * np.sin(psi) + m * self.b.gravity_m_s2 * np.cos(psi)
        return need, self.b.rolling * m * R * (w + y[4 + n :]) ** 2

    def power(
        self, t: FloatArray, y: FloatArray, held: NDArray[np.bool_] | None = None,
        slip: FloatArray | None = None,
    ) -> tuple[FloatArray, FloatArray, FloatArray]:  # fmt: skip
        """The drive's power, the power dissipated [W] and the energy [J] at ``(t, y)``.

        The drive holds ``theta(t)``: its torque is what the rotor's unbalance and the
        balls' drag and race forces ask, ``-sum_i x_i'' Im(U_i e^{i theta}) + |U_i| R_i
        theta'' + beta R^2 sum_j (theta' - psi_j') + R sum_j f_j`` (``x_i`` the motion at
        plane ``i``, ``f_j`` the race's tangential force on ball ``j``: what holds it, or its
        rolling resistance).  The energy counts the supports, the rotor's translation and
        tilt, the unbalance's spin (its masses at the correction radii) and its coupling to
        the translation, the balls' motion and their height."""
        n, m, R, beta, g = self.b.n, self.b.mass_kg, self.b.radius_m, self.b.drag_n_s_m, \
            self.b.gravity_m_s2  # fmt: skip
        h, sl = self.modes(held, slip)
        xdd, _ = self.accel(t, y, h, sl)
        v, x = y[2:4], y[:2]
        phi, dphi = y[4 : 4 + n], y[4 + n :]
        theta, w, al = self.speed.theta(t), self.speed.omega(t), self.speed.alpha(t)
        Npl = np.array([[1.0 - z / self.p.L, z / self.p.L] for z in self.zs])  # planes
        radii = np.array([self.p.R1, self.p.R2])
        e = self.U[:, None] * np.exp(1j * theta)
        xdd_pl, v_pl = Npl @ xdd, Npl @ v
        torque = -np.sum(xdd_pl * e.imag, axis=0) + np.sum(np.abs(self.U) * radii) * al
        torque = torque + beta * R**2 * np.sum(-dphi, axis=0)
        lost = np.sum(self.H[:, None] * v * v, axis=0) + beta * R**2 * np.sum(dphi**2, axis=0)
        if self.b.rolling > 0 or h.any():
            need, most = self.holding(t, y, h)
            f = np.where(h[:, None], need, -most * sl[:, None])
            torque = torque + R * np.sum(f, axis=0)
            lost = lost - R * np.sum(f * dphi, axis=0)
        drive = torque * w
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
    progress: Progress | None = None,
) -> BallsRun:
    """Integrate the stand and the balls with :func:`scipy.integrate.solve_ivp`.

    With rolling resistance the balls stick and roll: the integration stops where a
    rolling ball comes to rest on the race or a held one needs more than its rolling
    resistance gives (solve_ivp's events, located to the integrator's tolerance), and
    goes on in the new mode; a held ball does not move on its race at all (no creep).

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
    progress
        Told the simulated time reached now and then (a progress line); default none.
    """
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
    start = np.concatenate((np.zeros(4) if y0 is None else np.asarray(y0, float), phi0,
                            np.zeros(balls.n)))  # fmt: skip
    max_step = 0.5 * math.pi / w_top
    _not_too_stiff(balls, float(t_eval[-1]), max_step)
    options = {"method": method, "rtol": rtol, "atol": atol, "max_step": max_step}
    y, xdd, power, nfev = _segments(sys, start, t_eval, options, progress)
    n = balls.n
    return BallsRun(
        t_s=t_eval, x_m=y[:2].T.copy(), a_m_s2=xdd.T.copy(), phi_rad=y[4 : 4 + n].T.copy(),
        phi_rate_rad_s=y[4 + n :].T.copy(), theta_rad=speed.theta(t_eval),
        omega_rad_s=speed.omega(t_eval), drive_w=power[0], dissipated_w=power[1],
        energy_j=power[2], nfev=nfev,
    )  # fmt: skip


MAX_EVALUATIONS = 2_000_000
"""No run of the balls takes more evaluations of their equations (the 60 s demo-balls
takes about 101 000, 7 s): beyond, the integration is refused, never left running."""
EVALUATIONS_PER_STEP = 12
"""DOP853's evaluations per step."""


def _not_too_stiff(balls: Balls, t_end_s: float, max_step_s: float) -> None:
    """Refuse before it starts a run whose drag makes the balls' equations stiff: an
    explicit step must stay within about 3 of the drag's time constant ``m / c``, and the
    steps that asks for would take more than :data:`MAX_EVALUATIONS` evaluations."""
    if balls.drag_n_s_m <= 0:
        return
    tau = balls.mass_kg / balls.drag_n_s_m
    need = EVALUATIONS_PER_STEP * t_end_s / min(max_step_s, 3.0 * tau)
    if need > MAX_EVALUATIONS:
        raise ModelError(
            f"the balls' drag makes their equations stiff: a time constant of {tau:.2g} s "
            f"(ball mass / drag_n_s_m) asks for about {need:.2g} evaluations over {t_end_s:g} "
            f"s, more than {MAX_EVALUATIONS:g}: a drag this large holds the balls (lower it)"
        )


def _segments(
    sys: _System, y: FloatArray, t_eval: FloatArray, options: dict[str, Any],
    progress: Progress | None,
) -> tuple[FloatArray, FloatArray, FloatArray, int]:  # fmt: skip
    """The run in segments of one mode each (one segment without rolling resistance): the
    states, the support accelerations and the powers at ``t_eval``, and the evaluations."""
    from scipy.integrate import solve_ivp

    n, t0, t_end, done, nfev = sys.b.n, 0.0, float(t_eval[-1]), 0, 0
    held, slip = modes_at(sys, 0.0, y, np.full(n, sys.locked), np.zeros(n))
    ys, xdds, powers = [], [], []
    for _ in range(MAX_SWITCHES):
        h, sl = held.copy(), slip.copy()

        count = [nfev]

        def rhs(
            t: float, z: FloatArray, h: Any = h, sl: Any = sl, count: list[int] = count
        ) -> FloatArray:
            count[0] += 1
            if count[0] > MAX_EVALUATIONS:  # whatever made it stiff: ended, never left running
                raise ModelError(f"the balls' equations took more than {MAX_EVALUATIONS:g} "
                                 f"evaluations by t = {t:.3g} s: too stiff")  # fmt: skip
            if progress is not None and count[0] % PROGRESS_EVERY == 0:
                progress(t)
            xdd, phidd = sys.accel(t, z, h, sl)  # t a float, z 1-D: scalars are quicker
            return np.concatenate((z[2:4], xdd, z[4 + n :], phidd))

        events = events_of(sys, h, sl)
        sol = solve_ivp(rhs, (t0, t_end), y, t_eval=t_eval[done:], events=events or None,
                        **options)  # fmt: skip
        if not sol.success:
            raise ModelError(f"time integration failed: {sol.message}")
        nfev += int(sol.nfev)
        if len(sol.t):
            ys.append(sol.y)
            xdds.append(sys.accel(sol.t, sol.y, h, sl)[0])
            powers.append(np.array(sys.power(sol.t, sol.y, h, sl)))
            done += len(sol.t)
        if sol.status != 1:
            return np.hstack(ys), np.hstack(xdds), np.hstack(powers), nfev
        k = min((j for j in range(len(events)) if len(sol.t_events[j])),
                key=lambda j: sol.t_events[j][0])  # fmt: skip
        t0, y = float(sol.t_events[k][0]), sol.y_events[k][0].copy()
        held, slip = switch(sys, t0, y, h, sl, k)
    raise ModelError(f"the balls switch between sticking and rolling more than {MAX_SWITCHES} "
                     "times: a rolling resistance at the edge of what holds them")  # fmt: skip
