"""The ``[correction]`` table: how a rotor is corrected (weights, drilled holes, a milled slot).

::

    [correction]
    mode = "remove" | "add" | "drill" | "mill"
    positions, position0_deg, weights_g, weight_step_g      (remove and add)
    density_kg_m3 = 7850.0, depth_step_mm = 0.1, max_holes = 6   (drill and mill)
    [[correction.drills]]  diameter_mm, point_angle_deg = 118, max_depth_mm
    [correction.mill]      width_mm, depth_mm, max_arc_deg = 120
    [correction.plane1]    entry_radius_mm (default R1), direction = "radial" | "axial",
                           min_pitch_deg = 0, sectors = [[from_deg, to_deg], ...] or
                           positions_deg = [...]
    [correction.plane2]    the same for plane 2

Everything here is checked against the rotor (:func:`check_correction`): a bad value,
or a key the chosen mode does not use, is one :class:`ConfigError` naming the key.
Every size and value is bounded by what a stand can carry (``docs/configuration.md``).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, Field, FiniteFloat, NonNegativeFloat, NonNegativeInt, PositiveFloat

from stand.config.tables import STRICT
from stand.core.drill import Direction, Drill, min_depth
from stand.core.holes import Plane, sector_span
from stand.errors import ConfigError

Mm = Annotated[FiniteFloat, Field(gt=0.0, le=1e4)]
"""A length in mm, > 0 (at most 10 m)."""
Deg = Annotated[FiniteFloat, Field(ge=-360.0, le=720.0)]
"""An angle in degrees, from the reference mark against the direction of rotation."""


class DrillTable(BaseModel):
    """``[[correction.drills]]``: one drill of the table [mm, deg]."""

    model_config = STRICT

    diameter_mm: Mm
    point_angle_deg: Annotated[FiniteFloat, Field(gt=0.0, le=180.0)] = 118.0
    """The drill's point angle (118 for a standard twist drill; 180: flat bottom)."""
    max_depth_mm: Mm
    """The deepest hole this drill may make, to its tip."""


class MillTable(BaseModel):
    """``[correction.mill]``: the slot a cutter takes off the circumference [mm, deg]."""

    model_config = STRICT

    width_mm: Mm
    depth_mm: Mm
    max_arc_deg: Annotated[FiniteFloat, Field(gt=0.0, le=180.0)] = 120.0


class PlaneCorrectionTable(BaseModel):
    """``[correction.planeN]``: where one plane is drilled or milled."""

    model_config = STRICT

    entry_radius_mm: Mm | None = None
    """Radius of the surface the drill enters (radial) or of the hole's axis (axial);
    default: the plane's correction radius R."""
    direction: Literal["radial", "axial"] = "radial"
    min_pitch_deg: Annotated[FiniteFloat, Field(ge=0.0, le=180.0)] = 0.0
    """The least angle between two holes (more where deep holes would touch)."""
    sectors: (
        Annotated[
            list[Annotated[list[Deg], Field(min_length=2, max_length=2)]], Field(max_length=36)
        ]
        | None
    ) = None
    """Arcs holes may go in, ``[from_deg, to_deg]`` in the angles' sense (e.g. between an
    auger's flights)."""
    positions_deg: Annotated[list[Deg], Field(max_length=360)] | None = None
    """Or: the only angles holes may go at."""


class CorrectionTable(BaseModel):
    """``[correction]``: how the rotor is corrected."""

    model_config = STRICT

    mode: Literal["remove", "add", "drill", "mill"] = "remove"
    """remove / add: a mass at the correction radius; drill: holes of the drill table;
    mill: a slot along the circumference."""
    positions: Annotated[NonNegativeInt, Field(le=360)] = 0
    """0: any angle; N: only at N equally spaced positions (holes, blades)."""
    position0_deg: Deg = 0.0
    """Angle of position 0 from the reference mark, in the sense of phi [deg]."""
    weights_g: Annotated[list[Annotated[PositiveFloat, Field(le=1e6)]], Field(max_length=200)] = []
    """Available weights [g] (each correction is rounded to the nearest) ..."""
    weight_step_g: Annotated[NonNegativeFloat, Field(le=1e6)] = 0.0
    """... or weights in multiples of this [g]; 0 and [] mean any mass."""
    density_kg_m3: Annotated[FiniteFloat, Field(ge=100.0, le=23000.0)] = 7850.0
    """The rotor's material where it is drilled or milled (steel: 7850; from foam and
    wood, 100, to osmium, 23000)."""
    depth_step_mm: Annotated[FiniteFloat, Field(ge=0.0, le=10.0)] = 0.1
    """Depths are rounded to this step (0: not rounded)."""
    max_holes: Annotated[int, Field(ge=1, le=24)] = 6
    """The most holes one plane's correction is split over."""
    drills: Annotated[list[DrillTable], Field(max_length=50)] = []
    mill: MillTable | None = None
    plane1: PlaneCorrectionTable = PlaneCorrectionTable()
    plane2: PlaneCorrectionTable = PlaneCorrectionTable()

    def plane(self, i: int) -> PlaneCorrectionTable:
        """Plane ``i`` (0 or 1)."""
        return self.plane1 if i == 0 else self.plane2

    def core_drills(self) -> list[Any]:
        """The drill table as :class:`stand.core.drill.Drill` (SI units)."""

        return [
            Drill(d.diameter_mm * 1e-3, d.point_angle_deg, d.max_depth_mm * 1e-3)
            for d in self.drills
        ]

    def core_plane(self, i: int, R_m: float) -> Any:
        """Plane ``i`` (0 or 1) as :class:`stand.core.holes.Plane`, ``R_m`` the plane's
        correction radius (the entry radius unless given) [m]."""

        p = self.plane(i)
        return Plane(
            entry_radius_m=R_m if p.entry_radius_mm is None else p.entry_radius_mm * 1e-3,
            direction=p.direction,
            min_pitch_deg=p.min_pitch_deg,
            sectors=tuple((lo, hi) for lo, hi in p.sectors or ()),
            positions=tuple(p.positions_deg or ()),
        )


_WEIGHT_KEYS = frozenset({"positions", "position0_deg", "weights_g", "weight_step_g"})
_USES = {
    "remove": _WEIGHT_KEYS,
    "add": _WEIGHT_KEYS,
    "drill": frozenset(
        {"density_kg_m3", "depth_step_mm", "max_holes", "drills", "plane1", "plane2"}
    ),
    "mill": frozenset({"density_kg_m3", "mill", "plane1", "plane2"}),
}
"""The keys of ``[correction]`` each mode uses (``mode`` itself aside)."""
_PLANE_USES = {
    "drill": frozenset(
        {"entry_radius_mm", "direction", "min_pitch_deg", "sectors", "positions_deg"}
    ),
    "mill": frozenset({"entry_radius_mm", "direction", "sectors"}),
}
"""The keys of ``[correction.planeN]`` drilling and milling use."""
ENTRY_RADIUS_FACTOR = 10.0
"""An entry radius is at most this many times the plane's correction radius: further
out, the hole is not in the part the model's radius describes."""


def _fail(msg: str, source: str, key: str) -> ConfigError:
    return ConfigError(msg, source=source, key=f"correction.{key}")


def _changed(table: BaseModel, keys: frozenset[str]) -> list[str]:
    """The keys of ``table`` outside ``keys`` given a value other than their default (a
    run file's stored config writes every default out; those mean nothing)."""
    fields = type(table).model_fields
    return sorted(
        k for k in table.model_fields_set - keys if getattr(table, k) != fields[k].get_default()
    )


def _check_keys(c: CorrectionTable, source: str) -> None:
    """Refuse a key the mode does not use (it would be silently ignored)."""
    for key in _changed(c, _USES[c.mode] | {"mode", "plane1", "plane2"}):
        modes = " / ".join(m for m, keys in _USES.items() if key in keys)
        raise _fail(f'does not apply to mode = "{c.mode}" (it is for {modes})', source, key)
    for i in (0, 1):
        name = f"plane{i + 1}"
        for key in _changed(c.plane(i), _PLANE_USES.get(c.mode, frozenset())):
            raise _fail(f'does not apply to mode = "{c.mode}"', source, f"{name}.{key}")


def check_correction(c: CorrectionTable, rotor: Any, source: str) -> None:
    """Refuse, naming the key, what no machinist could carry out.

    A key the mode does not use, a drill mode without drills (a mill mode without
    ``[correction.mill]``), a drill deeper than the part (a radial hole past the axis)
    or as wide as it, a slot wider than the part, an entry radius far from the
    plane's, sectors that leave no angle, a plane with both sectors and positions.
    """
    if c.mode == "drill" and not c.drills:
        raise _fail('mode = "drill" needs at least one [[correction.drills]]', source, "drills")
    if c.mode == "mill" and c.mill is None:
        raise _fail('mode = "mill" needs a [correction.mill] table', source, "mill")
    _check_keys(c, source)
    if c.mode not in ("drill", "mill"):
        return
    drills = c.core_drills()
    for i, R_m in enumerate((rotor.R1, rotor.R2)):
        _check_plane(c, drills, i, R_m * 1e3, source)


def _check_plane(c: CorrectionTable, drills: list[Any], i: int, R_mm: float, source: str) -> None:
    p, name = c.plane(i), f"plane{i + 1}"
    entry = p.entry_radius_mm or R_mm
    if entry > ENTRY_RADIUS_FACTOR * R_mm:
        raise _fail(
            f"{entry:g} mm is more than {ENTRY_RADIUS_FACTOR:g} times the plane's correction "
            f"radius ({R_mm:g} mm)",
            source,
            f"{name}.entry_radius_mm",
        )
    if p.sectors is not None and p.positions_deg is not None:
        raise _fail("give sectors or positions_deg, not both", source, f"{name}.sectors")
    if p.sectors is not None and not any(sector_span(lo, hi) > 0 for lo, hi in p.sectors):
        raise _fail(
            f"the sectors {p.sectors} leave no angle to drill at", source, f"{name}.sectors"
        )
    if p.positions_deg is not None and not p.positions_deg:
        raise _fail("the list leaves no angle to drill at", source, f"{name}.positions_deg")
    if c.mode == "mill":
        _check_slot(c, i, entry, source)
        return
    for j, (d, drill) in enumerate(zip(c.drills, drills, strict=True)):
        _check_drill(d, drill, i, entry, p.direction, source, j)


def _check_slot(c: CorrectionTable, i: int, entry: float, source: str) -> None:
    assert c.mill is not None
    if c.plane(i).direction != "radial":
        raise _fail("a slot is milled radially", source, f"plane{i + 1}.direction")
    if c.mill.depth_mm >= entry:
        raise _fail(
            f"a slot {c.mill.depth_mm:g} mm deep is deeper than the part (radius "
            f"{entry:g} mm in plane {i + 1})",
            source,
            "mill.depth_mm",
        )
    if c.mill.width_mm > 2 * entry:
        raise _fail(
            f"a slot {c.mill.width_mm:g} mm wide is wider than the part's diameter "
            f"({2 * entry:g} mm in plane {i + 1}): it no longer acts in one plane",
            source,
            "mill.width_mm",
        )


def _check_drill(
    d: DrillTable, drill: Any, i: int, entry: float, direction: Direction, source: str, j: int
) -> None:
    if d.diameter_mm >= 2 * entry:
        raise _fail(
            f"a {d.diameter_mm:g} mm drill is wider than the part (radius {entry:g} mm "
            f"in plane {i + 1})",
            source,
            f"drills.{j}.diameter_mm",
        )
    if direction == "radial" and d.max_depth_mm >= entry:
        raise _fail(
            f"{d.max_depth_mm:g} mm is deeper than the part: a radial hole would pass the "
            f"axis (radius {entry:g} mm in plane {i + 1})",
            source,
            f"drills.{j}.max_depth_mm",
        )
    least = min_depth(drill, entry * 1e-3, direction) * 1e3
    if d.max_depth_mm < least:
        raise _fail(
            f"{d.max_depth_mm:g} mm does not reach the drill's full diameter: its point and "
            f"the curved surface need {least:.2f} mm (plane {i + 1})",
            source,
            f"drills.{j}.max_depth_mm",
        )
