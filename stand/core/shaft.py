"""A rotor described by its shaft: rigid-body properties and the first bending frequency.

The shaft is a chain of sections from its left end (length, outer diameter,
optional bore, optional added mass per length: flights, windings, which
add mass but no stiffness) plus point masses (discs, hubs, couplings: mass
and their own transverse inertia).  From it follow the stand model's rotor
values: the mass ``M3``, the inertia ``J3`` about a transverse axis through
the centre of mass, and the distances ``a, b, c, d`` (support 1 -> plane 1
-> centre of mass -> plane 2 -> support 2); and its first free-free bending
frequency ``f_ff`` (Euler-Bernoulli beam elements, cubic Hermite, in the
measuring plane), against which the rigid model's limit is judged
(:mod:`stand.core.flexible`).

A section's own transverse inertia counts its length and its radius
(``m (3 (r_o^2 + r_i^2) + l^2) / 12``); added mass counts its length only
(its radial extent is not known).  Pure numerics: numbers in, numbers out.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from stand.errors import ModelError

ELEMENTS = 60
"""Beam elements over the shaft's length for ``f_ff``: a uniform shaft's comes within
3e-8 of the exact ``4.7300^2 / (2 pi L^2) sqrt(EI / rho A)`` (tested)."""


@dataclass(frozen=True)
class Section:
    """One section of the shaft [m, kg/m]."""

    length_m: float
    diameter_m: float
    bore_m: float = 0.0
    added_kg_m: float = 0.0


@dataclass(frozen=True)
class PointMass:
    """A disc, hub or coupling: where [m from the left end], its mass, its transverse inertia."""

    at_m: float
    kg: float
    J_kg_m2: float = 0.0


@dataclass(frozen=True)
class ShaftRotor:
    """What the shaft gives: rigid-body values [kg, kg m^2, m] and ``f_ff`` [Hz]."""

    M3: float
    J3: float
    x_cm_m: float
    a: float
    b: float
    c: float
    d: float
    bending_hz: float


def _segments(
    sections: Sequence[Section], density: float
) -> list[tuple[float, float, float, float, float]]:
    """Per section: start, length, mass per length, EI/E (second moment), its radii term."""
    out, x = [], 0.0
    for s in sections:
        if not (s.length_m > 0 and s.diameter_m > 0 and 0 <= s.bore_m < s.diameter_m):
            raise ModelError(f"a section needs length > 0 and 0 <= bore < diameter, got {s}")
        area = math.pi / 4 * (s.diameter_m**2 - s.bore_m**2)
        second = math.pi / 64 * (s.diameter_m**4 - s.bore_m**4)
        radii = (s.diameter_m**2 + s.bore_m**2) / 4  # r_o^2 + r_i^2
        out.append((x, s.length_m, density * area + s.added_kg_m, second, radii))
        x += s.length_m
    return out


def rigid_values(
    sections: Sequence[Section], density_kg_m3: float, masses: Sequence[PointMass] = ()
) -> tuple[float, float, float]:
    """Mass [kg], centre of mass [m from the left end], inertia about it [kg m^2]."""
    segs = _segments(sections, density_kg_m3)
    parts = [(mu * ln, x0 + ln / 2) for x0, ln, mu, _, _ in segs] + [(p.kg, p.at_m) for p in masses]
    M = sum(m for m, _ in parts)
    if not M > 0:
        raise ModelError("the shaft and its masses weigh nothing")
    x_cm = sum(m * x for m, x in parts) / M
    J = sum(m * (x - x_cm) ** 2 for m, x in parts)
    for (_, ln, mu, _, radii), s in zip(segs, sections, strict=True):
        shaft_kg = (mu - s.added_kg_m) * ln  # the steel: its radius counts; added mass: not
        J += mu * ln * ln**2 / 12 + shaft_kg * 3 * radii / 12
    J += sum(p.J_kg_m2 for p in masses)
    return M, x_cm, J


def beam_element(
    h: float, mu: float, EI: float, rho_I: float = 0.0
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Stiffness and mass of one cubic Hermite beam element of length ``h`` [m]: bending
    stiffness ``EI`` [N m^2], mass per length ``mu`` [kg/m] (consistent), and the section's
    rotary inertia per length ``rho_I`` [kg m] (Rayleigh; 0: Euler-Bernoulli).  Degrees of
    freedom: displacement and rotation at each end."""
    k = EI / h**3 * np.array(
        [[12, 6 * h, -12, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h],
         [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]]
    )  # fmt: skip
    m = mu * h / 420 * np.array(
        [[156, 22 * h, 54, -13 * h], [22 * h, 4 * h * h, 13 * h, -3 * h * h],
         [54, 13 * h, 156, -22 * h], [-13 * h, -3 * h * h, -22 * h, 4 * h * h]]
    )  # fmt: skip
    if rho_I:
        m = m + rho_I / (30 * h) * np.array(
            [[36, 3 * h, -36, 3 * h], [3 * h, 4 * h * h, -3 * h, -h * h],
             [-36, -3 * h, 36, -3 * h], [3 * h, -h * h, -3 * h, 4 * h * h]]
        )  # fmt: skip
    return k, m


def free_free_bending_hz(
    sections: Sequence[Section],
    E_pa: float,
    density_kg_m3: float,
    masses: Sequence[PointMass] = (),
    elements: int = ELEMENTS,
) -> float:
    """The first free-free bending frequency [Hz]: beam elements, consistent mass, the
    point masses lumped at the nearest node (translation and rotation)."""
    from scipy.linalg import eigh

    segs = _segments(sections, density_kg_m3)
    total = sum(ln for _, ln, _, _, _ in segs)
    nodes = [0.0]
    props = []
    for x0, ln, mu, second, _ in segs:
        n = max(1, math.ceil(elements * ln / total))
        for k in range(n):
            nodes.append(x0 + ln * (k + 1) / n)
            props.append((ln / n, mu, E_pa * second))
    dof = 2 * len(nodes)
    K, Mm = np.zeros((dof, dof)), np.zeros((dof, dof))
    for e, (h, mu, EI) in enumerate(props):
        ke, me = beam_element(h, mu, EI)
        i = 2 * e
        K[i : i + 4, i : i + 4] += ke
        Mm[i : i + 4, i : i + 4] += me
    grid = np.array(nodes)
    for p in masses:
        if not 0 <= p.at_m <= total:
            raise ModelError(f"a point mass at {p.at_m} m lies off the shaft (0 to {total} m)")
        j = int(np.argmin(np.abs(grid - p.at_m)))
        Mm[2 * j, 2 * j] += p.kg
        Mm[2 * j + 1, 2 * j + 1] += p.J_kg_m2
    lam = eigh(K, Mm, eigvals_only=True, subset_by_index=[0, 2])
    return float(math.sqrt(max(lam[2], 0.0)) / (2 * math.pi))  # two rigid modes first


def shaft_rotor(
    sections: Sequence[Section],
    E_pa: float,
    density_kg_m3: float,
    support_positions_m: tuple[float, float],
    plane_positions_m: tuple[float, float],
    masses: Sequence[PointMass] = (),
) -> ShaftRotor:
    """The stand model's rotor values and ``f_ff`` of a shaft lying in its supports."""
    M, x_cm, J = rigid_values(sections, density_kg_m3, masses)
    (s1, s2), (p1, p2) = support_positions_m, plane_positions_m
    return ShaftRotor(
        M3=M,
        J3=J,
        x_cm_m=x_cm,
        a=p1 - s1,
        b=x_cm - p1,
        c=p2 - x_cm,
        d=s2 - p2,
        bending_hz=free_free_bending_hz(sections, E_pa, density_kg_m3, masses),
    )
