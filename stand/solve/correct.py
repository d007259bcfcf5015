"""What the operator or the machinist does in each plane: weights, drilled holes or a slot.

From the measured unbalance and the config's ``[correction]`` table
(:mod:`stand.config.correction`) to one :class:`stand.core.balance.Correction` per
plane; the arithmetic is the core's (:mod:`stand.core.balance`,
:mod:`stand.core.holes`).  Used by :func:`stand.solve.pipeline.build_result`, and for the
weights of the N-plane answers (:mod:`stand.field.planes`, :mod:`stand.field.speeds`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from stand.core.balance import Correction, correction
from stand.core.holes import plan_holes, plan_slot

HOLE_GOAL_SHARE = 0.1
"""A split over holes counts as done when it leaves at most this share of the plane's
tolerance (fewer holes are then preferred to a smaller leftover) ..."""
HOLE_GOAL_NO_TOLERANCE = 0.01
"""... or, without a tolerance, this share of the plane's unbalance."""


def plane_correction(
    U_kg_m: complex, R_m: float, c: Any, i: int, permissible_kg_m: float | None
) -> Correction:
    """Plane ``i``'s (0 or 1) correction of ``U_kg_m`` [kg m] at radius ``R_m`` [m] by the
    ``[correction]`` table ``c``; ``permissible_kg_m`` the plane's tolerance, if any."""
    if c.mode == "drill":
        goal = (
            HOLE_GOAL_SHARE * permissible_kg_m
            if permissible_kg_m is not None
            else HOLE_GOAL_NO_TOLERANCE * abs(U_kg_m)
        )
        holes, left = plan_holes(
            U_kg_m,
            c.core_drills(),
            c.core_plane(i, R_m),
            density_kg_m3=c.density_kg_m3,
            goal_kg_m=goal,
            depth_step_m=c.depth_step_mm * 1e-3,
            max_holes=c.max_holes,
        )
        return Correction((), True, left, holes=holes)
    if c.mode == "mill":
        slot, left = plan_slot(
            U_kg_m,
            c.core_plane(i, R_m),
            width_m=c.mill.width_mm * 1e-3,
            depth_m=c.mill.depth_mm * 1e-3,
            max_arc_deg=c.mill.max_arc_deg,
            density_kg_m3=c.density_kg_m3,
        )
        return Correction((), True, left, slot=slot)
    return weights_correction(U_kg_m, R_m, c)


def weights_correction(U_kg_m: complex, R_m: float, c: Any | None) -> Correction:
    """The correction of ``U_kg_m`` [kg m] at ``R_m`` [m] in weights, as the
    ``[correction]`` table ``c`` says (remove or add, positions, stock weights); without a
    table (None), masses to add at any angle."""
    if c is None:
        return correction(U_kg_m, R_m, remove=False)
    return correction(
        U_kg_m,
        R_m,
        remove=c.mode == "remove",
        positions=c.positions,
        position0_deg=c.position0_deg,
        steps_kg=[w * 1e-3 for w in c.weights_g],
        step_kg=c.weight_step_g * 1e-3,
    )


def corrections(
    U_kg_m: Any,
    radius_m: Sequence[float],
    c: Any,
    *,
    skip: Sequence[bool],
    permissible_kg_m: Sequence[float] | None,
) -> tuple[Correction, ...]:
    """Both planes' corrections (``U_kg_m``: both unbalances [kg m]); a plane in ``skip``
    (inside its interval, or within tolerance) gets none, its whole unbalance left."""
    return tuple(
        Correction((), c.mode != "add", complex(U))
        if skip[i]
        else plane_correction(
            complex(U), radius_m[i], c, i, None if permissible_kg_m is None else permissible_kg_m[i]
        )
        for i, U in enumerate(U_kg_m)
    )


def removed_masses(corr: Correction, R_m: float) -> list[tuple[float, float, float]]:
    """What one plane's correction puts on (grams > 0) or takes off (< 0):
    ``(grams, angle_deg, radius_m)`` each, a hole or slot at its centre of mass's radius."""
    if corr.holes:
        return [(-h.mass_kg * 1e3, h.angle_deg, h.centroid_radius_m) for h in corr.holes]
    if corr.slot is not None:
        s = corr.slot
        return [(-s.mass_kg * 1e3, s.angle_deg, s.moment_kg_m / s.mass_kg)]
    sign = -1.0 if corr.remove else 1.0
    return [(sign * w.mass_kg * 1e3, w.angle_deg, R_m) for w in corr.weights]


def weight_entries(corr: Any) -> list[dict[str, Any]]:
    """A plane's weights as JSON entries (g, deg, the position 1-based or None), those of
    mass only: the one form the N-plane answers give them in."""
    return [
        {
            "mass_g": round(w.mass_kg * 1e3, 4),
            "angle_deg": round(w.angle_deg, 2),
            "position": None if w.position is None else w.position + 1,
        }
        for w in corr.weights
        if w.mass_kg > 0
    ]
