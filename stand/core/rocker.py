"""The ball autobalancer on a grinder's rocker (seeds 000 and 004): closed forms and the
Floquet test of the parametric resonance.  Pure numerics, SI units.

The rocker turns about a hinge O (stiffness ``c`` and viscosity ``h`` reduced to the arm
``l``); the disc's centre K is at ``l`` from O.  With the balls near their balancing
position a small unbalance ``ds_u`` is left, and the rocker's angle ``z`` obeys (004's 8)::

    (1 + 2 eps cos wt) z'' + 2 (h' - eps w sin wt) z' + omega0^2 z = w^2 eps sin wt

with ``eps = l ds_u / J_O``, ``h' = h l^2 / (2 J_O)``, ``omega0^2 = c l^2 / J_O``.  Balancing
sets in where the mean of ``r_K . e`` over a turn is negative: ``omega > omega0`` (004's 12).
Cutting stiffens the hinge by the work's contact (``c_n``, ``f_n``, contact angle theta),
which bounds ``c_n`` from above (004's 13-15); at ``omega = 2 omega0`` a parametric
resonance is suppressed only with ``h' > eps omega0 / 2`` (004's 23-24).  Every formula was
re-derived here (docs/autobalancer.md says how); the seeds carry no numerical example.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, minimize_scalar

FLOQUET_RTOL = 1e-11
"""Relative tolerance of the monodromy integration (DOP853)."""
SIGMA_XTOL = 1e-10
"""Brent's tolerance on the damping parameter sigma at the stability boundary."""


def inertia_about_hinge(
    J_housing: float, J_disc: float, disc_kg: float, arm_m: float,
    masses_kg: np.ndarray, radii_m: np.ndarray,
) -> float:  # fmt: skip
    """``J_O`` (000's 2.4): housing and rocker, the disc about K carried to O, and each
    point mass (the unbalance and the balls) at ``l^2 + R_i^2`` [kg m^2]."""
    m = np.asarray(masses_kg, dtype=float)
    R = np.asarray(radii_m, dtype=float)
    return float(J_housing + J_disc + disc_kg * arm_m**2 + np.sum(m * (arm_m**2 + R**2)))


def natural(c_n_m: float, arm_m: float, J_O: float) -> float:
    """``omega0 = sqrt(c l^2 / J_O)`` [rad/s]."""
    return math.sqrt(c_n_m * arm_m**2 / J_O)


@dataclass(frozen=True)
class ThirdOrder:
    """004's (11): ``z = (eps M1 + eps^3 M13) cos wt + (eps N1 + eps^3 N13) sin wt
    + eps^2 (M2 cos 2wt + N2 sin 2wt) + eps^3 (M3 cos 3wt + N3 sin 3wt)`` [rad per
    eps^k]."""

    M1: float
    N1: float
    M2: float
    N2: float
    M13: float
    N13: float
    M3: float
    N3: float


def _D(i: int, w: float, w0: float, hp: float) -> float:
    return (w0**2 - (i * w) ** 2) ** 2 + 4 * hp**2 * (i * w) ** 2


def _forced(A: float, B: float, i: int, w: float, w0: float, hp: float) -> tuple[float, float]:
    """The steady answer ``M cos iwt + N sin iwt`` of ``z'' + 2h'z' + w0^2 z = A cos iwt +
    B sin iwt``."""
    W, d = i * w, _D(i, w, w0, hp)
    return ((w0**2 - W**2) * A - 2 * hp * W * B) / d, (2 * hp * W * A + (w0**2 - W**2) * B) / d


def third_order(w: float, w0: float, hp: float) -> ThirdOrder:
    """The coefficients of 004's (11) at speed ``w``: each order forced by the one before,
    ``-2 d/dt(z_{k-1}' cos wt)`` (the first by ``w^2 sin wt``)."""
    M1, N1 = _forced(0.0, w**2, 1, w, w0, hp)
    M2, N2 = _forced(2 * w**2 * M1, 2 * w**2 * N1, 2, w, w0, hp)
    M13, N13 = _forced(2 * w**2 * M2, 2 * w**2 * N2, 1, w, w0, hp)
    M3, N3 = _forced(6 * w**2 * M2, 6 * w**2 * N2, 3, w, w0, hp)
    return ThirdOrder(M1, N1, M2, N2, M13, N13, M3, N3)


def criterion(w: float, w0: float, hp: float, eps: float, arm_m: float) -> float:
    """The engineering criterion's mean ``(eps l / 2)(N1 + eps^2 N13)`` [m]: balancing sets
    in where it is negative."""
    t = third_order(w, w0, hp)
    return eps * arm_m / 2 * (t.N1 + eps**2 * t.N13)


def monodromy_radius(eps: float, k: float, sigma: float) -> float:
    """The largest Floquet multiplier's modulus of 004's (17),
    ``(1 + 2 eps cos tau) z'' + 2 eps (k sigma - sin tau) z' + k^2 z = 0`` over one period
    ``2 pi``: below 1 the rocker's rest is asymptotically stable."""

    def f(t: float, y: np.ndarray) -> np.ndarray:
        z, v = y[:2], y[2:]
        a = -(2 * eps * (k * sigma - math.sin(t)) * v + k * k * z) / (1 + 2 * eps * math.cos(t))
        return np.concatenate([v, a])

    sol = solve_ivp(f, (0.0, 2 * math.pi), np.array([1.0, 0.0, 0.0, 1.0]), method="DOP853",
                    rtol=FLOQUET_RTOL, atol=FLOQUET_RTOL * 1e-2)  # fmt: skip
    y = sol.y[:, -1]
    return float(np.max(np.abs(np.linalg.eigvals(np.array([[y[0], y[1]], [y[2], y[3]]])))))


def floquet_sigma_threshold(eps: float, k: float = 0.5) -> float:
    """The least ``sigma = h' / (eps omega0)`` that keeps 004's (17) stable at ``k =
    omega0 / omega`` (its multipliers inside the unit circle), found by Brent's method;
    averaging gives 1/2 at ``k = 1/2`` as eps -> 0 (004's 23)."""

    def gap(sigma: float) -> float:
        return monodromy_radius(eps, k, sigma) - 1.0

    lo, hi = 1e-3, 4.0
    if gap(lo) <= 0:
        return 0.0  # stable without damping: no parametric resonance at this k
    return float(brentq(gap, lo, hi, xtol=SIGMA_XTOL))


def contact(theta: float, arm_m: float, disc_radius_m: float, f_n: float) -> float:
    """``g(theta) = [l sin theta + f_n (R - l cos theta)] sin theta`` [m]: how much the
    work's contact stiffness ``c_n`` adds to the hinge's ``c l^2`` (``c_n l g``)."""
    return (arm_m * math.sin(theta) + f_n * (disc_radius_m - arm_m * math.cos(theta))) * math.sin(
        theta
    )


def contact_max_series(arm_m: float, disc_radius_m: float, f_n: float) -> tuple[float, float]:
    """The worst contact angle and ``max g`` by 004's series in ``f_n``:
    ``theta* = pi/2 + f_n/2 - R f_n^2/(4l) + (3R^2 - 4l^2) f_n^3/(24 l^2)``, ``g* = l + R f_n
    + l f_n^2/4 - R f_n^3/8`` [rad, m]."""
    L, R, f = arm_m, disc_radius_m, f_n
    theta = math.pi / 2 + f / 2 - R * f**2 / (4 * L) + (3 * R**2 - 4 * L**2) * f**3 / (24 * L**2)
    return theta, L + R * f + L * f**2 / 4 - R * f**3 / 8


def contact_max_exact(arm_m: float, disc_radius_m: float, f_n: float) -> tuple[float, float]:
    """The worst contact angle in (0, pi) and ``max g`` found numerically: the best of a
    0.25 deg grid, refined by bounded Brent within one grid step [rad, m]."""
    grid = np.linspace(0.0, math.pi, 721)
    step = grid[1] - grid[0]
    best = grid[int(np.argmax([contact(t, arm_m, disc_radius_m, f_n) for t in grid]))]
    found = minimize_scalar(lambda t: -contact(t, arm_m, disc_radius_m, f_n),
                            bounds=(max(best - step, 0.0), min(best + step, math.pi)),
                            method="bounded", options={"xatol": 1e-12})  # fmt: skip
    return float(found.x), -float(found.fun)
