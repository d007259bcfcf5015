"""Drilled holes and milled slots: the metal a correction removes, and where its mass sits.

Pure numerics: SI units (m, kg, kg m), no I/O.

A hole removes the unbalance ``rho S`` [kg m], ``S`` the **first moment** of its
volume about the rotor's axis [m^4] (the volume times the distance of its centre
of mass from the axis).  Dividing the mass ``U / R`` by ``rho pi r^2`` gives a
depth that is too shallow: the centre of mass of a radial hole moves inwards as it
deepens, the point cone removes a third of its cylinder, and the curved surface
the drill enters removes nothing above it.  Here ``S`` is exact:

**Radial hole** (the drill's axis along a radius, entering the rotor's cylindrical
surface of radius ``R``; the depth ``d`` is the tip's travel from where it first
touches the surface, on its own axis).  With ``r`` the drill's radius, ``alpha``
half its point angle, ``h = r / tan(alpha)`` the cone's height (0 for a flat
bottom) and ``x_s = R - d + h`` the shoulder's distance from the axis::

    V = pi r^2 (R - x_s) + pi r^2 h / 3 - V_cap
    S = pi r^2 (R^2 - x_s^2) / 2 + (pi r^2 h / 3) (x_s - h / 4) - pi r^4 / 8

The cap is what the flat-topped drill cylinder holds above the curved surface:
``V_cap = pi r^2 R - 2 I`` with
``I = (2R/3) ((R^2 + r^2) E(m) - (R^2 - r^2) K(m))``, ``m = (r/R)^2`` (complete
elliptic integrals), and its first moment ``pi r^4 / 8`` (closed form: the cap's
column at ``y`` reaches from ``sqrt(R^2 - y^2)`` to ``R``).  This holds while the
shoulder lies below the cap, ``d >= h + R - sqrt(R^2 - r^2)``: a radial hole is
drilled to its full diameter (:func:`min_depth`).

**Axial hole** (parallel to the axis at radius ``R``, into a flat face): every
cross-section is a disc centred at ``R``, so ``S = V R`` exactly;
``V = pi r^2 (d - h) + pi r^2 h / 3`` (``d >= h``) or the cone alone,
``pi tan(alpha)^2 d^3 / 3``.

**Milled slot** (a cutter of width ``w`` taking ``t`` off the circumference
at radius ``R``, over an arc ``beta``)::

    S = w (R^3 - (R - t)^3) / 3 * 2 sin(beta / 2),   V = w beta (R^2 - (R - t)^2) / 2

Depths and arcs are solved from ``S`` in closed form (a quadratic; an arcsine).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from stand.errors import ModelError

Direction = Literal["radial", "axial"]


@dataclass(frozen=True)
class Drill:
    """One drill of the table: diameter [m], point angle [deg] (180: flat bottom), the
    deepest hole it may drill [m]."""

    diameter_m: float
    point_angle_deg: float
    max_depth_m: float

    @property
    def cone_m(self) -> float:
        """Height of the point cone [m] (0 for a flat bottom)."""
        half = math.radians(self.point_angle_deg) / 2
        return 0.0 if self.point_angle_deg >= 180.0 else self.diameter_m / 2 / math.tan(half)


def _cap(r: float, R: float) -> tuple[float, float]:
    """Volume [m^3] and first moment [m^4] of what a flat-topped cylinder of radius ``r``
    holds above a cylindrical surface of radius ``R`` (its top touching the surface)."""
    from scipy.special import ellipe, ellipk  # here: scipy.special takes 0.2 s to import

    m = (r / R) ** 2
    inner = 2 * R / 3 * ((R * R + r * r) * ellipe(m) - (R * R - r * r) * ellipk(m))
    return math.pi * r * r * R - 2 * inner, math.pi * r**4 / 8


def cap_height(drill: Drill, R_m: float, direction: Direction) -> float:
    """How far below the tip's first touch the surface lies at the drill's rim [m]."""
    r = drill.diameter_m / 2
    return R_m - math.sqrt(R_m * R_m - r * r) if direction == "radial" else 0.0


def min_depth(drill: Drill, R_m: float, direction: Direction) -> float:
    """The shallowest hole this module computes [m]: radial holes to their full diameter
    (the shoulder below the surface everywhere); axial holes any depth."""
    return drill.cone_m + cap_height(drill, R_m, direction) if direction == "radial" else 0.0


def _check(drill: Drill, R_m: float) -> None:
    if not (drill.diameter_m > 0 and 0 < drill.point_angle_deg <= 180 and R_m > 0):
        raise ModelError("a drill needs a diameter > 0, a point angle in (0, 180] and R > 0")
    if drill.diameter_m >= 2 * R_m:
        raise ModelError(
            f"a drill of {drill.diameter_m * 1e3:g} mm is as wide as the part at radius "
            f"{R_m * 1e3:g} mm"
        )


def hole(depth_m: float, drill: Drill, R_m: float, direction: Direction) -> tuple[float, float]:
    """Volume [m^3] and first moment about the rotor's axis [m^4] of one hole.

    ``depth_m`` is the depth to the tip; ``R_m`` the entry radius (radial: the
    surface the drill enters; axial: the radius of the hole's axis).

    >>> v, s = hole(0.025, Drill(0.020, 180.0, 0.03), 0.09, "axial")
    >>> round(v * 1e9, 3), round(s / v * 1e3, 6)  # mm^3, the centre of mass [mm]
    (7853.982, 90.0)
    """
    _check(drill, R_m)
    r, h = drill.diameter_m / 2, drill.cone_m
    if direction == "axial":
        if depth_m >= h:
            v = math.pi * r * r * (depth_m - h) + math.pi * r * r * h / 3
        else:
            v = math.pi * (r * depth_m / h) ** 2 * depth_m / 3
        return v, v * R_m
    if depth_m < min_depth(drill, R_m, direction) * (1 - 1e-12):
        raise ModelError(
            f"a radial hole of {depth_m * 1e3:.3f} mm with a {drill.diameter_m * 1e3:g} mm "
            "drill does not reach its full diameter"
        )
    if depth_m >= R_m:
        raise ModelError(f"a hole {depth_m * 1e3:g} mm deep passes the axis (R {R_m * 1e3:g} mm)")
    x_s = R_m - depth_m + h
    v_cone = math.pi * r * r * h / 3
    v_cap, s_cap = _cap(r, R_m)
    v = math.pi * r * r * (R_m - x_s) + v_cone - v_cap
    s = math.pi * r * r * (R_m * R_m - x_s * x_s) / 2 + v_cone * (x_s - h / 4) - s_cap
    return v, s


def depth_for(S_m4: float, drill: Drill, R_m: float, direction: Direction) -> float:
    """The depth to the tip [m] whose hole has the first moment ``S_m4`` [m^4] (the
    inverse of :func:`hole`, in closed form).

    >>> d = Drill(0.020, 118.0, 0.025)
    >>> s = hole(0.021, d, 0.09, "radial")[1]
    >>> round(depth_for(s, d, 0.09, "radial") * 1e3, 9)
    21.0
    """
    _check(drill, R_m)
    r, h = drill.diameter_m / 2, drill.cone_m
    if direction == "axial":
        v = S_m4 / R_m
        v_cone = math.pi * r * r * h / 3
        if v >= v_cone:
            return (v - v_cone) / (math.pi * r * r) + h
        return float(np.cbrt(3 * v * h * h / (math.pi * r * r)))
    # S(x_s) = -(pi r^2 / 2) x_s^2 + v_cone x_s + const: the root with x_s > h / 3
    v_cone = math.pi * r * r * h / 3
    _, s_cap = _cap(r, R_m)
    const = math.pi * r * r * R_m * R_m / 2 - v_cone * h / 4 - s_cap
    a = math.pi * r * r / 2
    disc = v_cone * v_cone - 4 * a * (S_m4 - const)
    if disc < 0:
        raise ModelError("no radial hole of this drill removes that much")
    x_s = (v_cone + math.sqrt(disc)) / (2 * a)
    return R_m - x_s + h


@dataclass(frozen=True)
class Slot:
    """A milled slot: its centre angle [deg], arc [deg], width and depth [m] at radius
    ``R`` [m], the mass it removes [kg] and the unbalance it takes off [kg m]."""

    angle_deg: float
    arc_deg: float
    width_m: float
    depth_m: float
    entry_radius_m: float
    mass_kg: float
    moment_kg_m: float


def slot_moment(arc_rad: float, width_m: float, depth_m: float, R_m: float) -> tuple[float, float]:
    """Volume [m^3] and first moment [m^4] of a slot over ``arc_rad`` (at most 2 pi)."""
    if not (0 < depth_m < R_m and width_m > 0):
        raise ModelError("a slot needs 0 < depth < R and a width > 0")
    ring = (R_m**3 - (R_m - depth_m) ** 3) / 3
    v = width_m * arc_rad * (R_m * R_m - (R_m - depth_m) ** 2) / 2
    return v, width_m * ring * 2 * math.sin(arc_rad / 2)


def slot_arc(S_m4: float, width_m: float, depth_m: float, R_m: float) -> float:
    """The arc [rad] whose slot has the first moment ``S_m4`` (at most pi: a longer slot
    removes less)."""
    full = slot_moment(math.pi, width_m, depth_m, R_m)[1]
    if S_m4 >= full:
        return math.pi
    return 2 * math.asin(float(S_m4 / full))
