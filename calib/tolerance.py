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
from types import SimpleNamespace

import numpy as np
from numpy.typing import NDArray

from stand.core import StandParameters
from stand.core.dsp import radius95
from stand.core.model import plane_matrix

_MODEL = tuple(f.name for f in dataclasses.fields(StandParameters))
"""The stand's parameters (the gains are the nodes', not the model's)."""


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
    p: StandParameters, w: float, A: NDArray[np.complex128], changes: list[dict[str, float]]
) -> NDArray[np.float64]:
    """``[Re U1, Im U1, Re U2, Im U2]`` for each of ``changes`` (one row each).

    Each changed stand is checked as :class:`StandParameters` checks it; the
    inverse matrices of all of them are then computed at once, their
    parameters as arrays, one entry a change: the same IEEE operations
    elementwise, so each row is bitwise what :func:`inverse_matrix` of that
    stand alone gives (tested).
    """
    stands = [
        dataclasses.replace(p, **{k: getattr(p, k) + v for k, v in c.items() if k in _MODEL})
        for c in changes
    ]
    batch = SimpleNamespace(
        **{k: np.array([getattr(q, k) for q in stands]) for k in _MODEL}
    )  # read as a stand, by attribute only
    w_ = np.asarray(w, dtype=np.float64)
    scale = -1.0 / (w_ * w_ * (batch.b + batch.c))
    G = plane_matrix(batch, w_) * scale[:, None, None]  # type: ignore[arg-type]
    # a node that reads (1 + d) times the truth: the true phasor is A / (1 + d)
    g = np.array([[1 + c.get("gain1", 0.0), 1 + c.get("gain2", 0.0)] for c in changes])
    U = np.array([Gk @ (A / gk) for Gk, gk in zip(G, g, strict=True)])  # as solve_unbalance
    return np.stack([U[:, 0].real, U[:, 0].imag, U[:, 1].real, U[:, 1].imag], axis=1)


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
    steps = [1e-4 * scale[k] if scale[k] else 1e-9 for k, _, _ in params]
    changes: list[dict[str, float]] = [{}]
    for (k, _, _), step in zip(params, steps, strict=True):
        changes += [{k: step}, {k: -step}]
    U = _solve(p, omega_rad_s, A, changes)
    base = U[0]
    J = ((U[1::2] - U[2::2]) / (2 * np.array(steps))[:, None]).T
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
        draw = [
            {k: float(rng.uniform(-scale[k], scale[k])) for k, _, _ in params} for _ in range(draws)
        ]
        cov_mc = np.cov(_solve(p, omega_rad_s, A, draw).T)
    return ParameterUncertainty(
        U_kg_m=np.array([complex(base[0], base[1]), complex(base[2], base[3])]),
        cov_linear=cov_lin,
        cov_monte_carlo=cov_mc,
        radius95_linear=_radius(cov_lin),
        radius95_monte_carlo=_radius(cov_mc),
        shares=shares,
        draws=draws,
    )
