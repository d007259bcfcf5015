"""Independent references for the tests: not the product's formulation.

- :func:`seed_forward`: the seed's four equations plus the two rigid-rotor
  constraints, as one 6x6 complex linear system in (x1, x2, x3, phi, P1, P2),
  solved by numpy with no elimination by hand.
- :func:`exact_terms`: ``N``, ``det D'`` and ``G`` in exact rational
  arithmetic from the float inputs (undamped stands: everything real).
"""

from __future__ import annotations

from fractions import Fraction as Fr

import numpy as np

from stand.core import StandParameters


def seed_forward(p: StandParameters, w: float, U: np.ndarray) -> np.ndarray:
    """Support acceleration phasors from the seed's equations, solved as printed."""
    L1, L2 = p.a + p.b, p.c + p.d
    s = -w * w
    A = np.zeros((6, 6), complex)
    r = np.zeros(6, complex)
    A[0] = [p.M1 * s + 1j * w * p.H1 + p.C1, 0, 0, 0, 1, 0]  # M1 x1'' = -C1 x1 - H1 x1' - P1
    A[1] = [0, p.M2 * s + 1j * w * p.H2 + p.C2, 0, 0, 0, 1]
    A[2] = [0, 0, p.M3 * s, 0, -1, -1]  # M3 x3'' = P1 + P2 + F1 + F2
    r[2] = w * w * (U[0] + U[1])
    A[3] = [0, 0, 0, p.J3 * s, -L1, L2]  # J3 phi'' = P1 L1 - P2 L2 + b F1 - c F2
    r[3] = w * w * (p.b * U[0] - p.c * U[1])
    A[4] = [1, 0, -1, -L1, 0, 0]  # x1 = x3 + L1 phi
    A[5] = [0, 1, -1, L2, 0, 0]  # x2 = x3 - L2 phi
    X = np.linalg.solve(A, r)
    return s * X[:2]


def _exact_support_matrix(p: StandParameters, w: float) -> tuple[dict[str, Fr], Fr, list[list[Fr]]]:
    """Parameters, speed and D' as exact fractions (undamped stands only)."""
    assert p.H1 == 0 and p.H2 == 0
    P = {k: Fr(getattr(p, k)) for k in ("M1", "M2", "C1", "C2", "M3", "J3", "a", "b", "c", "d")}
    W = Fr(w)
    L1, L2 = P["a"] + P["b"], P["c"] + P["d"]
    L = L1 + L2
    g1 = P["C1"] / W / W - P["M1"]
    g2 = P["C2"] / W / W - P["M2"]
    D = [
        [g1 - P["M3"] * L2 / L, g2 - P["M3"] * L1 / L],
        [L1 * g1 - P["J3"] / L, -L2 * g2 + P["J3"] / L],
    ]
    return P, W, D


def exact_terms(p: StandParameters, w: float) -> tuple[list[list[Fr]], Fr, list[list[Fr]]]:
    """(N, det D', G) exactly, for H1 = H2 = 0, built the naive way: D' then B^{-1} D'."""
    P, W, D = _exact_support_matrix(p, w)
    det = D[0][0] * D[1][1] - D[0][1] * D[1][0]
    b, c = P["b"], P["c"]
    C = [[c, Fr(1)], [b, Fr(-1)]]
    N = [[C[i][0] * D[0][j] + C[i][1] * D[1][j] for j in range(2)] for i in range(2)]
    G = [[-N[i][j] / (W * W * (b + c)) for j in range(2)] for i in range(2)]
    return N, det, G


def exact_forward(p: StandParameters, w: float, U: np.ndarray) -> np.ndarray:
    """Support phasors exactly (H1 = H2 = 0), rounded once: A = -w^2 D'^{-1} B U."""
    P, W, D = _exact_support_matrix(p, w)
    det = D[0][0] * D[1][1] - D[0][1] * D[1][0]
    out = []
    for part in (np.real, np.imag):
        u1, u2 = (Fr(float(part(x))) for x in U)
        r1, r2 = u1 + u2, P["b"] * u1 - P["c"] * u2
        x1 = (D[1][1] * r1 - D[0][1] * r2) / det
        x2 = (-D[1][0] * r1 + D[0][0] * r2) / det
        out.append((-W * W * x1, -W * W * x2))
    return np.array([float(out[0][i]) + 1j * float(out[1][i]) for i in range(2)])
