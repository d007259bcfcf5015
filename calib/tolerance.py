"""How the stand's parameter tolerances move the computed unbalance.

The model-based method needs every mass, stiffness and length; each is
known only to a tolerance.  Seed 003 argues that their contribution must be
judged statistically: each parameter is drawn uniformly within its band
(standard deviation ``band / sqrt(3)``), independently.  With the measured
support phasors ``A`` held fixed, the unbalance is recomputed:

* **linearised**: the Jacobian of ``U`` (``[Re U1, Im U1, Re U2, Im U2]``)
  with respect to every parameter, by central differences, gives the
  covariance ``J diag(sigma^2) J^T`` and each parameter's share;
* **Monte Carlo**: ``n`` draws of all parameters at once, the covariance of
  the results (this also covers the nonlinearity, which matters near a
  natural frequency).

Sensor gains act on ``A`` itself (``A_i (1 + d_i)``).  Pure numerics.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from stand.core import StandParameters
from stand.core.dsp import radius95
from stand.core.model import inverse_matrix


@dataclass(frozen=True)
class Tolerances:
    """Half-widths of the tolerance bands (uniform distributions)."""

    C_rel: float = 0.05  # C1, C2
    M_rel: float = 0.02  # M1, M2, M3, J3
    length_m: float = 1e-3  # a, b, c, d
    gain_rel: float = 0.01  # each node's sensitivity


@dataclass(frozen=True)
class ParameterUncertainty:
    """The unbalance's spread from the parameter tolerances.

    ``radius95_*`` are each plane's 95 % radius [kg m]; ``shares`` the
    linearised variance share of each parameter (summing to 1 per plane).
    """

    U_kg_m: NDArray[np.complex128]
    cov_linear: NDArray[np.float64]
    cov_monte_carlo: NDArray[np.float64]
    radius95_linear: NDArray[np.float64]
    radius95_monte_carlo: NDArray[np.float64]
    shares: dict[str, tuple[float, float]]
    draws: int


def _names(tol: Tolerances) -> list[tuple[str, float, bool]]:
    """(parameter, half-width, relative?) for everything that has a tolerance."""
    out = [(k, tol.C_rel, True) for k in ("C1", "C2")]
    out += [(k, tol.M_rel, True) for k in ("M1", "M2", "M3", "J3")]
    out += [(k, tol.length_m, False) for k in ("a", "b", "c", "d")]
    out += [(k, tol.gain_rel, True) for k in ("gain1", "gain2")]
    return [x for x in out if x[1] > 0]


def _solve(
    p: StandParameters, w: float, A: NDArray[np.complex128], change: dict[str, float]
) -> NDArray[np.float64]:
    fields = {k: v for k, v in change.items() if not k.startswith("gain")}
    q = dataclasses.replace(p, **{k: getattr(p, k) + v for k, v in fields.items()})
    g = np.array([1 + change.get("gain1", 0.0), 1 + change.get("gain2", 0.0)])
    # a node that reads (1 + d) times the truth: the true phasor is A / (1 + d)
    # U = G A, as solve_unbalance gives it (the same G, bitwise), without the diagnostics
    # it adds (the split's condition, the static resultant): 25 of these per answer
    U = inverse_matrix(q, w) @ (A / g)
    return np.array([U[0].real, U[0].imag, U[1].real, U[1].imag])


def _radius(cov: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.array([radius95(cov[2 * i : 2 * i + 2, 2 * i : 2 * i + 2]) for i in range(2)])


def parameter_uncertainty(
    p: StandParameters,
    omega_rad_s: float,
    A: NDArray[np.complex128],
    tol: Tolerances = Tolerances(),
    draws: int = 1000,
    seed: int = 0,
) -> ParameterUncertainty:
    """The spread of the unbalance that the parameter tolerances cause, for fixed readings A
    (``draws = 0``: linearised only)."""
    params = _names(tol)
    scale = {
        k: (h * (getattr(p, k) if not k.startswith("gain") else 1.0) if rel else h)
        for k, h, rel in params
    }
    base = _solve(p, omega_rad_s, A, {})
    J = np.empty((4, len(params)))
    for j, (k, _, _) in enumerate(params):
        step = 1e-4 * scale[k] if scale[k] else 1e-9
        J[:, j] = (_solve(p, omega_rad_s, A, {k: step}) - _solve(p, omega_rad_s, A, {k: -step})) / (
            2 * step
        )
    sigma2 = np.array([scale[k] ** 2 / 3 for k, _, _ in params])  # uniform in +-band
    cov_lin = (J * sigma2) @ J.T
    contrib = J**2 * sigma2  # per component and parameter
    shares = {}
    for j, (k, _, _) in enumerate(params):
        per_plane = []
        for i in range(2):
            total = float(np.sum(contrib[2 * i : 2 * i + 2]))
            per_plane.append(float(np.sum(contrib[2 * i : 2 * i + 2, j])) / total if total else 0.0)
        shares[k] = (per_plane[0], per_plane[1])
    cov_mc = cov_lin  # draws = 0: the linearised answer only
    if draws > 0:
        rng = np.random.default_rng(seed)
        samples = np.empty((draws, 4))
        for n in range(draws):
            change = {k: float(rng.uniform(-scale[k], scale[k])) for k, _, _ in params}
            samples[n] = _solve(p, omega_rad_s, A, change)
        cov_mc = np.cov(samples.T)
    return ParameterUncertainty(
        U_kg_m=np.array([complex(base[0], base[1]), complex(base[2], base[3])]),
        cov_linear=cov_lin,
        cov_monte_carlo=cov_mc,
        radius95_linear=_radius(cov_lin),
        radius95_monte_carlo=_radius(cov_mc),
        shares=shares,
        draws=draws,
    )
