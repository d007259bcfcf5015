"""Inverse of the stand model: support phasors -> unbalances, with their trust.

Pure numerics: arrays in, arrays out, SI units, no I/O.

What the hard cases do (README repeats this):

- Planes close together: the split of the resultant into two planes has
  condition number :func:`split_condition` (about ``2 L / (b + c)`` for
  planes close together near the centre of mass).  Above ``PLANES_CLOSE_WARN`` a warning;
  above the caller's limit (default ``MAX_SPLIT_CONDITION``)
  :class:`~stand.errors.PlanesTooCloseError`, which carries the condition
  number and the static resultant ``U1 + U2``, computed from the force
  equation alone and well determined however close the planes are.
- Speed within a factor ``RESONANCE_BAND`` of a natural frequency: warning
  ``near_resonance`` with the mode's frequency; speed further below the
  highest one: warning ``below_support_resonance``.
- Very low speed: the inverse's gain ``||G||`` grows as about ``C / w^4``;
  it is reported (``noise_gain``) with every result, so a caller can turn
  noise in the accelerations into noise in the unbalances.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stand.core.model import (
    ComplexArray,
    StandParameters,
    inverse_matrix,
    natural_frequencies,
    rad_s_to_rpm,
    support_matrix,
)
from stand.errors import ModelError, PlanesTooCloseError
from stand.i18n.words import said

#: Default largest split condition number accepted: the planes' split then
#: multiplies relative measurement error by at most 1000 (planes closer
#: than about 1/500 of the support span).
MAX_SPLIT_CONDITION = 1e3
#: Split condition number above which a warning says the planes are close.
PLANES_CLOSE_WARN = 10.0
#: A speed within this factor of a natural frequency (above or below) is near it.
RESONANCE_BAND = 1.25


@dataclass(frozen=True)
class Diagnostic:
    """A warning about a usable but doubtful result.

    Attributes
    ----------
    code : str
        Stable identifier (``near_resonance``, ``below_support_resonance``,
        ``planes_close``).
    message : str
        One sentence for the operator, with the figure.
    value : float or None
        The figure the warning is about (a frequency ratio, a condition
        number, a count), or None when there is none.
    t_s : float or None
        When it was seen, from the start of the run [s], if it belongs to
        a moment.
    """

    code: str
    message: str
    value: float | None = None
    t_s: float | None = None


@dataclass(frozen=True)
class UnbalanceSolution:
    """The inverse's answer at one speed.

    Attributes
    ----------
    U_kg_m : complex ndarray, shape (2,)
        ``U_i = q_i R_i e^{-i phi_i}`` for plane 1, 2 [kg m].
    G : complex ndarray, shape (2, 2)
        The linear map ``U = G A`` [kg m / (m/s^2)].
    condition_number : float
        2-norm condition number of ``G``: relative error in ``A`` turns into
        at most this times that relative error in ``U``.
    split_condition : float
        Condition number of the plane split alone (geometry only).
    noise_gain : float
        ``||G||_2`` [kg m per m/s^2]: the largest unbalance an acceleration
        error of 1 m/s^2 can produce.
    static_kg_m : complex
        Static resultant ``U1 + U2`` [kg m].
    cov_U : ndarray or None
        Covariance of the unbalances, in the form the phasor covariance
        came in (see :func:`propagate_covariance`).
    diagnostics : list of Diagnostic
    """

    U_kg_m: ComplexArray
    G: ComplexArray
    condition_number: float
    split_condition: float
    noise_gain: float
    static_kg_m: complex
    cov_U: NDArray[np.float64] | ComplexArray | None = None
    diagnostics: list[Diagnostic] = field(default_factory=list)


def split_condition(p: StandParameters) -> float:
    """Condition number of the plane split ``[[1, 1], [b/L, -c/L]]`` (dimensionless).

    ``inf`` when the planes coincide.  As they close in it tends to
    ``(2 + (b/L)^2 + (c/L)^2) L / (b + c)``: about ``2 L / (b + c)`` for
    planes near the centre of mass.

    Examples
    --------
    >>> p = StandParameters(M1=8, M2=9, C1=4.5e4, C2=5.2e4, M3=60, J3=21,
    ...                     a=0.15, b=0.85, c=0.70, d=0.20, R1=0.09, R2=0.08)
    >>> round(split_condition(p), 3)
    2.456
    """
    return _cond2_real(1.0, 1.0, p.b / p.L, -p.c / p.L, det=-p.plane_separation / p.L)


def _cond2_real(m11: float, m12: float, m21: float, m22: float, det: float) -> float:
    """2-norm condition number of a real 2x2 matrix with a given (accurate) determinant."""
    if det == 0:
        return math.inf
    s = m11 * m11 + m12 * m12 + m21 * m21 + m22 * m22
    ad = abs(det)
    # sigma_max^2 = (s + sqrt(s^2 - 4 det^2)) / 2, factored to avoid cancellation.
    sig_max_sq = 0.5 * (s + math.sqrt(max(s - 2 * ad, 0.0) * (s + 2 * ad)))
    return sig_max_sq / ad


def static_resultant(p: StandParameters, omega_rad_s: float, A: ArrayLike) -> complex:
    """Static resultant ``U1 + U2`` [kg m] from the force equation alone.

    Well determined whatever the planes' separation (it does not use the
    moment equation).  It is the unbalance one plane at the centre of mass
    would correct.
    """
    w = float(omega_rad_s)
    Avec = np.asarray(A, dtype=np.complex128)
    D = support_matrix(p, w)
    return complex(-(D[0, 0] * Avec[0] + D[0, 1] * Avec[1]) / (w * w))


def propagate_covariance(G: ArrayLike, cov_A: ArrayLike) -> NDArray[np.float64] | ComplexArray:
    """Covariance of ``U = G A`` from the covariance of ``A``.

    Parameters
    ----------
    G
        Complex 2x2 (or ``n x n``) map.
    cov_A
        Either the complex covariance ``E[dA dA^H]``, shape ``(n, n)``
        (enough for circular noise, as from least squares on cos and sin
        with white noise), or the real covariance of
        ``[Re A1, Im A1, Re A2, Im A2, ...]``, shape ``(2n, 2n)`` (general).

    Returns
    -------
    ndarray
        Same form as ``cov_A``: ``G cov G^H`` or ``R cov R^T`` with ``R``
        the real form of ``G``.

    Examples
    --------
    >>> G = np.array([[2.0, 0.0], [0.0, 1j]])
    >>> propagate_covariance(G, np.eye(2)).real
    array([[4., 0.],
           [0., 1.]])
    """
    Gm = np.asarray(G, dtype=np.complex128)
    C = np.asarray(cov_A)
    n = Gm.shape[-1]
    if C.shape == (n, n):
        out: ComplexArray = Gm @ C.astype(np.complex128) @ Gm.conj().T
        return out
    if C.shape == (2 * n, 2 * n):
        R = real_form(Gm)
        out_r: NDArray[np.float64] = R @ C.astype(np.float64) @ R.T
        return out_r
    raise ModelError(
        f"phasor covariance must have shape ({n}, {n}) complex or ({2 * n}, {2 * n}) real, "
        f"got {C.shape}"
    )


def real_form(G: ArrayLike) -> NDArray[np.float64]:
    """Real ``2n x 2n`` matrix acting on ``[Re z1, Im z1, ...]`` as ``G`` acts on ``z``."""
    Gm = np.asarray(G, dtype=np.complex128)
    n, m = Gm.shape
    R = np.empty((2 * n, 2 * m))
    R[0::2, 0::2] = Gm.real
    R[0::2, 1::2] = -Gm.imag
    R[1::2, 0::2] = Gm.imag
    R[1::2, 1::2] = Gm.real
    return R


def speed_diagnostics(
    p: StandParameters, omega_rad_s: float, wn_rad_s: ArrayLike | None = None
) -> list[Diagnostic]:
    """Warnings about the balancing speed against the stand's natural frequencies (the rigid
    rotor's two, or ``wn_rad_s`` given: a flexible stand's)."""
    out: list[Diagnostic] = []
    wn = natural_frequencies(p) if wn_rad_s is None else np.asarray(wn_rad_s, dtype=float)
    w = float(omega_rad_s)
    ratios = w / wn
    near = [k for k, r in enumerate(ratios) if 1 / RESONANCE_BAND < r < RESONANCE_BAND]
    if near:
        k = min(near, key=lambda k: abs(math.log(ratios[k])))
        out.append(
            Diagnostic(
                "near_resonance",
                said(
                    "speed {rpm} rpm is {off} % from natural frequency {hz} Hz ({rpm_n} rpm) "
                    "of stand + rotor: the response is dominated by the stand there and small "
                    "errors in C, M or speed move the result",
                    rpm=f"{rad_s_to_rpm(w):.1f}",
                    off=f"{100 * (ratios[k] - 1):+.1f}",
                    hz=f"{wn[k] / (2 * math.pi):.3g}",
                    rpm_n=f"{rad_s_to_rpm(wn[k]):.0f}",
                ),
                float(ratios[k]),
            )
        )
    elif w < wn[-1]:
        out.append(
            Diagnostic(
                "below_support_resonance",
                said(
                    "speed {rpm} rpm is below the highest natural frequency {hz} Hz ({rpm_n} "
                    "rpm): a soft-bearing stand should run well above it; here the result "
                    "rests on C1, C2 and noise is amplified about C/omega^4",
                    rpm=f"{rad_s_to_rpm(w):.1f}",
                    hz=f"{wn[-1] / (2 * math.pi):.3g}",
                    rpm_n=f"{rad_s_to_rpm(wn[-1]):.0f}",
                ),
                float(w / wn[-1]),
            )
        )
    return out


def solve_unbalance(
    p: StandParameters,
    omega_rad_s: float,
    A: ArrayLike,
    cov_A: ArrayLike | None = None,
    *,
    max_split_condition: float = MAX_SPLIT_CONDITION,
) -> UnbalanceSolution:
    """Complex unbalances in both planes from the support acceleration phasors.

    Parameters
    ----------
    p
        Stand and rotor.
    omega_rad_s
        Shaft speed [rad/s].
    A
        Complex 1x acceleration of support 1, 2 [m/s^2], shape (2,), with
        ``a_i(t) = Re(A_i e^{i theta})``.
    cov_A
        Optional covariance of ``A`` (see :func:`propagate_covariance`).
    max_split_condition
        Refuse the two-plane split above this condition number.

    Returns
    -------
    UnbalanceSolution

    Raises
    ------
    PlanesTooCloseError
        If :func:`split_condition` exceeds ``max_split_condition``; the
        error carries the static resultant.
    ModelError
        For a bad speed or phasor shape.

    Examples
    --------
    >>> from stand.core.model import forward, unbalance_from_polar, unbalance_to_polar
    >>> p = StandParameters(M1=8, M2=9, C1=4.5e4, C2=5.2e4, M3=60, J3=21,
    ...                     a=0.15, b=0.85, c=0.70, d=0.20, R1=0.09, R2=0.08)
    >>> U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
    >>> sol = solve_unbalance(p, 94.25, forward(p, 94.25, U))
    >>> qR, phi = unbalance_to_polar(sol.U_kg_m)
    >>> [round(float(x) * 1e6, 6) for x in qR], [round(float(x), 9) for x in phi]
    ([5000.0, 3000.0], [30.0, 200.0])
    """
    w = float(omega_rad_s)
    Avec = np.asarray(A, dtype=np.complex128)
    if Avec.shape != (2,):
        raise ModelError(f"expected 2 support phasors, got shape {Avec.shape}")
    if not np.all(np.isfinite(Avec)):
        raise ModelError(f"support phasors must be finite, got {Avec}")
    kappa_split = split_condition(p)
    if not kappa_split <= max_split_condition:
        raise PlanesTooCloseError(
            split_condition=kappa_split,
            limit=max_split_condition,
            separation_m=p.plane_separation,
            static_unbalance_kg_m=static_resultant(p, w, Avec),
        )
    G = inverse_matrix(p, w)
    U: ComplexArray = G @ Avec
    sv = np.linalg.svd(G, compute_uv=False)
    diagnostics = speed_diagnostics(p, w)
    if kappa_split > PLANES_CLOSE_WARN:
        diagnostics.append(
            Diagnostic(
                "planes_close",
                said(
                    "correction planes {d} mm apart on a {span} mm span: the two-plane split "
                    "multiplies measurement error by up to {k}",
                    d=f"{p.plane_separation * 1e3:.4g}",
                    span=f"{p.L * 1e3:.4g}",
                    k=f"{kappa_split:.3g}",
                ),
                kappa_split,
            )
        )
    return UnbalanceSolution(
        U_kg_m=U,
        G=G,
        condition_number=float(sv[0] / sv[-1]),
        split_condition=kappa_split,
        noise_gain=float(sv[0]),
        static_kg_m=static_resultant(p, w, Avec),
        cov_U=None if cov_A is None else propagate_covariance(G, cov_A),
        diagnostics=diagnostics,
    )
