"""Resonances from a run-up's 1x curve, and the stand model's own modes.

A support's 1x acceleration ``A(w)`` on a run-up comes from the rotor's unbalance, a force
``U w^2`` turning with the shaft: the frequency-response shape ``G(w) = -A(w) / w^4``
(displacement per unit of that force, up to the constant ``U``) has a peak at each
resonance.  From ``G``:

- **half-power**: the peak ``w_n`` (refined by a parabola through the three highest
  points), the two speeds ``w_1 < w_n < w_2`` where ``|G|`` has fallen to ``1/sqrt 2`` of
  the peak (linear interpolation); the damping ratio ``zeta = (w_2 - w_1) / (2 w_n)`` and
  the amplification factor ``AF = w_n / (w_2 - w_1)`` (API 684's, from the half-power
  points);
- **circle fit** (Ewins, *Modal Testing*, 2nd ed., section 4.3): near a viscously damped
  mode the mobility ``i w G`` traces a circle in the complex plane.  The circle through
  the points within the half-power band (algebraic least squares, Kasa 1976); the
  natural frequency where the angle turns fastest; the damping from two points ``a``
  below and ``b`` above it (``th`` the angle each makes at the centre with the natural
  frequency's point), the median over the pairs (:func:`circle_fit`).

Arrays in, arrays out, SI units (rad/s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from stand.core.model import StandParameters, mass_matrix

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

HALF_POWER = 1.0 / math.sqrt(2.0)
"""The half-power level of a peak (``|G|`` at ``1/sqrt 2`` of its maximum)."""
MIN_PROMINENCE = 0.25
"""A peak counts when it stands this fraction of its height above the deeper of the two
lowest points between it and a higher neighbour (scipy's ``prominence``)."""


@dataclass(frozen=True)
class Resonance:
    """One peak of a run-up's response shape.

    ``omega_rad_s`` the half-power peak, ``omega_1/2`` its half-power speeds, ``zeta`` the
    half-power damping ratio, ``amplification`` API 684's ``AF``; ``circle_*`` the same
    from the circle fit (None where too few points lie in the band: said by the caller);
    ``points`` the curve's points inside the half-power band."""

    omega_rad_s: float
    omega_1_rad_s: float
    omega_2_rad_s: float
    zeta: float
    amplification: float
    circle_omega_rad_s: float | None
    circle_zeta: float | None
    points: int


def response_shape(omega_rad_s: FloatArray, accel_m_s2: ComplexArray) -> ComplexArray:
    """``G = -A / w^4``: a support's 1x acceleration per unit of the unbalance's force
    ``w^2`` and turned into displacement (``/ -w^2``) [m s^4 ... up to the unbalance]."""
    w = np.asarray(omega_rad_s, dtype=float)
    shape: ComplexArray = -np.asarray(accel_m_s2, dtype=complex) / w**4
    return shape


def _crossing(w: FloatArray, mag: FloatArray, k: int, level: float, step: int) -> float | None:
    """Where ``mag`` falls below ``level`` walking from ``k`` by ``step`` (linear between
    the two points about it), or None if it never does within the data."""
    j = k
    while 0 <= j + step < len(w):
        if mag[j + step] < level:
            f = (mag[j] - level) / (mag[j] - mag[j + step])
            return float(w[j] + f * (w[j + step] - w[j]))
        j += step
    return None


def _peak(w: FloatArray, mag: FloatArray, k: int) -> float:
    """The peak's speed: the vertex of the parabola through the three highest points
    (``w[k]`` at an end of the data)."""
    if k == 0 or k == len(w) - 1:
        return float(w[k])
    x, y = w[k - 1 : k + 2], mag[k - 1 : k + 2]
    c = np.polyfit(x - x[1], y, 2)
    if c[0] >= 0:
        return float(w[k])
    return float(np.clip(x[1] - c[1] / (2 * c[0]), x[0], x[2]))


def circle_fit(w: FloatArray, G: ComplexArray) -> tuple[float, float] | None:
    """Natural frequency [rad/s] and damping ratio of the points ``G`` at ``w`` about one
    mode (see the module's docstring), or None with fewer than 5 points or no pair.

    The circle is fitted to the mobility ``i w G``, which a viscously damped mode traces
    exactly (the receptance only nearly); the natural frequency is where the angle turns
    fastest against ``w``, the damping ``zeta = (w_b^2 - w_a^2) / (2 w_n (w_a tan(th_a / 2)
    + w_b tan(th_b / 2)))`` (Ewins, 4.3, viscous damping), the median over the pairs."""
    if len(w) < 5:
        return None
    Y = 1j * w * G
    x, y = Y.real, Y.imag
    A = np.column_stack((x, y, np.ones_like(x)))
    sol, *_ = np.linalg.lstsq(A, x * x + y * y, rcond=None)
    xc, yc = sol[0] / 2, sol[1] / 2
    ang = np.unwrap(np.angle((x - xc) + 1j * (y - yc)))
    rate = np.abs(np.diff(ang) / np.diff(w))
    m = int(np.argmax(rate))
    wn, an = float(0.5 * (w[m] + w[m + 1])), float(0.5 * (ang[m] + ang[m + 1]))
    zetas = []
    for a in np.flatnonzero(w < wn):
        for b in np.flatnonzero(w > wn):
            ta, tb = abs(an - ang[a]), abs(ang[b] - an)
            if 0 < ta < math.pi and 0 < tb < math.pi:
                turn = w[a] * math.tan(ta / 2) + w[b] * math.tan(tb / 2)
                zetas.append((w[b] ** 2 - w[a] ** 2) / (2 * wn * turn))
    if not zetas:
        return None
    return wn, float(np.median(zetas))


def resonances(omega_rad_s: FloatArray, G: ComplexArray) -> list[Resonance]:
    """The peaks of ``|G|`` over increasing speeds ``omega_rad_s``, each with its
    half-power band inside the data (a peak whose band runs off either end is left out:
    its damping cannot be read)."""
    from scipy.signal import find_peaks

    w = np.asarray(omega_rad_s, dtype=float)
    mag = np.abs(G)
    if len(w) < 3:
        return []
    top = float(mag.max())
    ks, _ = find_peaks(mag, prominence=MIN_PROMINENCE * top)
    out = []
    for k in ks:
        level = HALF_POWER * mag[k]
        w1, w2 = _crossing(w, mag, int(k), level, -1), _crossing(w, mag, int(k), level, +1)
        if w1 is None or w2 is None or not w2 > w1:
            continue
        wn = _peak(w, mag, int(k))
        band = (w >= w1) & (w <= w2)
        fit = circle_fit(w[band], G[band])
        out.append(Resonance(
            omega_rad_s=wn, omega_1_rad_s=w1, omega_2_rad_s=w2, zeta=(w2 - w1) / (2 * wn),
            amplification=wn / (w2 - w1), circle_omega_rad_s=None if fit is None else fit[0],
            circle_zeta=None if fit is None else fit[1], points=int(np.count_nonzero(band)),
        ))  # fmt: skip
    return out


def model_modes(p: StandParameters) -> tuple[FloatArray, FloatArray]:
    """The stand model's underdamped modes with its support damping ``H1, H2``: natural
    frequencies ``|lambda|`` [rad/s] ascending and damping ratios ``-Re lambda /
    |lambda|``, from the eigenvalues of ``[[0, I], [-M^-1 K, -M^-1 H]]`` (an overdamped
    mode, a pair of real eigenvalues, has no resonance and is left out)."""
    M = mass_matrix(p)
    Minv = np.linalg.inv(M)
    K, H = np.diag([p.C1, p.C2]), np.diag([p.H1, p.H2])
    S = np.block([[np.zeros((2, 2)), np.eye(2)], [-Minv @ K, -Minv @ H]])
    lam = np.linalg.eigvals(S)
    lam = lam[lam.imag > 0]
    wn = np.abs(lam)
    order = np.argsort(wn)
    zeta: FloatArray = (-lam.real / np.maximum(wn, 1e-300))[order]
    return wn[order], zeta


def separation_margin_required(amplification: float, below: bool) -> float:
    """API 684's (and API 617's) separation margin a resonance of amplification factor
    ``AF`` asks of the operating speed [fraction]: none under 2.5; else ``16 (1 - 1 /
    (AF - 1.5))`` % for a resonance below the speed (``below``), ``10 + 17 (1 - 1 / (AF -
    1.5))`` % (at most 26 %) for one above."""
    if amplification < 2.5:
        return 0.0
    f = 1.0 - 1.0 / (amplification - 1.5)
    return 0.16 * f if below else min(0.10 + 0.17 * f, 0.26)


@dataclass(frozen=True)
class ModalFit:
    """The modes fitted to every support's response shape at once: natural frequencies
    [rad/s] ascending, damping ratios, and the fit's weighted residual (1: the points'
    own noise)."""

    omega_rad_s: tuple[float, ...]
    zeta: tuple[float, ...]
    chi: float


def _basis(w: FloatArray, poles: ComplexArray) -> ComplexArray:
    """Columns ``1 / (i w - lambda)`` and ``1 / (i w - conj lambda)`` of each pole."""
    iw = 1j * w[:, None]
    return np.hstack((1.0 / (iw - poles[None, :]), 1.0 / (iw - poles.conj()[None, :])))


def _poles(x: FloatArray) -> ComplexArray:
    """Poles ``-zeta w_n + i w_n sqrt(1 - zeta^2)`` of ``x = (w_n..., log zeta...)``."""
    n = len(x) // 2
    wn, zeta = x[:n], np.minimum(np.exp(x[n:]), 0.99)
    poles: ComplexArray = -zeta * wn + 1j * wn * np.sqrt(1 - zeta * zeta)
    return poles


def _residual(x: FloatArray, w: FloatArray, shapes: list[tuple[ComplexArray, FloatArray]]
              ) -> FloatArray:  # fmt: skip
    """Weighted misfit of the best residues for the poles ``x`` (variable projection: the
    residues are linear, solved for each support; only the poles are searched)."""
    B = _basis(w, _poles(x))
    out: list[FloatArray] = []
    for G, se in shapes:
        Bw, Gw = B / se[:, None], G / se
        c, *_ = np.linalg.lstsq(Bw, Gw, rcond=None)
        r = Bw @ c - Gw
        out.extend((r.real, r.imag))
    return np.concatenate(out)


def modal_fit(omega_rad_s: FloatArray, shapes: list[tuple[ComplexArray, FloatArray]],
              n_modes: int) -> ModalFit | None:  # fmt: skip
    """``n_modes`` modes fitted to the response shapes ``G`` of every support at once, each
    with its standard error per component ``se`` at the speeds ``omega_rad_s``.

    The response of a linear stand to a force of constant complex amplitude is, with its
    poles ``lambda_k``, ``G(w) = sum_k r_k / (i w - lambda_k) + s_k / (i w - conj
    lambda_k)`` for complex ``r_k, s_k`` per support (a rational fraction in partial
    fractions; Richardson and Formenti 1982).  The poles are common to the supports;
    started from the best pair of a grid over the run's speeds (zeta 0.05), then refined
    by scipy's ``least_squares``.  None with fewer than ``6 n_modes`` points."""
    from itertools import combinations

    from scipy.optimize import least_squares

    w = np.asarray(omega_rad_s, dtype=float)
    if n_modes < 1 or len(w) < 6 * n_modes:
        return None
    grid = np.linspace(w[0], w[-1], 25)[1:-1]
    log_z = math.log(0.05)
    best, start = math.inf, None
    for combo in combinations(grid, n_modes):
        x = np.array([*combo, *([log_z] * n_modes)])
        cost = float(np.sum(_residual(x, w, shapes) ** 2))
        if cost < best:
            best, start = cost, x
    assert start is not None
    lo = np.array([w[0] * 0.5] * n_modes + [math.log(1e-4)] * n_modes)
    hi = np.array([w[-1] * 1.5] * n_modes + [math.log(0.9)] * n_modes)
    fit = least_squares(_residual, start, bounds=(lo, hi), args=(w, shapes), x_scale="jac")
    poles = _poles(fit.x)
    wn, zeta = np.abs(poles), -poles.real / np.abs(poles)
    order = np.argsort(wn)
    dof = max(2 * len(w) * len(shapes) - (2 * n_modes + 4 * n_modes * len(shapes)), 1)
    return ModalFit(tuple(float(v) for v in wn[order]), tuple(float(v) for v in zeta[order]),
                    math.sqrt(float(np.sum(fit.fun**2)) / dof))  # fmt: skip


def _swept_states(poles: ComplexArray, w: FloatArray, dt: FloatArray, u: ComplexArray
                  ) -> ComplexArray:  # fmt: skip
    """Each block's mean of the phasors ``p_j`` of ``p' = (lambda_j - i w(t)) p + u(t)``
    (``w``, ``u`` constant over a block of length ``dt``), from the steady state at the
    first block: exact for piecewise-constant speed, (N, poles)."""
    mu = poles[None, :] - 1j * w[:, None]  # (N, J)
    e = np.exp(mu * dt[:, None])
    f = (e - 1.0) / mu  # integral of exp(mu s) over the block
    g = (f - dt[:, None]) / mu  # integral of (exp(mu s) - 1) / mu
    out = np.empty((len(w), len(poles)), dtype=complex)
    p = -u[0] / mu[0]  # steady at the first block
    for k in range(len(w)):
        out[k] = (p * f[k] + u[k] * g[k]) / dt[k]
        p = e[k] * p + f[k] * u[k]
    return out


def swept_fit(omega_rad_s: FloatArray, t_s: FloatArray, accels: list[tuple[ComplexArray,
              FloatArray]], keep: NDArray[np.bool_], start: ModalFit) -> ModalFit:  # fmt: skip
    """The modes fitted to the supports' 1x accelerations ``A`` (standard errors ``se``)
    as a sweep gives them, not as steady states would.

    Each block (its mean speed ``w``, its start ``t_s``, of one revolution) is a stretch
    of constant speed; the unbalance's force is ``U (w^2 - i alpha) e^{i theta}``
    (``alpha`` the sweep).  A mode's phasor ``p = q e^{-i theta}`` then obeys ``p' =
    (lambda - i w) p + (w^2 - i alpha)``, integrated exactly block by block along the
    measured speed; a support's acceleration is ``sum_j c_j p_j + d (w^2 - i alpha)``
    (the state space's output with its direct term), its ``c_j, d`` complex and solved
    linearly for each trial of the poles.  The blocks ``keep`` are fitted (the others only
    carry the state); started from ``start`` (:func:`modal_fit`)."""
    from scipy.optimize import least_squares

    w = np.asarray(omega_rad_s, dtype=float)
    dt = np.diff(np.append(t_s, t_s[-1] + 2 * math.pi / w[-1]))
    alpha = np.gradient(w, t_s)
    u = w * w - 1j * alpha
    n = len(start.omega_rad_s)

    def misfit(x: FloatArray) -> FloatArray:
        p = _poles(x)
        basis = np.hstack((_swept_states(np.concatenate((p, p.conj())), w, dt, u),
                           u[:, None]))[keep]  # fmt: skip
        out: list[FloatArray] = []
        for A, se in accels:
            Bw, Aw = basis / se[keep, None], A[keep] / se[keep]
            c, *_ = np.linalg.lstsq(Bw, Aw, rcond=None)
            r = Bw @ c - Aw
            out.extend((r.real, r.imag))
        return np.concatenate(out)

    x0 = np.array([*start.omega_rad_s, *np.log(np.maximum(start.zeta, 1e-4))])
    lo = np.array([w.min()] * n + [math.log(1e-4)] * n)
    hi = np.array([w.max() * 1.5] * n + [math.log(0.9)] * n)
    fit = least_squares(misfit, np.clip(x0, lo, hi), bounds=(lo, hi), x_scale="jac")
    poles = _poles(fit.x)
    wn, zeta = np.abs(poles), -poles.real / np.abs(poles)
    order = np.argsort(wn)
    dof = max(2 * int(np.count_nonzero(keep)) * len(accels) - (2 * n + 2 * (2 * n + 1) *
                                                                len(accels)), 1)  # fmt: skip
    return ModalFit(tuple(float(v) for v in wn[order]), tuple(float(v) for v in zeta[order]),
                    math.sqrt(float(np.sum(fit.fun**2)) / dof))  # fmt: skip
