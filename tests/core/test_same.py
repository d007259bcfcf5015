"""Data too alike for noise: copies are caught, independent measurements never are."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stand.core.same import IMPOSSIBLE, coincidence_chance, is_same_data


def test_independent_measurements_are_never_called_the_same() -> None:
    """20,000 pairs of independent 4- and 8-dimensional noise: none is (the chance of one
    is 20,000 x 1e-12); the chance itself is uniform, as a chi-square's distribution
    function at its own variable is (its median within 0.02 of 0.5: 20,000 draws give a
    standard error of 0.0035)."""
    rng = np.random.default_rng(7)
    for k in (4, 8):
        A = rng.normal(size=(k, k))
        cov = A @ A.T + k * np.eye(k)
        L = np.linalg.cholesky(2 * cov)  # the difference of two draws
        chances = [coincidence_chance(L @ rng.normal(size=k), 2 * cov) for _ in range(10_000)]
        assert min(chances) > IMPOSSIBLE
        assert abs(float(np.median(chances)) - 0.5) < 0.02


@settings(max_examples=100, deadline=None)
@given(st.integers(2, 8), st.floats(1e-6, 1e3), st.floats(0.0, 1e-6))
def test_a_copy_is_the_same_data(k: int, sigma: float, off: float) -> None:
    """A copy, or a copy moved by at most 1e-6 of its noise, is the same data (in two
    dimensions the chance is ``off^2 / 2``: 5e-13 at 1e-6; more dimensions, less)."""
    cov = np.eye(k) * sigma**2
    assert is_same_data(np.full(k, off * sigma / np.sqrt(k)), cov)


@pytest.mark.parametrize("cov", [np.zeros((4, 4)), np.diag([1.0, 1.0, 0.0, 0.0])])
def test_without_noise_only_identical_data_are_the_same(cov: np.ndarray) -> None:
    assert is_same_data(np.zeros(4), cov)
    assert not is_same_data(np.array([0.0, 0.0, 1e-300, 0.0]), cov)
