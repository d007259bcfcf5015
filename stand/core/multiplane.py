"""Corrections in N planes from M readings: least squares, weighted, min-max.

Readings ``A`` (M complex values: sensors x speeds) and an influence matrix
``alpha`` (M x N: each reading's change per unit correction in each plane)
give the residual after a correction ``W`` (N complex values)::

    r = A + alpha W

and the correction is chosen to make ``r`` small (Goodman 1964):

- ``ls``: the least ``sum |r_i|^2``;
- ``wls``: the least ``sum w_i^2 |r_i|^2``, ``w_i`` a weight per reading
  (e.g. one over its noise, or over its permissible value);
- ``minmax``: the least ``max w_i |r_i|`` (Woomer & Pilkey 1979; Foiles,
  Allaire & Gunter 2000), ``w_i = 1`` unless given.

each optionally with a cap on each plane's ``|W_j|``.  Min-max is solved as
a linear program with scipy's HiGHS: ``|z| <= t`` becomes ``Re(z e^{-i
theta_k}) <= t`` for :data:`POLYGON` directions ``theta_k`` (a regular
polygon around the circle, so the true ``max |r|`` is at most
``1 / cos(pi / POLYGON)``, 1.0003, above the program's ``t``), then
polished on the exact circles with SLSQP; the answer is the better of the
two, and never worse than least squares (which is a candidate as well).
The caps are inner polygons: a capped ``|W_j|`` never exceeds its cap.

Before solving, the planes are tested for independence (Darlow 1982): the
columns, by decreasing norm, are orthogonalised in turn against those kept;
a column whose part orthogonal to them is at most :data:`SIGNIFICANCE_MIN`
of its norm is a plane the others can imitate, and it is left out of the
solution (its correction is zero), with a warning naming it.

Pure numerics: arrays in, arrays out; the units are the caller's (the
stand's: ``A`` in m/s^2, ``W`` in kg m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stand.core.inverse import Diagnostic
from stand.errors import ModelError
from stand.i18n.words import said

METHODS = ("ls", "wls", "minmax")
"""The criteria: least squares, weighted least squares, min-max."""
METHOD_NAMES = {"ls": "least squares", "wls": "weighted least squares", "minmax": "min-max"}
"""Each criterion as the operator reads it."""
SIGNIFICANCE_MIN = 0.2
"""Darlow's significance factor at or below which a plane counts as not independent
(the value Darlow recommends)."""
POLYGON = 128
"""Sides of the polygon that stands for each circle in the min-max program."""
COND_WARN = 10.0
"""A weighted matrix (columns scaled to one) with a condition number above this draws a
warning: reading errors are magnified that much in the correction."""

ComplexVector = NDArray[np.complex128]


@dataclass(frozen=True)
class MultiPlaneSolution:
    """A correction in N planes and what it leaves at every reading.

    Attributes
    ----------
    W : complex ndarray, shape (N,)
        The correction per plane (zero for a plane left out), in the unit of
        ``alpha``'s columns (the stand's: kg m, ``m r e^{-i angle}``).
    residual : complex ndarray, shape (M,)
        ``A + alpha W``: the readings predicted after the correction.
    rms, worst : float
        ``sqrt(mean |r_i|^2)`` and ``max |r_i|`` (unweighted, the readings' unit).
    method : str
        ``ls``, ``wls`` or ``minmax``.
    condition_number : float
        Of the weighted matrix of the planes kept, columns scaled to unit norm.
    significance : ndarray, shape (N,)
        Darlow's factor per plane (1 for the first, the largest column).
    dependent : tuple of int
        The planes (0-based) left out as not independent.
    at_cap : tuple of bool
        Whether each plane's correction sits at its cap.
    diagnostics : list of Diagnostic
    """

    W: ComplexVector
    residual: ComplexVector
    rms: float
    worst: float
    method: str
    condition_number: float
    significance: NDArray[np.float64]
    dependent: tuple[int, ...]
    at_cap: tuple[bool, ...]
    diagnostics: list[Diagnostic] = field(default_factory=list)


def significance_factors(alpha: ArrayLike) -> NDArray[np.float64]:
    """Darlow's significance factor of each column (plane) of ``alpha``.

    Columns are taken by decreasing norm; each is orthogonalised against the
    columns already kept (those whose factor exceeded :data:`SIGNIFICANCE_MIN`);
    its factor is the norm of what is left over its own norm.

    >>> f = significance_factors([[1, 2, 1], [1, 2, 0], [0, 0, 1]])
    >>> [round(float(x), 3) for x in f]
    [0.0, 1.0, 0.866]
    """
    a = np.asarray(alpha, dtype=np.complex128)
    norms = np.linalg.norm(a, axis=0)
    out = np.zeros(a.shape[1])
    basis: list[ComplexVector] = []
    for j in np.argsort(-norms, kind="stable"):
        if norms[j] == 0:
            continue
        v = a[:, j].copy()
        for e in basis:  # modified Gram-Schmidt, twice for round-off
            v -= (e.conj() @ v) * e
        for e in basis:
            v -= (e.conj() @ v) * e
        out[j] = float(np.linalg.norm(v) / norms[j])
        if out[j] > SIGNIFICANCE_MIN:
            basis.append(v / np.linalg.norm(v))
    return out


def _check(
    A: ArrayLike, alpha: ArrayLike, weights: ArrayLike | None, caps: ArrayLike | None
) -> tuple[ComplexVector, NDArray[np.complex128], NDArray[np.float64], NDArray[np.float64]]:
    a = np.asarray(alpha, dtype=np.complex128)
    r = np.asarray(A, dtype=np.complex128)
    if a.ndim != 2 or r.shape != (a.shape[0],):
        raise ModelError(
            f"the readings ({np.shape(A)}) and the influence matrix ({np.shape(alpha)}) do "
            "not match: one matrix row per reading"
        )
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(r))):
        raise ModelError("the readings and the influence matrix must be finite")
    w = np.ones(len(r)) if weights is None else np.asarray(weights, dtype=float)
    if w.shape != r.shape or not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise ModelError(f"expected {len(r)} finite positive weights, one per reading")
    c = np.full(a.shape[1], np.inf) if caps is None else np.asarray(caps, dtype=float)
    if c.shape != (a.shape[1],) or np.any(np.isnan(c)) or np.any(c <= 0):
        raise ModelError(f"expected {a.shape[1]} positive caps, one per plane")
    return r, a, w, c


def solve_multiplane(
    A: ArrayLike,
    alpha: ArrayLike,
    method: str = "ls",
    weights: ArrayLike | None = None,
    caps: ArrayLike | None = None,
) -> MultiPlaneSolution:
    """The correction ``W`` that makes ``A + alpha W`` small by ``method``.

    Parameters
    ----------
    A : complex, shape (M,)
        The readings (any unit, the same for all).
    alpha : complex, shape (M, N)
        Influence coefficients: reading change per unit correction.
    method : {"ls", "wls", "minmax"}
    weights : float, shape (M,), optional
        Per reading; required for ``wls``, optional for ``minmax``, refused for ``ls``.
    caps : float, shape (N,), optional
        The largest ``|W_j|`` per plane (``inf`` for none).

    Returns
    -------
    MultiPlaneSolution
    """
    if method not in METHODS:
        raise ModelError(f"method {method!r}: one of {', '.join(METHODS)}")
    if method == "wls" and weights is None:
        raise ModelError("weighted least squares needs a weight per reading")
    if method == "ls" and weights is not None:
        raise ModelError("least squares takes no weights: use wls")
    r0, a, w, cap = _check(A, alpha, weights, caps)
    aw = a * w[:, None]
    sig = significance_factors(aw)
    keep = np.flatnonzero(sig > SIGNIFICANCE_MIN)
    if keep.size == 0:
        raise ModelError("the influence matrix is zero: no plane moves any reading")
    # scale: readings to about one, every kept column to unit norm
    s = float(np.max(np.abs(r0 * w))) or 1.0
    col = np.linalg.norm(aw[:, keep], axis=0)
    B = aw[:, keep] / col
    b = r0 * w / s
    box = cap[keep] * col / s
    y = _least_squares(b, B, box)
    if method == "minmax":
        y = _minmax(b, B, box, y)
    W = np.zeros(a.shape[1], complex)
    W[keep] = y * s / col
    res = r0 + a @ W
    cond = float(np.linalg.cond(B))
    at_cap = tuple(
        bool(np.isfinite(cap[j]) and abs(W[j]) >= cap[j] * (1 - 1e-6)) for j in range(len(W))
    )
    notes = _notes(sig, keep, cond)
    return MultiPlaneSolution(
        W=W,
        residual=res,
        rms=float(np.sqrt(np.mean(np.abs(res) ** 2))),
        worst=float(np.max(np.abs(res))),
        method=method,
        condition_number=cond,
        significance=sig,
        dependent=tuple(int(j) for j in np.flatnonzero(sig <= SIGNIFICANCE_MIN)),
        at_cap=at_cap,
        diagnostics=notes,
    )


def _notes(sig: NDArray[np.float64], keep: NDArray[Any], cond: float) -> list[Diagnostic]:
    notes = [
        Diagnostic(
            "dependent_plane",
            said(
                "plane {plane} is not independent of the others (Darlow's significance "
                "factor {sig}, at most {most}): the others can do what it does, so it is left "
                "out and the correction uses the remaining planes",
                plane=j + 1,
                sig=f"{sig[j]:.3f}",
                most=f"{SIGNIFICANCE_MIN:g}",
            ),
            float(sig[j]),
        )
        for j in range(len(sig))
        if j not in keep
    ]
    if cond > COND_WARN:
        notes.append(
            Diagnostic(
                "ill_conditioned",
                said(
                    "the influence matrix has condition number {cond}: the planes act almost "
                    "alike on the readings, and reading errors are magnified that much in the "
                    "correction",
                    cond=f"{cond:.3g}",
                ),
                cond,
            )
        )
    return notes


def _least_squares(b: ComplexVector, B: NDArray[np.complex128], box: NDArray[Any]) -> ComplexVector:
    """The least ``||b + B y||`` with ``|y_j| <= box_j`` (scaled problem)."""
    y = np.linalg.lstsq(B, -b, rcond=None)[0]
    if np.all(np.abs(y) <= box):
        return np.asarray(y, dtype=np.complex128)
    from scipy.optimize import minimize

    n = B.shape[1]
    Br = _real(B)

    def f(x: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        e = np.concatenate([b.real, b.imag]) + Br @ x
        return float(e @ e), 2 * Br.T @ e

    limited = np.flatnonzero(np.isfinite(box))
    cons = {
        "type": "ineq",
        "fun": lambda x: box[limited] ** 2 - x[limited] ** 2 - x[n + limited] ** 2,
        "jac": lambda x: _cap_jacobian(x, limited, n),
    }
    start = np.where(np.abs(y) > box, y * box / np.maximum(np.abs(y), 1e-300), y)
    sol = minimize(
        f,
        _pack(start),
        jac=True,
        constraints=[cons],
        method="SLSQP",
        options={"maxiter": 500, "ftol": 1e-14},
    )
    return _clip(_unpack(sol.x), box)


def _cap_jacobian(x: NDArray[np.float64], limited: NDArray[Any], n: int) -> NDArray[np.float64]:
    J = np.zeros((len(limited), x.size))
    J[np.arange(len(limited)), limited] = -2 * x[limited]
    J[np.arange(len(limited)), n + limited] = -2 * x[n + limited]
    return J


def _minmax(
    b: ComplexVector, B: NDArray[np.complex128], box: NDArray[Any], y_ls: ComplexVector
) -> ComplexVector:
    """The least ``max |b + B y|`` with ``|y_j| <= box_j``: the polygon LP, then polished."""
    from scipy.optimize import linprog

    m, n = B.shape
    theta = 2 * np.pi * np.arange(POLYGON) / POLYGON
    c, s = np.cos(theta), np.sin(theta)
    # Re((b_i + B_i y) e^{-i th}) = cos th Re(.) + sin th Im(.) <= t
    rows = []
    rhs = []
    Br, Bi = B.real, B.imag
    for i in range(m):
        # Re(B_i y) = Br x_re - Bi x_im ; Im(B_i y) = Bi x_re + Br x_im
        re = np.concatenate([Br[i], -Bi[i]])
        im = np.concatenate([Bi[i], Br[i]])
        rows.append(np.column_stack([c[:, None] * re + s[:, None] * im, -np.ones(POLYGON)]))
        rhs.append(-(c * b[i].real + s * b[i].imag))
    inner = math.cos(math.pi / POLYGON)
    for j in np.flatnonzero(np.isfinite(box)):
        row = np.zeros((POLYGON, 2 * n + 1))
        row[:, j], row[:, n + j] = c, s
        rows.append(row)
        rhs.append(np.full(POLYGON, box[j] * inner))
    cost = np.zeros(2 * n + 1)
    cost[-1] = 1.0
    lp = linprog(
        cost,
        A_ub=np.vstack(rows),
        b_ub=np.concatenate(rhs),
        bounds=[(None, None)] * (2 * n) + [(0, None)],
        method="highs",
    )
    candidates = [y_ls]
    if lp.status == 0:
        y_lp = _unpack(lp.x[:-1])
        candidates += [y_lp, _polish(b, B, box, y_lp)]
    worst = [float(np.max(np.abs(b + B @ y))) for y in candidates]
    return candidates[int(np.argmin(worst))]


def _polish(
    b: ComplexVector, B: NDArray[np.complex128], box: NDArray[Any], y0: ComplexVector
) -> ComplexVector:
    """Min-max on the exact circles (SLSQP from the LP's answer): minimise ``t`` with
    ``t^2 >= |b_i + B_i y|^2`` and the caps."""
    from scipy.optimize import minimize

    n = B.shape[1]
    Br = _real(B)
    b2 = np.concatenate([b.real, b.imag])
    m = len(b)
    limited = np.flatnonzero(np.isfinite(box))

    def resid(z: NDArray[np.float64]) -> NDArray[np.float64]:
        e = b2 + Br @ z[:-1]
        return e[:m] ** 2 + e[m:] ** 2

    def cons_fun(z: NDArray[np.float64]) -> NDArray[np.float64]:
        out = [z[-1] ** 2 - resid(z)]
        if limited.size:
            x = z[:-1]
            out.append(box[limited] ** 2 - x[limited] ** 2 - x[n + limited] ** 2)
        return np.concatenate(out)

    def cons_jac(z: NDArray[np.float64]) -> NDArray[np.float64]:
        e = b2 + Br @ z[:-1]
        de = 2 * (e[:m, None] * Br[:m] + e[m:, None] * Br[m:])
        J = np.column_stack([-de, 2 * z[-1] * np.ones(m)])
        if limited.size:
            J = np.vstack(
                [J, np.column_stack([_cap_jacobian(z[:-1], limited, n), np.zeros(len(limited))])]
            )
        return J

    x0 = _pack(y0)
    z0 = np.concatenate([x0, [float(np.sqrt(np.max(resid(np.append(x0, 0.0)))))]])
    sol = minimize(
        lambda z: (z[-1], np.eye(len(z))[-1]),
        z0,
        jac=True,
        method="SLSQP",
        constraints=[{"type": "ineq", "fun": cons_fun, "jac": cons_jac}],
        options={"maxiter": 500, "ftol": 1e-15},
    )
    return _clip(_unpack(sol.x[:-1]), box)


def _real(B: NDArray[np.complex128]) -> NDArray[np.float64]:
    """``[[Re B, -Im B], [Im B, Re B]]``: the complex map on ``[Re y, Im y]``."""
    return np.block([[B.real, -B.imag], [B.imag, B.real]])


def _pack(y: ComplexVector) -> NDArray[np.float64]:
    return np.concatenate([y.real, y.imag])


def _unpack(x: NDArray[np.float64]) -> ComplexVector:
    n = len(x) // 2
    return np.asarray(x[:n] + 1j * x[n:], dtype=np.complex128)


def _clip(y: ComplexVector, box: NDArray[Any]) -> ComplexVector:
    """Onto the caps (the solvers meet them to their tolerance; this makes it exact)."""
    mag = np.abs(y)
    over = mag > box
    y = y.copy()
    y[over] *= box[over] / mag[over]
    return y
