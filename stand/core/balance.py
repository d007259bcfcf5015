"""Corrections: from unbalances to what the operator does.

Pure numerics: arrays in, arrays out, SI units (kg m, m, rad/s), no I/O.

Tolerances and acceptance live in :mod:`stand.core.tolerance`.

**Corrections.**  Removing ``q_i`` at the angle ``phi_i`` (the seed's angle,
from the reference mark against the direction of rotation), or adding it at
``phi_i + 180 deg``, cancels ``U_i``.  A rotor that takes weights only at N
fixed positions gets the correction split onto the two positions either
side; weights may be rounded to the steps available, and what the rounding
leaves is reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from stand.core.model import StandParameters


@dataclass(frozen=True)
class Weight:
    """One weight (or one removal): mass [kg] at an angle [deg, the seed's sense].

    ``position`` is the index of the hole or blade (0 for the first; shown as
    1..N); ``pieces_kg`` the stock weights stacked to make ``mass_kg`` (empty for a
    continuous mass).
    """

    mass_kg: float
    angle_deg: float
    position: int | None = None
    pieces_kg: tuple[float, ...] = ()


STACK_CELLS = 200_000
"""Beyond this many steps of the weights' common unit the stack is chosen greedily."""


def stack(mass_kg: float, steps_kg: ArrayLike) -> tuple[float, ...]:
    """Stock weights (each size any number of times) whose sum is nearest ``mass_kg``,
    with the fewest pieces among the nearest; largest first.

    An unbounded change-making by dynamic programming on the weights' common unit
    (their greatest common divisor, to the microgram); greedy beyond
    :data:`STACK_CELLS` units.

    >>> [round(w * 1e3) for w in stack(0.046, [1e-3, 2e-3, 5e-3, 10e-3, 20e-3])]
    [20, 20, 5, 1]
    """
    steps = sorted({float(x) for x in np.asarray(steps_kg, dtype=float).ravel() if x > 0})
    if not steps or mass_kg <= 0:
        return ()
    ug = [max(1, round(x * 1e9)) for x in steps]
    unit = ug[0]
    for u in ug[1:]:
        unit = math.gcd(unit, u)
    sizes = [u // unit for u in ug]
    target = mass_kg * 1e9 / unit
    top = math.ceil(target) + max(sizes)
    if top > STACK_CELLS:  # greedy: largest first, then the nearest last piece
        pieces, left = [], mass_kg
        for x in reversed(steps):
            while left >= x:
                pieces.append(x)
                left -= x
        if left > steps[0] / 2:
            pieces.append(steps[0])
        return tuple(pieces)
    count = [0] + [-1] * top  # fewest pieces to make each sum, -1: cannot
    last = [0] * (top + 1)
    for v in range(1, top + 1):
        for k, size in enumerate(sizes):
            if (
                size <= v
                and count[v - size] >= 0
                and (count[v] < 0 or count[v - size] + 1 < count[v])
            ):
                count[v], last[v] = count[v - size] + 1, k
    made = [v for v in range(top + 1) if count[v] >= 0]
    best = min(made, key=lambda v: (abs(v - target), count[v]))
    pieces = []
    while best > 0:
        pieces.append(steps[last[best]])
        best -= sizes[last[best]]
    return tuple(sorted(pieces, reverse=True))


@dataclass(frozen=True)
class Correction:
    """What to do in one plane.

    Attributes
    ----------
    weights : tuple of Weight
        One (free angle) or two (fixed positions) weights; to remove or to add.
    remove : bool
        True: remove at ``angle_deg``; False: add.
    residual_kg_m : complex
        Unbalance left by rounding to positions and steps [kg m] (0 if exact).
    holes : tuple of stand.core.holes.Hole
        Drilled holes, in drilling order (mode drill; then ``weights`` is empty).
    slot : stand.core.drill.Slot or None
        A milled slot (mode mill).
    """

    weights: tuple[Weight, ...]
    remove: bool
    residual_kg_m: complex
    holes: tuple[Any, ...] = ()
    slot: Any = None


def _wrap(deg: float) -> float:
    return float(np.mod(deg, 360.0))


def correction(
    U_kg_m: complex,
    R_m: float,
    *,
    remove: bool = True,
    positions: int = 0,
    position0_deg: float = 0.0,
    steps_kg: ArrayLike = (),
    step_kg: float = 0.0,
) -> Correction:
    """The correction of one plane's unbalance ``U = q R e^{-i phi}``.

    Parameters
    ----------
    U_kg_m
        The plane's unbalance [kg m], the seed's convention.
    R_m
        Correction radius [m].
    remove
        Remove material at ``phi`` (True) or add at ``phi + 180`` (False).
    positions
        0 for any angle, else N equally spaced positions (holes, blades).
    position0_deg
        Angle of position 0 (same sense and zero as ``phi``) [deg].
    steps_kg
        Available stock weights [kg]: each correction mass is made of as
        many of them as come nearest (:func:`stack`); empty for continuous
        masses.
    step_kg
        Or: weights come in multiples of this [kg] (0: continuous).
    """
    q = abs(U_kg_m) / R_m
    phi = _wrap(-math.degrees(np.angle(U_kg_m)))
    at = phi if remove else _wrap(phi + 180.0)
    weights: list[Weight] = []
    if positions <= 0:
        weights.append(Weight(q, at))
    elif positions <= 2:
        # one axis only: the best is the projection onto the position facing the correction;
        # the perpendicular part stays as a residual
        pitch = 360.0 / positions
        best = max(
            range(positions), key=lambda j: math.cos(math.radians(at - position0_deg - j * pitch))
        )
        m = q * math.cos(math.radians(at - position0_deg - best * pitch))
        if m > 0:
            weights.append(Weight(m, _wrap(position0_deg + best * pitch), best))
    else:
        pitch = 360.0 / positions
        rel = _wrap(at - position0_deg)
        k = int(rel // pitch) % positions
        t = math.radians(rel - k * pitch)
        span = math.radians(pitch)
        # m_k e^{i a_k} + m_k1 e^{i a_k1} = q e^{i at}  (angles a_k, a_k + pitch < 180 deg apart)
        m_k = q * math.sin(span - t) / math.sin(span)
        m_k1 = q * math.sin(t) / math.sin(span)
        for j, m in ((k, m_k), ((k + 1) % positions, m_k1)):
            if m > 1e-15 * max(q, 1e-300):
                weights.append(Weight(m, _wrap(position0_deg + j * pitch), j))
    steps = np.sort(np.asarray(steps_kg, dtype=float))
    if steps.size:  # stock weights, stacked in one hole as needed
        stacked = [(stack(w.mass_kg, steps), w) for w in weights]
        weights = [Weight(sum(p), w.angle_deg, w.position, p) for p, w in stacked if p]
    elif step_kg > 0:
        weights = [
            Weight(round(w.mass_kg / step_kg) * step_kg, w.angle_deg, w.position) for w in weights
        ]
        weights = [w for w in weights if w.mass_kg > 0]
    # what the weights do, in the seed's sense (an angle counted against rotation: e^{-i angle})
    sign = 1.0 if remove else -1.0  # removing at phi cancels U; adding at phi+180 too
    done = sum(sign * w.mass_kg * R_m * np.exp(-1j * math.radians(w.angle_deg)) for w in weights)
    return Correction(tuple(weights), remove, complex(U_kg_m - done))


def static_couple(p: StandParameters, U_kg_m: ArrayLike) -> tuple[complex, complex]:
    """The static part ``U1 + U2`` and the couple part ``(U1 - U2) / 2`` [kg m].

    The couple part is a pair, ``+(U1 - U2)/2`` in plane 1 and ``-(U1 - U2)/2``
    in plane 2, ``b + c`` apart: its moment is ``|U1 - U2| (b + c) / 2``
    [kg m^2].  Static plus couple give back ``U1`` and ``U2`` when the static
    part is shared equally between the planes.
    """
    U = np.asarray(U_kg_m, dtype=complex)
    return complex(U[0] + U[1]), complex((U[0] - U[1]) / 2)


def index_split(
    U_0_kg_m: ArrayLike, cov_0: ArrayLike, U_180_kg_m: ArrayLike, cov_180: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The two-run index procedure: the tooling's and the rotor's unbalance apart.

    The rotor is measured on its tooling, then turned 180 deg on it.  The reference
    mark is on the rotor, so the rotor's unbalance ``U_r`` stays where it was and the
    tooling's ``U_t`` turns half a revolution: ``U_0 = U_r + U_t`` and
    ``U_180 = U_r - U_t``, hence ``U_t = (U_0 - U_180) / 2`` and
    ``U_r = (U_0 + U_180) / 2``.  The runs are independent: each half's covariance
    (real 4 x 4, ``Re U1, Im U1, Re U2, Im U2``) is ``(C_0 + C_180) / 4``.

    Returns ``U_t``, its covariance, ``U_r``, its covariance [kg m, kg^2 m^2].

    >>> t, _, r, _ = index_split([3 + 1j, 2j], np.eye(4), [1 + 1j, 0j], np.eye(4))
    >>> t.tolist(), r.tolist()
    ([(1+0j), 1j], [(2+1j), 1j])
    """
    U0, U180 = np.asarray(U_0_kg_m, dtype=complex), np.asarray(U_180_kg_m, dtype=complex)
    cov = (np.asarray(cov_0, dtype=float) + np.asarray(cov_180, dtype=float)) / 4
    return (U0 - U180) / 2, cov, (U0 + U180) / 2, cov.copy()
