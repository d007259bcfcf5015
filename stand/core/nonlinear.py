"""Nonlinear supports (dry friction, a clearance) recognised from the 3x they make.

The stand model is linear.  A support with dry friction or a clearance adds a
force that is an odd function of the support's own motion (seed 003 writes
both as smoothed ``(2/pi) arctan`` terms):

- dry friction ``-F_i sign(v_i)``: a square wave in step with the velocity;
- a clearance ``g_i`` in the spring of stiffness ``C_i``: the spring pushes
  only beyond the gap, i.e. the linear model's ``C_i x_i`` is too large by
  ``C_i clip(x_i, -g_i, g_i)``, a square wave of height ``k_i = C_i g_i`` in
  step with the displacement (once the motion exceeds the gap).

With the support moving as ``x_i = Re(X_i e^{i theta})`` (``X_i = -A_i /
w^2``, ``V_i = i w X_i``), a square wave ``s(u) = (4/pi)(cos u - cos 3u / 3 +
...)`` gives

- friction: 1x force ``-(4/pi) F_i e^{i psi_i}``, 3x force ``+(4/(3 pi)) F_i
  e^{3 i psi_i}``, ``psi_i = arg V_i``;
- clearance: 1x force ``+(4/pi) k_i e^{i chi_i}``, 3x force ``-(4/(3 pi)) k_i
  e^{3 i chi_i}``, ``chi_i = arg X_i``.

The 3x forces shake the stand at ``3 w``, where its accelerations per unit
support force are ``R(W) = -W^2 (K + i W H - W^2 M)^-1`` (:func:`accelerance`).
So each kind predicts the 3x at both nodes from two non-negative numbers
(``F_1, F_2`` or ``k_1, k_2``) and the measured 1x: four real equations, two
unknowns.  A 3x that a kind explains (a small residual) is that kind's
signature; a misaligned drive's 3x has no such tie to the supports' motion,
and a 2x says nothing here.  The kind's 1x force, put through the stand
model and the inverse, is the error it makes in the unbalance
(:func:`implied_error`).  Arrays in, arrays out; SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from stand.core.model import ComplexArray, StandParameters, inverse_matrix, mass_matrix

KINDS = ("friction", "clearance")


def accelerance(p: StandParameters, omega_rad_s: float) -> ComplexArray:
    """Support accelerations per unit support force at ``omega`` [m/s^2 / N], (2, 2).

    ``R = -W^2 (K + i W H - W^2 M)^-1`` with ``K = diag(C1, C2)``, ``H =
    diag(H1, H2)`` and ``M`` the :func:`~stand.core.model.mass_matrix`.
    """
    W = float(omega_rad_s)
    Z = np.diag([p.C1, p.C2]) + 1j * W * np.diag([p.H1, p.H2]) - W * W * mass_matrix(p)
    result: ComplexArray = np.asarray(-W * W * np.linalg.inv(Z), dtype=complex)
    return result


TURN = 1024
"""Points of one turn on which the motion's sign changes are found (each then placed by
linear interpolation, so its error is second order: about 1e-6 of a turn)."""


def _sign_harmonics(values: np.ndarray, k: int) -> ComplexArray:
    """The ``k``-th harmonic phasor of ``sign(values)`` over one turn, per row, exactly
    for the interpolated crossings: ``(1/pi) sum_j s_j (e^{-ik a_j} - e^{-ik b_j}) / (ik)``."""
    h = 2 * math.pi / values.shape[1]
    out = np.zeros(len(values), dtype=complex)
    for r, v in enumerate(values):
        nxt = np.roll(v, -1)
        pos, pos_next = v >= 0, nxt >= 0
        at = np.flatnonzero(pos != pos_next)
        if len(at) == 0:
            continue  # no change of sign: a constant has no harmonics
        cross = (at + v[at] / (v[at] - nxt[at])) * h
        after = np.where(pos_next[at], 1.0, -1.0)  # the sign from each crossing to the next
        ends = np.append(cross[1:], cross[0] + 2 * math.pi)
        terms = after * (np.exp(-1j * k * cross) - np.exp(-1j * k * ends)) / (1j * k)
        out[r] = terms.sum() / math.pi
    return out


def unit_force(
    A: ComplexArray, omega: float, kind: str, orders: tuple[int, ...] = (1, 3, 5)
) -> dict[int, ComplexArray]:
    """The kind's force per newton of size on each support [N/N]: its phasors at ``orders``.

    ``A``: the supports' measured acceleration harmonics, shape (K, 2), row
    ``k - 1`` the ``k``-th (at least the 1x; the 2x, 3x and 5x refine the
    waveform).  The motion is rebuilt over one turn from them (displacement
    ``-A_k / (k w)^2`` or velocity ``-i A_k / (k w)``), and the harmonics of
    its sign read off.  For a pure 1x this is the Fourier series:
    ``-(4/pi) e^{i psi}``, ``(4/(3 pi)) e^{3 i psi}``, ``-(4/(5 pi)) e^{5 i psi}``
    for friction, the opposite signs (and ``chi``) for a clearance; with a
    strong 3x in the motion (heavy friction) the switching points move, and so
    do the phasors.
    """
    A = np.atleast_2d(np.asarray(A, dtype=complex))
    k = np.arange(1, len(A) + 1)[:, None]
    motion = -A / (k * omega) ** 2 if kind == "clearance" else -1j * A / (k * omega)
    theta = np.arange(TURN) * (2 * math.pi / TURN)
    turn = np.einsum("ki,kt->it", motion, np.exp(1j * k * theta)).real  # (2, TURN)
    sign = -1.0 if kind == "friction" else 1.0
    return {n: sign * _sign_harmonics(turn, n) for n in orders}


def force_1x(A: ComplexArray, omega: float, kind: str, size_n: np.ndarray) -> ComplexArray:
    """The kind's 1x force on each support [N] for sizes ``F_i`` or ``k_i`` [N]."""
    result: ComplexArray = np.asarray(size_n) * unit_force(A, omega, kind, (1,))[1]
    return result


def orders_of(A: ComplexArray) -> tuple[int, ...]:
    """The odd harmonics beyond 1x that ``A`` holds: (3, 5), or (3,) without a 5x row."""
    return (3, 5) if len(np.atleast_2d(A)) >= 5 else (3,)


def columns(
    p: StandParameters, omega: float, A: ComplexArray, kind: str, orders: tuple[int, ...]
) -> ComplexArray:
    """Both nodes' accelerations at each order per newton of the kind at each support,
    stacked order by order: shape (2 len(orders), 2)."""
    h = unit_force(A, omega, kind, orders)
    result: ComplexArray = np.vstack([accelerance(p, n * omega) * h[n][None, :] for n in orders])
    return result


@dataclass(frozen=True)
class OddFit:
    """How well one kind explains the measured odd harmonics (3x, and 5x where measured).

    Attributes
    ----------
    kind : str
        ``"friction"`` or ``"clearance"``.
    size_n : ndarray, shape (2,)
        ``F_i`` (friction) or ``k_i = C_i g_i`` (clearance) per support [N], >= 0.
    residual : float
        ``|a - model| / |a|``: the part of the odd harmonics the kind leaves unexplained.
    chi2 : float
        ``a^T C^-1 a``: how far they stand above their noise (4 real dof per order).
    """

    kind: str
    size_n: np.ndarray
    residual: float
    chi2: float


def _real(z: ComplexArray) -> np.ndarray:
    z = np.asarray(z)
    return np.concatenate([z.real, z.imag], axis=0)


def fit_kind(
    p: StandParameters,
    omega: float,
    A: ComplexArray,
    cov3: np.ndarray,
    kind: str,
    min_chi2: float = 0.0,
) -> OddFit:
    """Fit the odd harmonics ``a = columns @ size`` with ``size >= 0``, weighted by noise.

    ``A``: the harmonics of both supports, shape (K, 2), row ``k - 1`` the
    ``k``-th (K = 5 with the 5x, 3 without) [m/s^2]; ``cov3`` the (4, 4)
    noise covariance of one order's ``(Re a_1, Im a_1, Re a_2, Im a_2)``
    (white noise: the same at each order).
    """
    A = np.atleast_2d(np.asarray(A, dtype=complex))
    orders = orders_of(A)
    a = np.concatenate([A[n - 1] for n in orders])
    return fit_columns(kind, columns(p, omega, A, kind, orders), a, cov3, min_chi2)


def fit_columns(
    kind: str, B: ComplexArray, a: ComplexArray, cov3: np.ndarray, min_chi2: float = 0.0
) -> OddFit:
    """``a = B @ size``, ``size >= 0``: non-negative least squares whitened by the noise.

    ``a`` holds ``m`` orders of both nodes, ``(a_1, a_2)`` per order; each order's
    (4, 4) covariance is ``cov3``.  Harmonics whose chi^2 is below ``min_chi2`` are not
    fitted (nothing stands out of the noise to explain): sizes 0, residual 1.
    """
    n = len(a)  # complex entries; _real stacks their real parts, then their imaginary parts
    C = np.zeros((2 * n, 2 * n))
    for o in range(n // 2):
        idx = [2 * o, n + 2 * o, 2 * o + 1, n + 2 * o + 1]  # (Re a1, Im a1, Re a2, Im a2)
        C[np.ix_(idx, idx)] = cov3
    L = np.linalg.cholesky(C + np.eye(2 * n) * 1e-30 * max(np.trace(C), 1e-300))
    y = np.linalg.solve(L, _real(a))
    if float(y @ y) < min_chi2:
        return OddFit(kind=kind, size_n=np.zeros(B.shape[1]), residual=1.0, chi2=float(y @ y))
    X = np.linalg.solve(L, _real(B))
    from scipy.optimize import nnls  # here: scipy.optimize takes 0.3 s to import

    size, _ = nnls(X, y)
    resid = a - B @ size
    return OddFit(
        kind=kind,
        size_n=size,
        residual=float(np.linalg.norm(resid)) / max(float(np.linalg.norm(a)), 1e-300),
        chi2=float(y @ y),
    )


def implied_error(p: StandParameters, omega: float, A: ComplexArray, fit: OddFit) -> ComplexArray:
    """The error the kind's 1x force makes in the unbalance of both planes [kg m].

    The measured 1x holds ``R(w) S1`` besides the unbalance's response; the
    inverse turns it into ``G R(w) S1`` of unbalance that is not there.
    """
    S1 = force_1x(A, omega, fit.kind, fit.size_n)
    result: ComplexArray = inverse_matrix(p, omega) @ (accelerance(p, omega) @ S1)
    return result


RESIDUAL_MAX = 0.3
"""A kind explains the 3x when it leaves at most 30 % of it (friction and clearance
scenes leave 0.6 to 7 %; a misaligned drive's 3x, tied to no support's motion, about 50 %)."""
CHI2_MIN = 25.0
"""The odd harmonics must stand out of their noise: chi^2 (4 real dof per order) above 25."""
MATERIAL_DEG = 0.5
"""Flag when the implied error reaches 0.5 deg in a plane, as an angle: ``|dU| / |U|``
in radians (1 deg is 1.75 % of the unbalance, in any direction)."""


@dataclass(frozen=True)
class Nonlinearity:
    """A nonlinear support found: the kind, its fit, and the error it makes.

    Attributes
    ----------
    fit : OddFit
        The kind that explains the 3x.
    dU_kg_m : ndarray, complex, shape (2,)
        The error it makes in each plane's unbalance [kg m].
    error_deg : ndarray, shape (2,)
        ``|dU| / |U|`` per plane, as an angle [deg].
    """

    fit: OddFit
    dU_kg_m: ComplexArray
    error_deg: np.ndarray


def detect(
    p: StandParameters, omega: float, A: ComplexArray, cov3: np.ndarray, U_kg_m: ComplexArray
) -> Nonlinearity | None:
    """The kind of nonlinear support that explains a significant 3x and moves the answer
    by :data:`MATERIAL_DEG` or more; None if none does.

    ``A``: the measured harmonics of both supports, (5, 2) (1x to 5x, the 4x
    row unused) or (3, 2) where the 5x is beyond the sample rate [m/s^2];
    ``cov3``: one order's (4, 4) noise covariance (the 1x's serves: white
    noise); ``U_kg_m``: the unbalances solved from the 1x.
    """
    best: Nonlinearity | None = None
    for kind in KINDS:
        fit = fit_kind(p, omega, A, cov3, kind, CHI2_MIN)
        if fit.residual > RESIDUAL_MAX or fit.chi2 < CHI2_MIN:
            continue
        dU = implied_error(p, omega, A, fit)
        deg = np.degrees(np.abs(dU) / np.maximum(np.abs(U_kg_m), 1e-300))
        found = Nonlinearity(fit, dU, deg)
        if deg.max() >= MATERIAL_DEG and (best is None or fit.residual < best.fit.residual):
            best = found
    return best
