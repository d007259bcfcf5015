"""How sure a correction in N planes is: its covariance from the readings' covariance.

Pure numerics (arrays in, arrays out).  :func:`stand.core.multiplane.solve_multiplane`
maps the readings ``A`` to the correction ``W``.  By least squares (weighted or not)
without a cap that map is linear, ``W = K A``; by min-max, or with a cap in force, it is
not, and it is linearised where it is used.  Both ways the Jacobian ``J = dW/dA`` is taken
by central differences of the solver itself, one real component of the readings at a time
(exact to rounding where the map is linear), and::

    cov_W = J cov_A J^T

on ``[Re W1, Im W1, Re W2, Im W2, ...]``.  Each plane's 95 % radius is
:func:`stand.core.dsp.radius95` of its 2 x 2 block.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stand.core.dsp import radius95
from stand.core.multiplane import solve_multiplane

FloatArray = NDArray[np.float64]

STEP = 1e-3
"""Each reading component is moved by this share of its standard deviation."""


def complex_block(E: ArrayLike) -> FloatArray:
    """The real map of a complex matrix on interleaved ``[Re z1, Im z1, Re z2, Im z2, ...]``.

    >>> complex_block([[1j]]).tolist()
    [[0.0, -1.0], [1.0, 0.0]]
    """
    Ec = np.asarray(E, dtype=np.complex128)
    out = np.empty((2 * Ec.shape[0], 2 * Ec.shape[1]))
    out[0::2, 0::2], out[0::2, 1::2] = Ec.real, -Ec.imag
    out[1::2, 0::2], out[1::2, 1::2] = Ec.imag, Ec.real
    return out


def correction_covariance(
    A: ArrayLike, alpha: ArrayLike, cov_A: ArrayLike, **solver: Any
) -> FloatArray:
    """``cov_W`` (2N x 2N, interleaved real and imaginary parts) of the correction that
    :func:`~stand.core.multiplane.solve_multiplane` gives for readings ``A`` (M) with real
    covariance ``cov_A`` (2M x 2M, interleaved); ``solver``: its ``method``, ``weights`` and
    ``caps``."""
    A0 = np.asarray(A, dtype=np.complex128)
    cov = np.asarray(cov_A, dtype=float)
    n = np.asarray(alpha).shape[1]
    J = np.zeros((2 * n, 2 * len(A0)))
    for k in range(2 * len(A0)):
        h = STEP * float(np.sqrt(max(cov[k, k], 0.0)))
        if h == 0.0:
            continue  # a component without noise moves nothing
        dA = np.zeros(len(A0), complex)
        dA[k // 2] = h if k % 2 == 0 else 1j * h
        up = solve_multiplane(A0 + dA, alpha, **solver).W
        down = solve_multiplane(A0 - dA, alpha, **solver).W
        d = (up - down) / (2 * h)
        J[0::2, k], J[1::2, k] = d.real, d.imag
    out: FloatArray = J @ cov @ J.T
    return out


def plane_radii(cov_W: ArrayLike) -> FloatArray:
    """Each plane's 95 % radius from ``cov_W`` (2N x 2N, interleaved) [the unit of W]."""
    c = np.asarray(cov_W, dtype=float)
    return np.array([radius95(c[2 * j : 2 * j + 2, 2 * j : 2 * j + 2]) for j in range(len(c) // 2)])
