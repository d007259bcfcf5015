"""``[tolerance]`` in the forms customers write, and ``[[rotor.keys]]`` (ISO 21940-32).

Exactly one form per rotor type (``docs/tolerance.md`` gives each with its source):

* ``grade_mm_s`` + ``max_speed_rpm``: ISO 21940-11's balance quality grade;
* ``per_plane_g_mm = [U1, U2]``: a drawing's limits in the correction planes;
* ``static_g_mm`` + ``couple_g_mm2``: ISO 21940-11's separate resultant and moment limits;
* ``api_journal_kg = [W1, W2]`` + ``max_speed_rpm``: API's ``6350 W / N`` per bearing plane.

``bearing_planes_m = [zA, zB]`` (the rotor's own bearings, from support 1) moves the grade
and API forms from the supports to those planes.  ``acceptance`` chooses ISO 21940-14's
moment: ``after_balancing`` (the stand's own verdict) or ``later_check`` (a rotor balanced
elsewhere, checked here).  What pydantic cannot see alone (the planes against the rotor,
the journals against its mass) :func:`check_tolerance` checks with the parameters.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, Field, FiniteFloat, model_validator

from stand.config.tables import STRICT, Angle, Length, Name
from stand.core.model import StandParameters
from stand.errors import ConfigError

GMm = Annotated[FiniteFloat, Field(gt=0.0, le=1e9)]
"""An unbalance [g mm], > 0, at most 1 kg m."""
GMm2 = Annotated[FiniteFloat, Field(gt=0.0, le=1e12)]
"""A moment unbalance [g mm^2], > 0, at most 1 kg m^2."""
JOURNALS_AGREE = 0.25
"""The journals' static loads must sum to the rotor's mass within this share."""

FORMS = {
    "grade": ("grade_mm_s", "max_speed_rpm"),
    "per_plane": ("per_plane_g_mm",),
    "static_couple": ("static_g_mm", "couple_g_mm2"),
    "api": ("api_journal_kg", "max_speed_rpm"),
}
"""Each form and the keys that make it."""


class ToleranceTable(BaseModel):
    """``[tolerance]``: one form, its source, and the moment of acceptance."""

    model_config = STRICT

    grade_mm_s: Annotated[FiniteFloat, Field(ge=0.01, le=4000.0)] | None = None
    """G [mm/s]: G 0.16 to G 4000 in ISO 21940-11's table (0.01 allowed for finer work)."""
    max_speed_rpm: Annotated[FiniteFloat, Field(ge=1.0, le=1e6)] | None = None
    """The rotor's maximum service (API: maximum continuous) speed [rpm]."""
    per_plane_g_mm: Annotated[list[GMm], Field(min_length=2, max_length=2)] | None = None
    static_g_mm: GMm | None = None
    couple_g_mm2: GMm2 | None = None
    api_journal_kg: (
        Annotated[
            list[Annotated[FiniteFloat, Field(gt=0.0, le=1e6)]], Field(min_length=2, max_length=2)
        ]
        | None
    ) = None
    """Each journal's static load [kg], measured (not half the rotor's mass)."""
    bearing_planes_m: Annotated[list[Length], Field(min_length=2, max_length=2)] | None = None
    """Axial positions of the rotor's bearings, from support 1 [m] (grade and API forms)."""
    acceptance: Literal["after_balancing", "later_check"] = "after_balancing"
    """ISO 21940-14's moment: directly after balancing, or a later check by the user."""
    source: Name | None = None
    """Where the limit comes from, as the certificate names it (e.g. "drawing 4711 C")."""

    @model_validator(mode="after")
    def _one_form(self) -> ToleranceTable:
        given = {k for k in self.model_fields_set if getattr(self, k) is not None}
        forms = [f for f, keys in FORMS.items() if set(keys) <= given]
        if "grade" in forms and "api" in forms:
            raise ValueError("grade_mm_s and api_journal_kg both given: one form per rotor type")
        if len(forms) != 1:
            what = ", ".join(f"({' + '.join(k)})" for k in FORMS.values())
            raise ValueError(
                f"{'no' if not forms else 'more than one'} tolerance form: give exactly one "
                f"of {what}"
            )
        used = set(FORMS[forms[0]]) | {"bearing_planes_m", "acceptance", "source"}
        stray = sorted((given - used) & {k for keys in FORMS.values() for k in keys})
        if stray:
            raise ValueError(f"{stray[0]} does not belong to the {forms[0]} form: one form only")
        if self.bearing_planes_m is not None and forms[0] not in ("grade", "api"):
            raise ValueError("bearing_planes_m belongs to the grade and API forms only")
        return self

    @property
    def form(self) -> str:
        """``grade``, ``per_plane``, ``static_couple`` or ``api``."""
        if self.api_journal_kg is not None:
            return "api"
        return next(f for f, ks in FORMS.items() if all(getattr(self, k) is not None for k in ks))


class KeyTable(BaseModel):
    """``[[rotor.keys]]``: a key (or its empty keyway) on the rotor, and the convention the
    part is balanced by (ISO 21940-32)."""

    model_config = STRICT

    plane: Literal[1, 2] | None = None
    """The correction plane the key lies in; or give ``position_m``."""
    position_m: Length | None = None
    """The key's axial centre, from support 1 [m]."""
    angle_deg: Angle
    """The keyway's angle from the reference mark, against the direction of rotation."""
    width_mm: Annotated[FiniteFloat, Field(gt=0.0, le=1000.0)]
    height_mm: Annotated[FiniteFloat, Field(gt=0.0, le=1000.0)]
    length_mm: Annotated[FiniteFloat, Field(gt=0.0, le=10000.0)]
    radius_mm: Annotated[FiniteFloat, Field(ge=0.0, le=5000.0)]
    """The key's centroid's distance from the axis [mm]."""
    density_kg_m3: Annotated[FiniteFloat, Field(ge=100.0, le=25000.0)] = 7850.0
    convention: Literal["half", "full", "none"] = "half"
    """How the part is balanced: with a half-key (ISO 21940-32's rule), a full key, none."""
    fitted: Literal["none", "half", "full"] = "none"
    """What is in the keyway on the stand; the difference is counted by computation."""

    @model_validator(mode="after")
    def _one_place(self) -> KeyTable:
        if (self.plane is None) == (self.position_m is None):
            raise ValueError("give the key's plane or its position_m (one of them)")
        return self

    @property
    def mass_kg(self) -> float:
        """The whole key's mass [kg]."""
        return self.width_mm * self.height_mm * self.length_mm * 1e-9 * self.density_kg_m3


REACH_SHARE = 0.25
"""The rotor reaches a quarter of the supports' span beyond its outermost support or
correction plane (journal and shaft ends): bearing planes and keys lie within it."""
KEYS_SHARE = 0.1
"""All keys together weigh at most a tenth of the rotor."""


def rotor_reach(p: StandParameters) -> tuple[float, float]:
    """The axial extent a bearing plane or a key may lie in [m from support 1]: from the
    outermost support or correction plane, :data:`REACH_SHARE` of the span further."""
    lo, hi = min(0.0, p.a), max(p.L, p.a + p.b + p.c)
    return lo - REACH_SHARE * p.L, hi + REACH_SHARE * p.L


def _outside(value_m: float, p: StandParameters) -> str | None:
    lo, hi = rotor_reach(p)
    if lo <= value_m <= hi:
        return None
    return f"{value_m:g} m lies outside the rotor ({lo:.3g} to {hi:.3g} m from support 1)"


def check_tolerance(t: ToleranceTable | None, p: StandParameters, source: str) -> None:
    """The table against the rotor: bearing planes apart and on the rotor, journals that
    carry the rotor's mass (ConfigError naming the key and the figure)."""
    if t is None:
        return
    if t.bearing_planes_m is not None:
        zA, zB = t.bearing_planes_m
        if zB - zA < 1e-3:
            raise ConfigError(
                f"[{zA:g}, {zB:g}] m: bearing A must lie at least 1 mm before bearing B",
                source=source, key="tolerance.bearing_planes_m",
            )  # fmt: skip
        for k, z in enumerate((zA, zB)):
            if (why := _outside(z, p)) is not None:
                raise ConfigError(f"bearing {'AB'[k]} at {why}", source=source,
                                  key="tolerance.bearing_planes_m")  # fmt: skip
    if t.api_journal_kg is not None:
        W = sum(t.api_journal_kg)
        if abs(W - p.M3) > JOURNALS_AGREE * p.M3:
            raise ConfigError(
                f"{W:g} kg on the journals, the rotor's M3 is {p.M3:g} kg: static loads sum to "
                f"the rotor's weight (within {JOURNALS_AGREE:.0%})",
                source=source, key="tolerance.api_journal_kg",
            )  # fmt: skip


def check_mass_on_rotor(
    mass_kg: float, radius_m: float, p: StandParameters, source: str, key: str
) -> None:
    """A test or trial mass fixed on the rotor: within its largest correction radius and no
    heavier than a tenth of it (ConfigError naming ``key``)."""
    radius_mm = 1e3 * max(p.R1, p.R2)
    if radius_m * 1e3 > radius_mm * (1 + 1e-9):
        raise ConfigError(
            f"{radius_m * 1e3:g} mm is beyond the rotor's largest correction radius "
            f"({radius_mm:g} mm)", source=source, key=key,
        )  # fmt: skip
    if mass_kg > KEYS_SHARE * p.M3:
        raise ConfigError(
            f"{mass_kg * 1e3:g} g on a rotor of {p.M3:g} kg: more than a tenth of it",
            source=source, key=key,
        )  # fmt: skip


def check_keys(keys: list[KeyTable], p: StandParameters, source: str) -> None:
    """Each key on the rotor: on its length, within its largest correction radius, and all
    keys together no heavier than a tenth of it (ConfigError naming ``rotor.keys[k]``)."""
    radius_mm = 1e3 * max(p.R1, p.R2)
    total = 0.0
    for k, key in enumerate(keys):
        where = f"rotor.keys[{k}]"
        if key.position_m is not None and (why := _outside(key.position_m, p)) is not None:
            raise ConfigError(f"position_m {why}", source=source, key=f"{where}.position_m")
        if key.radius_mm > radius_mm:
            raise ConfigError(
                f"radius_mm {key.radius_mm:g} mm is beyond the rotor's largest correction "
                f"radius ({radius_mm:g} mm): a key lies in the rotor",
                source=source, key=f"{where}.radius_mm",
            )  # fmt: skip
        total += key.mass_kg
        if total > KEYS_SHARE * p.M3:
            raise ConfigError(
                f"keys of {total:.3g} kg together (up to this one) on a rotor of {p.M3:g} kg: "
                "more than a tenth of it (check width_mm, height_mm, length_mm, density_kg_m3)",
                source=source, key=where,
            )  # fmt: skip
