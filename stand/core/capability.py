"""The measuring process's capability for a vector quantity: repeated readings of one
master rotor's unbalance in a plane against its known value and the plane's tolerance.

Pure numerics: complex readings [kg m] in, figures out.

A scalar gauge's type-1 study (VDA 5; Bosch booklet 10) compares 20 % of the tolerance
with the readings' spread: ``Cg = 0.2 T / 6 s`` and ``Cgk = (0.1 T - |bias|) / 3 s``,
``T`` the tolerance's width, ``3 s`` the half-width that holds 99.73 % of a normal
spread.  The unbalance is a vector and its tolerance a circle of radius ``U_per`` (half
of ``T``'s role), so the spread is judged as a circle too, amount and angle together:

* ``Cg_v = 0.2 U_per / r_mean``, ``r_mean`` the radius of the circle about the readings'
  mean that holds 99.73 % of the fitted bivariate normal (its covariance from the
  readings, any shape: :func:`radius_holding`);
* ``Cgk_v = 0.2 U_per / r_ref``, ``r_ref`` the same about the master's known value: the
  bias enters as the offset of the circle, not subtracted apart.

For a round spread of standard deviation ``s`` per axis, ``r_mean = 3.44 s``.  Both
indices must reach 1.33 (the threshold VDA 5 and Bosch booklet 10 give for Cg and Cgk).
Their 95 % intervals are percentile bootstraps of the readings (:func:`capability`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import brentq
from scipy.special import ndtr

COVER = 0.9973
"""The share of readings the circles hold: that of +-3 s for a scalar."""
BAND = 0.2
"""The share of the tolerance the readings' circle is compared with."""
CAPABLE = 1.33
"""The threshold both indices must reach."""
MIN_RUNS = 25
"""Readings a study needs (VDA 5's type-1 study asks for at least 25; 50 preferred)."""
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(96)


def _held(r: float, mean: np.ndarray, sd: np.ndarray) -> float:
    """P(|X| <= r) for X with independent normal axes of means ``mean``, s.d. ``sd``: along
    the first axis, Gauss-Legendre over where the circle and the density overlap."""
    a, b = max(-r, mean[0] - 9 * sd[0]), min(r, mean[0] + 9 * sd[0])
    if a >= b:
        return 0.0
    x = 0.5 * (a + b) + 0.5 * (b - a) * _NODES
    h = np.sqrt(np.maximum(r * r - x * x, 0.0))
    density = np.exp(-0.5 * ((x - mean[0]) / sd[0]) ** 2) / (sd[0] * math.sqrt(2 * math.pi))
    band = ndtr((h - mean[1]) / sd[1]) - ndtr((-h - mean[1]) / sd[1])
    return float(0.5 * (b - a) * np.dot(_WEIGHTS, density * band))


def radius_holding(cov: ArrayLike, offset: complex = 0j, cover: float = COVER) -> float:
    """The radius of the circle about ``offset`` (from the spread's centre) that holds
    ``cover`` of a bivariate normal of covariance ``cov`` (real 2 x 2, re/im).

    >>> round(radius_holding(np.eye(2)), 4)  # a round spread: sqrt(-2 ln(1 - 0.9973))
    3.4393
    """
    lam, vec = np.linalg.eigh(np.asarray(cov, dtype=float))
    sd = np.sqrt(np.maximum(lam, 1e-300 * max(float(lam.max()), 1e-300)))
    centre = vec.T @ np.array([-offset.real, -offset.imag])  # the spread's centre, seen from it
    hi = float(np.abs(centre).sum() + 8 * sd.max())
    return float(brentq(lambda r: _held(r, centre, sd) - cover, 0.0, hi, xtol=1e-12 * hi))


def _indices(z: np.ndarray, reference: complex, band: float) -> tuple[float, float, float, float]:
    """(Cg_v, Cgk_v, r_mean, r_ref) of readings ``z``."""
    cov = np.cov(np.vstack([z.real, z.imag]))
    bias = complex(z.mean() - reference)
    r_mean = radius_holding(cov)
    r_ref = radius_holding(cov, -bias)
    return band / r_mean, band / r_ref, r_mean, r_ref


@dataclass(frozen=True)
class Capability:
    """One plane's study: readings, bias [kg m], the 99.73 % radii about the mean and the
    reference [kg m], the indices with their 95 % intervals, the verdict."""

    runs: int
    mean_kg_m: complex
    bias_kg_m: complex
    r_mean_kg_m: float
    r_ref_kg_m: float
    cg: float
    cgk: float
    cg_interval: tuple[float, float]
    cgk_interval: tuple[float, float]

    @property
    def capable(self) -> bool:
        """Both indices at or above :data:`CAPABLE`."""
        return self.cg >= CAPABLE and self.cgk >= CAPABLE


def capability(
    readings_kg_m: ArrayLike, reference_kg_m: complex, tolerance_kg_m: float,
    resamples: int = 1000, seed: int = 0,
) -> Capability:  # fmt: skip
    """The study of one plane's readings against the master's ``reference`` and the plane's
    tolerance ``U_per`` (a percentile bootstrap of ``resamples``, seeded: repeatable)."""
    z = np.asarray(readings_kg_m, dtype=complex).ravel()
    if z.size < MIN_RUNS:
        raise ValueError(f"{z.size} readings: a capability study needs at least {MIN_RUNS}")
    band = BAND * tolerance_kg_m
    cg, cgk, r_mean, r_ref = _indices(z, reference_kg_m, band)
    rng = np.random.default_rng(seed)
    boot = np.array([_indices(z[rng.integers(0, z.size, z.size)], reference_kg_m, band)[:2]
                     for _ in range(resamples)])  # fmt: skip
    lo, hi = np.percentile(boot, [2.5, 97.5], axis=0)
    mean = complex(z.mean())
    return Capability(z.size, mean, mean - reference_kg_m, r_mean, r_ref, cg, cgk,
                      (float(lo[0]), float(hi[0])), (float(lo[1]), float(hi[1])))  # fmt: skip


def runs_needed(cg: float, threshold: float = CAPABLE, most: int = 10_000) -> int | None:
    """The fewest readings for which an index estimated at ``cg`` has the lower end of its
    95 % interval at ``threshold`` (a round spread: the variance's chi-square with 2(N-1)
    degrees of freedom); None if more than ``most``."""
    from scipy.stats import chi2

    if cg <= threshold:
        return None
    for n in range(MIN_RUNS, most + 1):
        dof = 2 * (n - 1)
        if cg * math.sqrt(chi2.ppf(0.025, dof) / dof) >= threshold:
            return n
    return None
