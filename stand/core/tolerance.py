"""Tolerances and acceptance: what a rotor may carry, and whether it does.

Pure numerics: arrays in, arrays out, SI units (kg m, kg m^2, m, rad/s), no I/O.

**Forms** (``docs/tolerance.md`` quotes each rule with its source):

* ISO 21940-11's grade: ``U_per = G m / Omega`` (:func:`permissible_unbalance`), split
  to the rotor's two bearing planes by the lever rule about the centre of mass, each share
  held within 30 .. 70 % (:func:`bearing_shares`).
* API 610/617/687: ``U_max = 6350 W / N`` g mm per bearing plane, W the journal's static
  load [kg], N the maximum continuous speed [rpm] (:func:`api_permissible`).
* A drawing's limit per correction plane, and ISO 21940-11's separate resultant (static)
  and moment (couple) limits for rotors outside its conditions for a simple split.
* The rotor's shape decides the grade form's allocation (:func:`rotor_shape`): a rotor
  whose centre of mass lies outside its bearing planes (overhung) or whose correction
  planes lie close together (narrow) is judged by resultant and moment
  (:func:`shape_limits`), not by a split clamped to 30 .. 70 %.

**Criteria.**  Every form judges quantities that are linear in the two correction-plane
unbalances: ``|w1 U1 + w2 U2|`` against a limit (:class:`Criterion`).  A plane is
``w = (1, 0)``; a bearing plane the exact static transfer (:func:`transfer`); the
resultant ``(1, 1)``; the moment about the centre of mass ``(x1 - x_cm, x2 - x_cm)``.
The combined error of such a quantity, from per-plane error radii ``e``, is at most
``|w1| e1 + |w2| e2``: it holds the truth whenever each plane's does.

**Acceptance (ISO 21940-14).**  Directly after balancing a criterion passes when
``U + dU <= U_per`` and fails when ``U - dU > U_per``; between, it is undecided (measure
longer).  At a later check by the user it passes when ``U <= U_per + dU``
(:func:`judge`).  A rotor fails when any criterion fails, is undecided when any is and
none fails, and passes when all pass (:func:`overall`).

**Keys (ISO 21940-32).**  A key of mass ``m`` with its centroid at radius ``r`` at the
keyway's angle ``phi`` is an unbalance ``m r e^{-i phi}``; the half-key convention
counts half of it (:func:`key_unbalance`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from stand.core.model import StandParameters
from stand.i18n.words import N_, said

SHARE_MIN, SHARE_MAX = 0.3, 0.7
"""ISO 21940-11's limits on a bearing plane's share of ``U_per``."""

API_G_MM_RPM_PER_KG = 6350.0
"""API's constant: ``U_max [g mm] = 6350 W [kg] / N [rpm]`` (``4 W / N`` oz in, W in lb)."""

AFTER_BALANCING, LATER_CHECK = "after_balancing", "later_check"
"""ISO 21940-14's two moments of acceptance."""

Moment = Literal["after_balancing", "later_check"]
State = Literal["pass", "fail", "undecided"]

NARROW_SHARE = 1.0 / 3.0
"""A rotor is *narrow* when its correction planes lie closer together than this share of
its bearing distance.  ISO 21940-11 names narrow rotors without a figure in the sources
the product quotes: a third is the product's assumption, said so wherever it is used."""

Shape = Literal["between", "overhung", "narrow"]

KEY_SHARE = {"none": 0.0, "half": 0.5, "full": 1.0}
"""The share of a key's mass each convention counts in the part (ISO 21940-32)."""


def permissible_unbalance(mass_kg: float, grade_m_s: float, omega_rad_s: float) -> float:
    """``U_per = G m / Omega`` [kg m] (G in m/s: G 6.3 is 6.3e-3 m/s).

    >>> round(permissible_unbalance(60.0, 6.3e-3, 1500 * 2 * math.pi / 60) * 1e6, 1)  # g mm
    2406.4
    """
    return grade_m_s * mass_kg / omega_rad_s


def api_permissible(journal_kg: float, max_speed_rpm: float) -> float:
    """API's ``U_max = 6350 W / N`` [kg m] for a journal's static load ``W`` [kg] at the
    maximum continuous speed ``N`` [rpm].

    >>> round(api_permissible(226.8, 15000.0) * 1e6, 1)  # g mm: 500 lb at 15 000 rpm
    96.0
    """
    return API_G_MM_RPM_PER_KG * journal_kg / max_speed_rpm * 1e-6


def lever_shares(x_cm_m: float, z_m: ArrayLike) -> tuple[float, float]:
    """The shares of bearing planes ``z = (zA, zB)`` in ``U_per`` by the lever rule about
    the centre of mass at ``x_cm``, each held within 30 .. 70 %."""
    zA, zB = (float(v) for v in np.asarray(z_m, dtype=float))
    share = min(max((zB - x_cm_m) / (zB - zA), SHARE_MIN), SHARE_MAX)
    return share, 1.0 - share


def rotor_shape(x_m: ArrayLike, x_cm_m: float, z_m: ArrayLike) -> Shape:
    """Whether ISO 21940-11's simple split holds: ``overhung`` when the centre of mass
    lies outside the bearing planes ``z`` (a lever share below 0 or above 1), ``narrow``
    when the correction planes ``x`` lie closer than :data:`NARROW_SHARE` of the bearing
    distance, else ``between``.

    >>> rotor_shape([0.2, 0.8], 0.5, [0.0, 1.0]), rotor_shape([1.1, 1.4], 1.25, [0.0, 1.0])
    ('between', 'overhung')
    >>> rotor_shape([0.45, 0.55], 0.5, [0.0, 1.0])
    'narrow'
    """
    x = np.asarray(x_m, dtype=float)
    zA, zB = (float(v) for v in np.asarray(z_m, dtype=float))
    share = (zB - x_cm_m) / (zB - zA)
    if not 0.0 <= share <= 1.0:
        return "overhung"
    return "narrow" if abs(float(x[1] - x[0])) < NARROW_SHARE * (zB - zA) else "between"


def shape_limits(U_per_kg_m: float, z_m: ArrayLike) -> tuple[float, float]:
    """The resultant [kg m] and moment [kg m^2] limits of a rotor outside the simple split:
    the resultant ``U_per`` (the grade's own definition, ``e_per m`` at the centre of mass)
    and the moment about the centre of mass ``U_per l / 2`` for the bearing distance
    ``l`` (the couple that loads each bearing plane as the even split's ``U_per / 2``).
    The quoted sources give no number for either: the product's assumption, said so.

    >>> shape_limits(2.0, [0.0, 1.5])
    (2.0, 1.5)
    """
    zA, zB = (float(v) for v in np.asarray(z_m, dtype=float))
    return U_per_kg_m, U_per_kg_m * (zB - zA) / 2.0


def transfer(x_m: ArrayLike, z_m: ArrayLike) -> np.ndarray:
    """The exact static transfer of unbalances at axial positions ``x`` to the two planes
    ``z = (zA, zB)``: the rows give ``U_A`` and ``U_B`` with the same resultant and the
    same moment (``T @ U``; real, 2 x len(x)).

    >>> transfer([0.25], [0.0, 1.0]).ravel().tolist()
    [0.75, 0.25]
    """
    x = np.asarray(x_m, dtype=float)
    zA, zB = (float(v) for v in np.asarray(z_m, dtype=float))
    span = zB - zA
    return np.array([(zB - x) / span, (x - zA) / span])


def carried_limits(x_m: ArrayLike, z_m: ArrayLike, limits: ArrayLike) -> tuple[float, float]:
    """Correction-plane limits equivalent to bearing-plane ``limits`` whatever the phases:
    the largest ``k`` with ``|T| k s <= s`` (``T`` from :func:`transfer`), times ``s``.

    Conservative: residuals within them keep both bearing planes within theirs at any
    phase; the exact verdict is the bearing planes' own (:class:`Criterion`).
    """
    s = np.asarray(limits, dtype=float)
    load = np.abs(transfer(x_m, z_m)) @ s
    k = float(np.min(s / load))
    return float(k * s[0]), float(k * s[1])


def static_couple_limits(
    x_m: ArrayLike, x_cm_m: float, static: float, couple: float
) -> tuple[float, float]:
    """Equal correction-plane limits [kg m] within which the resultant stays within
    ``static`` [kg m] and the moment about the centre of mass within ``couple`` [kg m^2]
    whatever the phases."""
    arm = float(np.sum(np.abs(np.asarray(x_m, dtype=float) - x_cm_m)))
    k = min(static / 2.0, couple / arm if arm > 0 else math.inf)
    return k, k


@dataclass(frozen=True)
class Criterion:
    """One judged quantity ``|w1 U1 + w2 U2|`` against ``limit``.

    Attributes
    ----------
    name : str
        What it is: ``plane 1``, ``bearing plane A``, ``resultant``, ``moment``.
    weights : tuple of float
        ``w1, w2`` [1 for unbalances; m for the moment].
    limit : float
        The permissible value [kg m; kg m^2 for the moment].
    plane : int or None
        The correction plane (1, 2) it judges alone, if any.
    """

    name: str
    weights: tuple[float, float]
    limit: float
    plane: int | None = None

    def value(self, U_kg_m: ArrayLike) -> float:
        """``|w . U|``."""
        return float(abs(np.dot(self.weights, np.asarray(U_kg_m, dtype=complex))))

    def error(self, radii: ArrayLike) -> float:
        """``|w1| e1 + |w2| e2`` for per-plane error radii ``e`` [kg m]."""
        return float(np.dot(np.abs(self.weights), np.asarray(radii, dtype=float)))


def plane_criteria(limits: ArrayLike) -> tuple[Criterion, ...]:
    """Each correction plane against its own limit [kg m]."""
    u = np.asarray(limits, dtype=float)
    return tuple(
        Criterion(said("plane {plane}", plane=i + 1), (1.0 - i, float(i)), float(u[i]), i + 1)
        for i in range(2)
    )


def bearing_criteria(x_m: ArrayLike, z_m: ArrayLike, limits: ArrayLike) -> tuple[Criterion, ...]:
    """Bearing planes A and B (at ``z``) against their limits [kg m]."""
    T = transfer(x_m, z_m)
    s = np.asarray(limits, dtype=float)
    return tuple(
        Criterion(
            said("bearing plane {name}", name=n), (float(T[i, 0]), float(T[i, 1])), float(s[i])
        )
        for i, n in enumerate("AB")
    )


def static_couple_criteria(
    x_m: ArrayLike, x_cm_m: float, static: float, couple: float
) -> tuple[Criterion, ...]:
    """The resultant ``U1 + U2`` [kg m] and the moment about the centre of mass
    ``sum U_i (x_i - x_cm)`` [kg m^2] against their limits."""
    arm = np.asarray(x_m, dtype=float) - x_cm_m
    return (
        Criterion(N_("resultant"), (1.0, 1.0), float(static)),
        Criterion(N_("moment"), (float(arm[0]), float(arm[1])), float(couple)),
    )


def judge(value: float, error: float, limit: float, moment: Moment) -> State:
    """ISO 21940-14's acceptance of one quantity with its combined error.

    >>> judge(9.0, 0.5, 10.0, "after_balancing"), judge(9.8, 0.5, 10.0, "after_balancing")
    ('pass', 'undecided')
    >>> judge(10.6, 0.5, 10.0, "after_balancing"), judge(10.4, 0.5, 10.0, "later_check")
    ('fail', 'pass')
    """
    if moment == LATER_CHECK:
        return "pass" if value <= limit + error else "fail"
    if value + error <= limit:
        return "pass"
    return "fail" if value - error > limit else "undecided"


def overall(states: ArrayLike) -> State:
    """The rotor's verdict: ``fail`` if any fails, else ``undecided`` if any is, else
    ``pass``."""
    s = set(np.asarray(states, dtype=object).ravel().tolist())
    if "fail" in s:
        return "fail"
    return "undecided" if "undecided" in s else "pass"


def key_mass(width_m: float, height_m: float, length_m: float, density_kg_m3: float) -> float:
    """A rectangular key's mass [kg]."""
    return width_m * height_m * length_m * density_kg_m3


def key_unbalance(mass_kg: float, radius_m: float, angle_deg: float, share: float) -> complex:
    """The unbalance ``share m r e^{-i phi}`` [kg m] a key (or its half) adds at the
    keyway's angle ``phi`` (the seed's sense, as every unbalance here).

    >>> round(abs(key_unbalance(0.2, 0.03, 90.0, 0.5)) * 1e6, 6)  # g mm: m r / 2
    3000.0
    """
    return complex(share * mass_kg * radius_m * np.exp(-1j * math.radians(angle_deg)))


def bearing_shares(p: StandParameters, U_per_kg_m: float) -> tuple[float, float]:
    """``U_per`` split onto supports 1 and 2 by the lever rule, held within 30 .. 70 % [kg m]."""
    s1, s2 = lever_shares(p.a + p.b, (0.0, p.L))
    return s1 * U_per_kg_m, s2 * U_per_kg_m


def plane_tolerances(p: StandParameters, U_per_kg_m: float) -> tuple[float, float]:
    """Permissible residual unbalance in correction planes 1 and 2 [kg m], the supports
    taken as the bearing planes: :func:`carried_limits` of :func:`bearing_shares`.
    Planes at the supports get the bearing shares; a plane outside its support
    (``a < 0``) loads that support by more than itself, so its limit comes out stricter.

    >>> import dataclasses
    >>> at_supports = StandParameters(M1=1, M2=1, C1=1e4, C2=1e4, M3=10, J3=1, a=0.0, b=0.5,
    ...                               c=0.5, d=0.0, R1=0.1, R2=0.1)
    >>> [round(u, 6) for u in plane_tolerances(at_supports, 1.0)]
    [0.5, 0.5]
    """
    x = (p.a, p.a + p.b + p.c)
    return carried_limits(x, (0.0, p.L), bearing_shares(p, U_per_kg_m))
