"""The interval of a correction in N planes (stand.core.multiplane_interval).

* By least squares (plain or weighted) the correction is linear in the readings: the
  Jacobian taken by central differences of the solver equals the pseudo-inverse's, to
  1e-6 relative (the differences' rounding: steps of 1e-3 standard deviations).
* Coverage: 400 noisy sets of readings drawn about a truth; the correction of the truth
  lies within each plane's 95 % radius of the noisy correction in at least 93 % of them
  (the radius is taken on the error ellipse's largest axis, so it over-covers; 93 % is
  two binomial standard deviations, 1.1 % each, below 95 %).
"""

from __future__ import annotations

import numpy as np
import pytest

from stand.core.multiplane import solve_multiplane
from stand.core.multiplane_interval import complex_block, correction_covariance, plane_radii


def _problem(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Three speeds (six readings), three planes, correlated noise within each speed."""
    rng = np.random.default_rng(seed)
    alpha = rng.normal(size=(6, 3)) + 1j * rng.normal(size=(6, 3))
    A = rng.normal(size=6) + 1j * rng.normal(size=6)
    cov = np.zeros((12, 12))
    for k in range(3):
        m = rng.normal(size=(4, 4)) * 0.05
        cov[4 * k : 4 * k + 4, 4 * k : 4 * k + 4] = m @ m.T + 0.01 * np.eye(4)
    sd = np.sqrt(np.diag(cov).reshape(6, 2).mean(1))
    return A, alpha, cov, 1.0 / sd


@pytest.mark.parametrize("method", ["ls", "wls"])
def test_least_squares_is_linear_and_its_jacobian_is_the_pseudo_inverse(method: str) -> None:
    A, alpha, cov, w = _problem(1)
    weights = w if method == "wls" else None
    got = correction_covariance(A, alpha, cov, method=method, weights=weights)
    wr = np.repeat(np.ones(6) if weights is None else weights, 2)
    K = -np.linalg.pinv(complex_block(alpha) * wr[:, None]) * wr[None, :]
    want = K @ cov @ K.T
    assert np.allclose(got, want, rtol=1e-6, atol=1e-9 * np.abs(want).max())


def test_the_radius_holds_the_truth_in_95_percent() -> None:
    A, alpha, cov, _ = _problem(2)
    truth = solve_multiplane(A, alpha).W
    radii = plane_radii(correction_covariance(A, alpha, cov))
    rng = np.random.default_rng(3)
    L = np.linalg.cholesky(cov)
    hits = np.zeros(3)
    for _ in range(400):
        e = L @ rng.normal(size=12)
        W = solve_multiplane(A + e[0::2] + 1j * e[1::2], alpha).W
        hits += np.abs(W - truth) <= radii
    share = hits / 400
    assert np.all(share >= 0.93), share


def test_min_max_and_caps_are_linearised_where_used() -> None:
    """Min-max (and a cap in force) are not linear: their radius is the local one, finite
    and of the size of least squares' (within a factor of 3 here)."""
    A, alpha, cov, _ = _problem(4)
    ls = plane_radii(correction_covariance(A, alpha, cov))
    mm = plane_radii(correction_covariance(A, alpha, cov, method="minmax"))
    assert np.all(np.isfinite(mm)) and np.all(mm > ls / 3) and np.all(mm < 3 * ls), (ls, mm)
