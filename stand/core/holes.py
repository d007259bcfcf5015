"""Where the holes go: one plane's correction split over the fewest holes at allowed angles.

Pure numerics: SI units, no I/O.  The metal of one hole is :mod:`stand.core.drill`.

A plane's unbalance ``U = q R e^{-i phi}`` is cancelled by removing metal whose
first moments add up to ``U / rho``: holes at angles ``theta_j`` with moments
``s_j`` [kg m] cancel ``sum_j s_j e^{-i theta_j}``.  One hole at ``phi`` does it when
it is deep enough and ``phi`` is allowed.  Otherwise the correction is split:

* the candidates for ``k`` holes are fans of ``k`` angles ``pitch`` apart, centred
  on ``phi`` (free angles) or, where angles are restricted (sectors between an
  auger's flights, fixed positions), centred every 0.5 deg within 90 deg of ``phi``
  and each angle moved to the nearest allowed one (a fan whose holes then come
  closer than the pitch is dropped);
* for each, the moments are the box-constrained least squares (each hole between
  its shallowest and its deepest) of the leftover ``U - sum``;
* the plan is the fewest holes whose leftover is within ``goal``, then the
  smallest leftover; with no such plan, the smallest leftover of all (0 holes
  included);
* each drill of the table is tried alone (one drill per plane: one tool change);
  the drill with the fewest holes wins, then the smaller leftover, then the table's
  order.

Depths are then rounded to the machine's step and the leftover is that of the
rounded holes.  The pitch is at least ``min_pitch_deg`` and at least the angle
at which two holes of the deepest allowed depth would touch at their shoulders.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from stand.core.drill import (
    Direction,
    Drill,
    Slot,
    depth_for,
    hole,
    min_depth,
    slot_arc,
    slot_moment,
)

CENTRE_STEP_DEG = 0.5
"""Fan centres tried where angles are restricted [deg]."""
GRID_STEP_DEG = 0.25
"""Allowed angles inside sectors are taken on this grid (plus each sector's ends) [deg]."""


@dataclass(frozen=True)
class Hole:
    """One hole to drill.

    Attributes
    ----------
    angle_deg
        From the reference mark, against the direction of rotation [deg].
    depth_m
        Depth to the tip, from where the tip first touches the part [m].
    drill
        The drill.
    entry_radius_m, direction
        Where it enters and which way it goes.
    mass_kg
        The metal it removes [kg].
    moment_kg_m
        The unbalance it takes off (mass times its centre of mass's radius) [kg m].
    """

    angle_deg: float
    depth_m: float
    drill: Drill
    entry_radius_m: float
    direction: Direction
    mass_kg: float
    moment_kg_m: float

    @property
    def centroid_radius_m(self) -> float:
        """Where the removed metal's centre of mass is, from the axis [m]."""
        return self.moment_kg_m / self.mass_kg


@dataclass(frozen=True)
class Plane:
    """Where and how one plane is drilled.

    ``sectors``: allowed ``(from_deg, to_deg)`` arcs counted in the angles' sense (an
    arc may wrap through 0); ``positions``: allowed angles [deg]; both empty: any angle.
    """

    entry_radius_m: float
    direction: Direction = "radial"
    min_pitch_deg: float = 0.0
    sectors: tuple[tuple[float, float], ...] = ()
    positions: tuple[float, ...] = ()

    @property
    def free(self) -> bool:
        return not self.sectors and not self.positions


def _wrap(deg: np.ndarray) -> np.ndarray:
    return np.asarray(np.mod(deg, 360.0), dtype=float)


def _gap(a: float, b: float) -> float:
    """Angular distance [deg], 0..180."""
    d = abs((a - b) % 360.0)
    return min(d, 360.0 - d)


def sector_span(lo: float, hi: float) -> float:
    """The arc ``lo..hi`` covers, counted in the angles' sense [deg], 0..360.

    ``[350, 10]`` wraps through 0 (20 deg); ``[0, 360]`` (or any two ends a nonzero
    multiple of 360 apart) is the whole circle; ``[a, a]`` is no arc.
    """
    span = (hi - lo) % 360.0
    return 360.0 if span == 0.0 and hi != lo else span


def allowed_angles(plane: Plane) -> np.ndarray:
    """The allowed angles on a grid (sectors) or as given (positions) [deg]; empty when
    every angle is allowed."""
    if plane.positions:
        return np.unique(_wrap(np.asarray(plane.positions, dtype=float)))
    out: list[np.ndarray] = []
    for lo, hi in plane.sectors:
        span = sector_span(lo, hi)
        n = int(span // GRID_STEP_DEG)
        out.append(lo + GRID_STEP_DEG * np.arange(n + 1))
        out.append(np.array([lo + span]))
    return np.unique(np.round(_wrap(np.concatenate(out)), 9)) if out else np.array([])


def is_allowed(angle_deg: float, plane: Plane) -> bool:
    """Whether a hole may be drilled at ``angle_deg``."""
    if plane.free:
        return True
    if plane.positions:
        return any(_gap(angle_deg, p) < 1e-9 for p in plane.positions)
    for lo, hi in plane.sectors:
        if (angle_deg - lo) % 360.0 <= sector_span(lo, hi) + 1e-9:
            return True
    return False


def pitch_deg(plane: Plane, drill: Drill) -> float:
    """The least angle between two holes [deg]: the configured pitch, or more where two
    holes of the deepest allowed depth would touch at their shoulders."""
    r = drill.diameter_m / 2
    inner = plane.entry_radius_m
    if plane.direction == "radial":
        inner = plane.entry_radius_m - drill.max_depth_m + drill.cone_m
    touch = 180.0 if r >= inner else math.degrees(2 * math.asin(r / inner))
    return max(plane.min_pitch_deg, touch)


def _box_lsq(target: complex, angles: np.ndarray, lo: float, hi: float) -> tuple[np.ndarray, float]:
    """Moments in ``[lo, hi]`` of holes at ``angles`` [deg] nearest ``target`` (in the
    holes' own sense, ``s e^{i theta}``); returns them and the leftover's size."""
    from scipy.optimize import lsq_linear

    th = np.radians(angles)
    A = np.vstack([np.cos(th), np.sin(th)])
    b = np.array([target.real, target.imag])
    if lo == hi:
        s = np.full(len(angles), lo)
    else:
        s = lsq_linear(A, b, bounds=(lo, hi), method="bvls").x
    return s, float(np.hypot(*(b - A @ s)))


def _fans(phi: float, k: int, pitch: float, plane: Plane, grid: np.ndarray) -> list[np.ndarray]:
    """Candidate angle sets of ``k`` holes [deg]."""
    offsets = (np.arange(k) - (k - 1) / 2) * pitch
    if plane.free:
        return [_wrap(phi + offsets)]
    if grid.size == 0:
        return []
    found: dict[tuple[float, ...], np.ndarray] = {}
    for c in np.arange(-90.0, 90.0 + 1e-9, CENTRE_STEP_DEG):
        want = _wrap(phi + c + offsets)
        gaps = np.abs((want[:, None] - grid[None, :] + 180.0) % 360.0 - 180.0)
        got = grid[np.argmin(gaps, axis=1)]
        if (
            k > 1
            and min(_gap(a, b) for i, a in enumerate(got) for b in got[i + 1 :]) < pitch - 1e-9
        ):
            continue
        found.setdefault(tuple(np.round(np.sort(got), 9)), got)
    return list(found.values())


def _plan_one_drill(
    target: complex, drill: Drill, plane: Plane, rho: float, goal: float, max_holes: int
) -> tuple[np.ndarray, np.ndarray, float]:
    """Angles [deg], moments [kg m] and leftover [kg m] of the best plan with this drill."""
    R, d = plane.entry_radius_m, plane.direction
    lo = rho * hole(min_depth(drill, R, d), drill, R, d)[1] if d == "radial" else 0.0
    hi = rho * hole(drill.max_depth_m, drill, R, d)[1]
    phi = math.degrees(math.atan2(target.imag, target.real))
    pitch, grid = pitch_deg(plane, drill), allowed_angles(plane)
    best = (np.array([]), np.array([]), abs(target))
    for k in range(1, max_holes + 1):
        if k * pitch > 360.0 + 1e-9:
            break
        for angles in _fans(phi, k, pitch, plane, grid):
            s, left = _box_lsq(target, angles, lo, hi)
            if left < best[2] - 1e-15 * max(abs(target), 1e-300):
                best = (angles, s, left)
        if best[2] <= goal:
            break
    return best


def plan_holes(
    U_kg_m: complex,
    drills: Sequence[Drill],
    plane: Plane,
    *,
    density_kg_m3: float,
    goal_kg_m: float,
    depth_step_m: float = 1e-4,
    max_holes: int = 6,
) -> tuple[tuple[Hole, ...], complex]:
    """The holes that remove ``U_kg_m`` (the seed's ``q R e^{-i phi}``) and the unbalance
    they leave [kg m], in drilling order (the largest first).

    Parameters
    ----------
    drills
        The drill table, in order of preference.
    goal_kg_m
        A plan leaving at most this much counts as done: fewer holes are preferred to
        a smaller leftover beyond it.
    depth_step_m
        Depths are rounded to this step (0: not rounded).
    """
    # removing at phi cancels U: a hole's moment s at theta takes off s e^{-i theta}, so in
    # the holes' own sense (s e^{+i theta}) the target is conj(U)
    target = complex(U_kg_m).conjugate()
    ranked = []
    for j, drill in enumerate(drills):
        angles, s, left = _plan_one_drill(target, drill, plane, density_kg_m3, goal_kg_m, max_holes)
        ranked.append((left > goal_kg_m, len(angles), left, j, angles, s))
    if not ranked:
        return (), complex(U_kg_m)
    _, _, _, j, angles, s = min(ranked, key=lambda x: x[:4])
    drill = drills[j]
    holes = [
        _rounded(a, m, drill, plane, density_kg_m3, depth_step_m)
        for a, m in zip(angles, s, strict=True)
    ]
    holes.sort(key=lambda h: (-h.mass_kg, h.angle_deg))
    done = sum(h.moment_kg_m * np.exp(-1j * math.radians(h.angle_deg)) for h in holes)
    return tuple(holes), complex(U_kg_m - done)


def _rounded(
    angle: float, moment: float, drill: Drill, plane: Plane, rho: float, step: float
) -> Hole:
    """One hole of the moment ``moment`` [kg m], its depth rounded to ``step`` [m]."""
    R, d = plane.entry_radius_m, plane.direction
    depth = depth_for(moment / rho, drill, R, d)
    lo, hi = min_depth(drill, R, d), drill.max_depth_m
    if step > 0:
        depth = round(depth / step) * step
        lo, hi = math.ceil(lo / step - 1e-9) * step, math.floor(hi / step + 1e-9) * step
    depth = min(max(depth, lo), hi)
    v, s = hole(depth, drill, R, d)
    return Hole(float(angle % 360.0), depth, drill, R, d, rho * v, rho * s)


def _slot_at(
    target: complex, centre: float, w: float, t: float, R: float, rho: float, max_arc: float
) -> tuple[float, float, complex]:
    """The arc [rad] of a slot centred at ``centre`` [deg] nearest ``target`` (the holes'
    sense), its moment [kg m] and what it leaves."""
    along = abs(target) * math.cos(math.radians(centre) - math.atan2(target.imag, target.real))
    arc = min(slot_arc(max(along, 0.0) / rho, w, t, R), max_arc) if along > 0 else 0.0
    moment = rho * slot_moment(arc, w, t, R)[1] if arc > 0 else 0.0
    return arc, moment, target - moment * complex(math.cos(math.radians(centre)),
                                                  math.sin(math.radians(centre)))  # fmt: skip


def _in_sector(phi: float, arc_deg: float, lo: float, hi: float) -> tuple[float, float]:
    """The centre [deg] nearest ``phi`` of a slot of ``arc_deg`` inside the sector
    ``lo..hi``, and the longest arc there [rad]."""
    span = sector_span(lo, hi)
    half = min(arc_deg, span) / 2
    rel = (phi - lo) % 360.0
    if rel > span:  # outside: to the nearer end
        rel = span if rel - span < 360.0 - rel else 0.0
    rel = min(max(rel, half), span - half)
    return (lo + rel) % 360.0, math.radians(2 * min(rel, span - rel))


def plan_slot(
    U_kg_m: complex,
    plane: Plane,
    *,
    width_m: float,
    depth_m: float,
    max_arc_deg: float,
    density_kg_m3: float,
) -> tuple[Slot | None, complex]:
    """The milled slot that removes ``U_kg_m`` and the unbalance it leaves [kg m].

    The slot is centred on the unbalance's angle where it fits inside an allowed
    sector, else as near as it fits; a slot longer than ``max_arc_deg`` is cut at that
    length and the rest is left.  Positions (``positions_deg``) are not used by a slot.
    """
    target = complex(U_kg_m).conjugate()
    phi = math.degrees(math.atan2(target.imag, target.real)) % 360.0
    R, rho, w, t = plane.entry_radius_m, density_kg_m3, width_m, depth_m
    max_arc = math.radians(max_arc_deg)
    arc0 = _slot_at(target, phi, w, t, R, rho, max_arc)[0]
    places = [(phi, max_arc)]  # (centre [deg], longest arc there [rad])
    if plane.sectors:
        places = [_in_sector(phi, math.degrees(arc0), lo, hi) for lo, hi in plane.sectors]
        places = [(c, min(max_arc, room)) for c, room in places]
    best: tuple[float, float, float, complex] | None = None
    for c, longest in places:
        arc, moment, left = _slot_at(target, c, w, t, R, rho, longest)
        if best is None or abs(left) < abs(best[3]):
            best = (c, arc, moment, left)
    assert best is not None
    c, arc, moment, left = best
    if arc <= 0:
        return None, complex(U_kg_m)
    mass = rho * slot_moment(arc, w, t, R)[0]
    slot = Slot(c, math.degrees(arc), w, t, R, mass, moment)
    return slot, complex(left).conjugate()
