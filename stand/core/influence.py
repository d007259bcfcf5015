"""A measured inverse: influence coefficients in place of the stand model.

The field method measures how each support's 1x answers a known unbalance
(trial runs, :mod:`stand.calib.influence`) instead of computing it from
masses and stiffnesses.  In the model's own convention, with the support
phasors ``A`` [m/s^2] and the unbalances ``U = q R e^{-i phi}`` [kg m]::

    A = alpha U             alpha: (supports, planes) [m/s^2 per kg m]
    U = alpha^+ A           (least squares when supports > planes)

so a measured ``alpha`` serves every step after the 1x phasors exactly as
the model's ``G`` does: corrections, tolerance, check.  The matrix is
measured, so it carries an error of its own; to first order
``dU = alpha^+ (dA - d alpha U)``, and both parts enter the covariance.

Pure numerics: arrays in, arrays out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stand.core.inverse import Diagnostic, UnbalanceSolution, propagate_covariance
from stand.core.model import ComplexArray
from stand.errors import ModelError
from stand.i18n.words import said

COND_WARN = 10.0
"""An influence matrix with a condition number above this draws a warning."""


@dataclass(frozen=True)
class InfluenceMap:
    """Support phasors per unit unbalance, measured.

    Attributes
    ----------
    alpha : complex ndarray, shape (supports, planes)
        ``dA / dU`` [m/s^2 per kg m], ``U = q R e^{-i phi}``.
    cov_alpha : ndarray or None, shape (2 s p, 2 s p)
        Real covariance of ``[Re, Im]`` of ``alpha.ravel()`` (row-major), from the
        trial runs' noise; None when unknown (typed-in readings).
    """

    alpha: ComplexArray
    cov_alpha: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        a = np.asarray(self.alpha)
        if a.ndim != 2 or a.shape[0] < a.shape[1] or not np.all(np.isfinite(a)):
            raise ModelError(
                f"an influence matrix is finite, supports x planes with supports >= planes, "
                f"got shape {a.shape}"
            )
        n = 2 * a.size
        if self.cov_alpha is not None and np.shape(self.cov_alpha) != (n, n):
            raise ModelError(f"the matrix covariance must be {n} x {n}")


def matrix_jacobian(G: ArrayLike, U: ArrayLike, supports: int) -> NDArray[np.float64]:
    """``d[Re U, Im U] / d[Re alpha, Im alpha]`` at ``U``: real, ``(2 p, 2 s p)``.

    From ``dU = -G d alpha U`` (exact for square ``alpha``; for least squares the
    first-order term of the residual is left out, small when the fit is good).
    """
    Gm = np.asarray(G, dtype=np.complex128)
    Uv = np.asarray(U, dtype=np.complex128)
    planes = Gm.shape[0]
    J = np.empty((2 * planes, 2 * supports * planes))
    for i in range(supports):
        for j in range(planes):
            k = 2 * (i * planes + j)
            for part, unit in ((0, 1.0), (1, 1j)):
                dU = -Gm[:, i] * Uv[j] * unit
                J[0::2, k + part] = dU.real
                J[1::2, k + part] = dU.imag
    return J


def solve_influence(
    imap: InfluenceMap, A: ArrayLike, cov_A: ArrayLike | None = None
) -> UnbalanceSolution:
    """The unbalances from support phasors through a measured influence matrix.

    Parameters
    ----------
    imap
        The matrix and its covariance.
    A
        Support phasors [m/s^2].
    cov_A
        Real covariance of ``[Re A1, Im A1, ...]`` (or None).

    Returns
    -------
    UnbalanceSolution
        ``G = alpha^+``; ``cov_U`` (real) holds the phasors' noise and the
        matrix's own error; ``split_condition`` is the matrix's condition number.
    """
    alpha = np.asarray(imap.alpha, dtype=np.complex128)
    Avec = np.asarray(A, dtype=np.complex128)
    if Avec.shape != (alpha.shape[0],) or not np.all(np.isfinite(Avec)):
        raise ModelError(f"expected {alpha.shape[0]} finite support phasors, got {Avec}")
    G = np.asarray(np.linalg.pinv(alpha), dtype=np.complex128)
    U = G @ Avec
    sv = np.linalg.svd(G, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    cov = None
    if cov_A is not None:
        cov = np.asarray(propagate_covariance(G, cov_A)).real
        if imap.cov_alpha is not None:
            J = matrix_jacobian(G, U, alpha.shape[0])
            cov = cov + J @ imap.cov_alpha @ J.T
    notes = []
    if cond > COND_WARN:
        notes.append(
            Diagnostic(
                "ill_conditioned",
                said(
                    "the influence matrix has condition number {cond}: the planes act almost "
                    "alike on the sensors, and reading errors are magnified that much in the "
                    "correction; choose planes further apart or sensors that tell them apart",
                    cond=f"{cond:.3g}",
                ),
                cond,
            )
        )
    return UnbalanceSolution(
        U_kg_m=U,
        G=G,
        condition_number=cond,
        split_condition=cond,
        noise_gain=float(sv[0]),
        static_kg_m=complex(U.sum()),
        cov_U=cov,
        diagnostics=notes,
    )
