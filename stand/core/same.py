"""Two measurements that are one: data too alike for noise to have made them.

Two independent measurements of anything differ by their noise: the difference
``delta`` (k real numbers) with covariance ``cov`` (both measurements'
covariances summed) makes ``d2 = delta^T cov^-1 delta`` chi-square with k
degrees of freedom, at least (a real difference between the two only adds to
it).  The chance that noise alone brings it as low as ``d2`` is the
chi-square distribution at ``d2``; below :data:`IMPOSSIBLE` the two are the
same data under two names (the same run given twice, a byte copy, a datum
copied under another digest).

Pure numerics: arrays in, numbers out.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

IMPOSSIBLE = 1e-12
"""A chance this small is no chance: at a million comparisons a day, once in three
thousand years."""


def coincidence_chance(delta: ArrayLike, cov: ArrayLike) -> float:
    """The chance that two independent measurements differ by ``delta`` or less
    (real, k values), their difference's covariance ``cov`` (k x k): the chi-square
    distribution with k degrees of freedom at ``delta^T cov^-1 delta``.

    >>> round(coincidence_chance([0.0, 0.0], np.eye(2)), 12)
    0.0
    >>> round(coincidence_chance([1.0, 1.0], np.eye(2)), 4)  # 1 - exp(-1)
    0.6321
    """
    from scipy.special import gammainc

    d = np.asarray(delta, dtype=float).ravel()
    C = np.asarray(cov, dtype=float).reshape(d.size, d.size)
    try:
        d2 = float(d @ np.linalg.solve(C, d))
    except np.linalg.LinAlgError:  # no noise to judge by: the same only when identical
        return 0.0 if not np.any(d) else 1.0
    if not np.isfinite(d2):
        return 1.0
    return float(gammainc(d.size / 2, max(d2, 0.0) / 2))


def is_same_data(delta: ArrayLike, cov: ArrayLike) -> bool:
    """Whether noise cannot have made two measurements this alike
    (:func:`coincidence_chance` below :data:`IMPOSSIBLE`)."""
    return coincidence_chance(delta, cov) < IMPOSSIBLE
