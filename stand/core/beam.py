"""The flexible stand: the shaft as beam elements lying in the two elastic supports.

The shaft (:mod:`stand.core.shaft`) is cut into cubic Hermite beam elements
in the measuring plane (Rayleigh beam: Euler-Bernoulli bending with the
sections' rotary inertia, so that a stiff shaft has exactly the rigid
rotor's ``J3``), with nodes at the section ends, the supports, the
correction planes and the point masses.  Each support adds its moving mass
``M_i``, stiffness ``C_i`` and damping ``H_i`` at its node, as in the seed's
model.  At steady speed ``w``, with ``X`` the nodes' complex amplitudes::

    (K - w^2 M + i w H) X = w^2 F U,        A_i = -w^2 X_support_i

(``F`` puts each plane's unbalance force on its node), which is the stand
model's forward with a bending rotor; as the shaft stiffens it tends to the
rigid :func:`stand.core.model.forward` as ``1 / E`` (tested).  The forward is
linear in ``U``: ``A = H(w) U``, and the inverse is ``U = H(w)^-1 A``.

Used wherever a config or scene has a ``[rotor.shaft]`` table
(:meth:`stand.config.schema.RotorTable.beam`).  Pure numerics: arrays in, arrays out.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stand.core.influence import InfluenceMap, solve_influence
from stand.core.inverse import RESONANCE_BAND, Diagnostic, UnbalanceSolution, speed_diagnostics
from stand.core.model import ComplexArray, StandParameters, rad_s_to_rpm
from stand.core.shaft import ELEMENTS, PointMass, Section, beam_element
from stand.errors import ModelError
from stand.i18n.words import said


@dataclass(frozen=True)
class BeamRotor:
    """The shaft's beam model: node positions [m], stiffness and mass matrices (2 dof per
    node: displacement, rotation), and the nodes of the supports and the planes."""

    x_m: NDArray[np.float64]
    K: NDArray[np.float64]
    M: NDArray[np.float64]
    support_nodes: tuple[int, int]
    plane_nodes: tuple[int, int]


def beam_rotor(
    sections: Sequence[Section],
    E_pa: float,
    density_kg_m3: float,
    support_positions_m: tuple[float, float],
    plane_positions_m: tuple[float, float],
    masses: Sequence[PointMass] = (),
    elements: int = ELEMENTS,
    *,
    extra_positions_m: Sequence[float] = (),
) -> BeamRotor:
    """The beam model of a shaft in its supports (see the module docstring);
    ``extra_positions_m``: more places that get a node of their own (correction planes
    beyond the two, :func:`receptance_at`)."""
    bounds, x = [0.0], 0.0
    for s in sections:
        x += s.length_m
        bounds.append(x)
    total = bounds[-1]
    marks = [
        *support_positions_m,
        *plane_positions_m,
        *(p.at_m for p in masses),
        *extra_positions_m,
    ]
    if not all(0.0 <= m <= total for m in marks):
        raise ModelError(f"supports, planes and masses must lie on the shaft (0 to {total} m)")
    cuts = sorted(set(bounds) | set(marks))
    nodes = [0.0]
    for lo, hi in itertools.pairwise(cuts):
        n = max(1, math.ceil(elements * (hi - lo) / total - 1e-9))
        nodes += [lo + (hi - lo) * (k + 1) / n for k in range(n)]
    grid = np.array(nodes)
    dof = 2 * len(grid)
    K, M = np.zeros((dof, dof)), np.zeros((dof, dof))
    for e in range(len(grid) - 1):
        mid = 0.5 * (grid[e] + grid[e + 1])
        j = min(int(np.searchsorted(bounds, mid)) - 1, len(sections) - 1)
        s = sections[max(j, 0)]
        area = math.pi / 4 * (s.diameter_m**2 - s.bore_m**2)
        second = math.pi / 64 * (s.diameter_m**4 - s.bore_m**4)
        mu = density_kg_m3 * area + s.added_kg_m
        k, m = beam_element(grid[e + 1] - grid[e], mu, E_pa * second, density_kg_m3 * second)
        K[2 * e : 2 * e + 4, 2 * e : 2 * e + 4] += k
        M[2 * e : 2 * e + 4, 2 * e : 2 * e + 4] += m

    def node(at: float) -> int:
        return int(np.argmin(np.abs(grid - at)))

    for p in masses:
        i = node(p.at_m)
        M[2 * i, 2 * i] += p.kg
        M[2 * i + 1, 2 * i + 1] += p.J_kg_m2
    return BeamRotor(
        x_m=grid,
        K=K,
        M=M,
        support_nodes=(node(support_positions_m[0]), node(support_positions_m[1])),
        plane_nodes=(node(plane_positions_m[0]), node(plane_positions_m[1])),
    )


def _dynamic(rotor: BeamRotor, p: StandParameters, w: float) -> ComplexArray:
    """The stand's dynamic stiffness ``K - w^2 M + i w H`` with the supports."""
    D: ComplexArray = np.asarray(rotor.K - w * w * rotor.M, dtype=np.complex128)
    for i, (m, c, h) in zip(
        rotor.support_nodes, ((p.M1, p.C1, p.H1), (p.M2, p.C2, p.H2)), strict=True
    ):
        D[2 * i, 2 * i] += c - w * w * m + 1j * w * h
    return D


def nodal_response(
    rotor: BeamRotor, p: StandParameters, omega_rad_s: float, U_nodes_kg_m: ArrayLike
) -> ComplexArray:
    """The shaft's displacement phasors at every node [m] for an unbalance at every node
    [kg m] (the force ``w^2 U`` on each node's lateral dof)."""
    w = float(omega_rad_s)
    U = np.asarray(U_nodes_kg_m, dtype=complex)
    F = np.zeros((2 * len(rotor.x_m), *U.shape[1:]), complex)
    F[0::2] = w * w * U
    try:
        X = np.linalg.solve(_dynamic(rotor, p, w), F)
    except np.linalg.LinAlgError as exc:
        raise ModelError(f"no steady state at {w:g} rad/s (a natural frequency)") from exc
    out: ComplexArray = np.asarray(X[0::2], dtype=np.complex128)
    return out


def plane_loads(rotor: BeamRotor, U_kg_m: ArrayLike) -> ComplexArray:
    """The planes' unbalances [kg m] as an unbalance per node (zero elsewhere)."""
    U = np.asarray(U_kg_m, dtype=complex)
    out = np.zeros((len(rotor.x_m), *U.shape[1:]), complex)
    for j, i in enumerate(rotor.plane_nodes):
        out[i] += U[j]
    return out


def receptance(rotor: BeamRotor, p: StandParameters, omega_rad_s: float) -> ComplexArray:
    """``H`` with ``A = H U``: support accelerations [m/s^2] per unbalance [kg m], 2 x 2."""
    X = nodal_response(rotor, p, omega_rad_s, plane_loads(rotor, np.eye(2)))
    H: ComplexArray = np.asarray(-(omega_rad_s**2) * X[list(rotor.support_nodes), :])
    return H


def node_at(rotor: BeamRotor, at_m: float) -> int:
    """The node at ``at_m`` [m from the left end] (ModelError if none is there: the place
    was not given to :func:`beam_rotor`)."""
    i = int(np.argmin(np.abs(rotor.x_m - at_m)))
    if abs(rotor.x_m[i] - at_m) > 1e-9 * max(1.0, float(rotor.x_m[-1])):
        raise ModelError(f"no node of the shaft at {at_m:g} m")
    return i


def receptance_at(
    rotor: BeamRotor, p: StandParameters, omega_rad_s: float, positions_m: Sequence[float]
) -> ComplexArray:
    """Support accelerations [m/s^2] per unbalance [kg m] at each of ``positions_m`` (the
    correction planes of a balancing across speeds): 2 x N."""
    U = np.zeros((len(rotor.x_m), len(positions_m)), complex)
    for j, at in enumerate(positions_m):
        U[node_at(rotor, at), j] = 1.0
    X = nodal_response(rotor, p, omega_rad_s, U)
    H: ComplexArray = np.asarray(-(omega_rad_s**2) * X[list(rotor.support_nodes), :])
    return H


def lumped_masses(rotor: BeamRotor) -> NDArray[np.float64]:
    """The translational mass each node carries [kg]: the rows of the consistent mass
    matrix's translational block, summed (they add up to the rotor's mass)."""
    out: NDArray[np.float64] = rotor.M[0::2, 0::2].sum(axis=1)
    return out


def distributed_unbalance(
    rotor: BeamRotor, eccentricity_m: ArrayLike, angle_deg: float
) -> ComplexArray:
    """The unbalance per node [kg m] of a mass centre line ``eccentricity_m`` off the axis
    at each node [m], all at one angle ``angle_deg`` (the seed's phi: ``e^{-i phi}``)."""
    e = np.asarray(eccentricity_m, dtype=float)
    out: ComplexArray = lumped_masses(rotor) * e * np.exp(-1j * math.radians(angle_deg))
    return out


def forward_beam(
    rotor: BeamRotor,
    p: StandParameters,
    omega_rad_s: float,
    U_kg_m: ArrayLike,
    U_nodes_kg_m: ArrayLike | None = None,
) -> ComplexArray:
    """Support acceleration phasors [m/s^2] of the flexible stand for the planes'
    unbalances ``U`` and, optionally, an unbalance spread along the shaft (per node)."""
    out: ComplexArray = receptance(rotor, p, omega_rad_s) @ np.asarray(U_kg_m, dtype=complex)
    if U_nodes_kg_m is not None:
        X = nodal_response(rotor, p, omega_rad_s, U_nodes_kg_m)
        out = out - omega_rad_s**2 * X[list(rotor.support_nodes)]
    return out


def natural_frequencies_beam(rotor: BeamRotor, p: StandParameters, count: int = 4) -> Any:
    """The lowest undamped natural frequencies of the flexible stand [rad/s]: the two
    rigid-body modes on the supports, then the bending modes."""
    from scipy.linalg import eigh

    K, M = rotor.K.copy(), rotor.M.copy()
    for i, (m, c) in zip(rotor.support_nodes, ((p.M1, p.C1), (p.M2, p.C2)), strict=True):
        K[2 * i, 2 * i] += c
        M[2 * i, 2 * i] += m
    lam = eigh(K, M, eigvals_only=True, subset_by_index=[0, count - 1])
    return np.sqrt(np.maximum(lam, 0.0))


def solve_beam(
    rotor: BeamRotor,
    p: StandParameters,
    omega_rad_s: float,
    A: Any,
    cov_A: Any = None,
) -> UnbalanceSolution:
    """The unbalances from the support phasors through the flexible stand: ``U = H^-1 A``,
    the covariance propagated as for the rigid model, the speed judged against the flexible
    stand's natural frequencies (:func:`natural_frequencies_beam`)."""

    sol = solve_influence(InfluenceMap(receptance(rotor, p, omega_rad_s)), A, cov_A)
    wn = natural_frequencies_beam(rotor, p, 3)
    notes = speed_diagnostics(p, omega_rad_s, wn[:2])  # the modes on the supports
    if omega_rad_s > wn[2] / RESONANCE_BAND:
        notes.append(
            Diagnostic(
                "near_bending_mode",
                said(
                    "speed {rpm} rpm is within a factor {k} of the rotor's first bending "
                    "mode in the stand, {hz} Hz ({rpm_n} rpm): the answer rests on the shaft's "
                    "description there; balance well below it",
                    rpm=f"{rad_s_to_rpm(omega_rad_s):.0f}",
                    k=f"{RESONANCE_BAND:g}",
                    hz=f"{wn[2] / (2 * math.pi):.3g}",
                    rpm_n=f"{rad_s_to_rpm(wn[2]):.0f}",
                ),
                float(omega_rad_s / wn[2]),
            )
        )
    return replace(sol, diagnostics=notes)
