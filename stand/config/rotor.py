"""The rotor's tables: its rigid values, or the shaft they follow from, and its planes.

``[rotor]`` holds the stand model's rotor values (M3, J3, a, b, c, d, R1, R2)
or a ``[rotor.shaft]`` table they follow from (:mod:`stand.core.shaft`; the
rotor then bends, :mod:`stand.core.beam`), and optionally ``[[rotor.planes]]``,
the correction planes of a balancing across speeds (:mod:`stand.field.speeds`).
Part of the configuration (:mod:`stand.config.schema`).
"""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, Field, FiniteFloat, model_validator

from stand.config.serials import SerialRule
from stand.config.tables import STRICT, Inertia, Length, Mass, Name
from stand.config.tolerance import KeyTable
from stand.core.beam import beam_rotor
from stand.core.shaft import PointMass, Section

Positive = Annotated[FiniteFloat, Field(gt=0.0, le=1e12)]
Pair = Annotated[list[Length], Field(min_length=2, max_length=2)]


class ShaftSection(BaseModel):
    """One section of ``[rotor.shaft] sections`` [m, kg/m]."""

    model_config = STRICT

    length_m: Annotated[FiniteFloat, Field(gt=0.0, le=1e3)]
    diameter_m: Annotated[FiniteFloat, Field(gt=0.0, le=1e2)]
    bore_m: Annotated[FiniteFloat, Field(ge=0.0, le=1e2)] = 0.0
    added_kg_m: Annotated[FiniteFloat, Field(ge=0.0, le=1e6)] = 0.0
    """Mass without stiffness: flights, windings [kg/m]."""


class ShaftMass(BaseModel):
    """A disc, hub or coupling on the shaft [m from the left end, kg, kg m^2]."""

    model_config = STRICT

    at_m: Length
    kg: Annotated[FiniteFloat, Field(ge=0.0, le=1e6)]
    J_kg_m2: Annotated[FiniteFloat, Field(ge=0.0, le=1e9)] = 0.0


class ShaftTable(BaseModel):
    """``[rotor.shaft]``: the shaft the rotor values follow from (:mod:`stand.core.shaft`)."""

    model_config = STRICT

    E_pa: Positive
    density_kg_m3: Positive
    sections: Annotated[list[ShaftSection], Field(min_length=1, max_length=1000)]
    support_positions_m: Pair
    plane_positions_m: Pair
    masses: list[ShaftMass] = []

    def core_args(self) -> tuple[Any, ...]:
        """The table as :func:`stand.core.shaft.shaft_rotor` and
        :func:`stand.core.beam.beam_rotor` take it: sections, E, density, support and plane
        positions, point masses."""

        return (
            [Section(**x.model_dump()) for x in self.sections],
            self.E_pa,
            self.density_kg_m3,
            (self.support_positions_m[0], self.support_positions_m[1]),
            (self.plane_positions_m[0], self.plane_positions_m[1]),
            [PointMass(**m.model_dump()) for m in self.masses],
        )


SHAFT_AGREE = 0.01
"""Rotor values given beside a ``[rotor.shaft]`` table agree with it within 1 % (lengths:
1 % of the support span), or the config is refused."""


class CorrectionPlane(BaseModel):
    """``[[rotor.planes]]``: a correction plane for balancing across speeds (N planes on a
    bending rotor, :mod:`stand.field.speeds`): where along the shaft, at what radius."""

    model_config = STRICT

    position_m: Annotated[FiniteFloat, Field(ge=0.0)]
    """From the shaft's left end [m], as ``[rotor.shaft]`` measures."""
    radius_m: Length
    """The correction radius [m]."""


class RotorTable(BaseModel):
    """``[rotor]``: mass (kg), inertia (kg m^2), lengths and radii (m); M3, J3 and a, b, c,
    d may instead follow from a ``[rotor.shaft]`` table."""

    model_config = STRICT

    M3: Mass | None = None
    J3: Inertia | None = None
    a: Length | None = None
    b: Length | None = None
    c: Length | None = None
    d: Length | None = None
    R1: Length
    R2: Length
    type: Name | None = None
    """The rotor type's name (optional): stored with each run and influence matrix."""
    serial_rule: SerialRule | None = None
    """How the station makes a serial for a rotor without one (optional):
    ``"AUG-{date}-{n:04}"`` (:mod:`stand.config.serials`)."""
    bending_hz: Annotated[FiniteFloat, Field(gt=0.0, le=1e6)] | None = None
    """The rotor's first free-free bending frequency [Hz] (optional): the rigid model's
    limit is judged against it (:mod:`stand.core.flexible`)."""
    shaft: ShaftTable | None = None
    planes: Annotated[list[CorrectionPlane], Field(max_length=16)] = []
    """The correction planes for balancing across speeds (``stand solve --across-speeds``);
    they need the shaft."""
    keys: Annotated[list[KeyTable], Field(max_length=16)] = []
    """Keys and keyways, and the convention the part is balanced by (ISO 21940-32)."""

    @model_validator(mode="after")
    def _planes_on_the_shaft(self) -> RotorTable:
        if self.planes and self.shaft is None:
            raise ValueError("[[rotor.planes]] needs the shaft ([rotor.shaft]) they lie on")
        if self.planes and self.shaft is not None:
            length = sum(s.length_m for s in self.shaft.sections)
            for k, pl in enumerate(self.planes):
                if pl.position_m > length:
                    raise ValueError(
                        f"planes[{k}] at {pl.position_m:g} m is beyond the shaft's {length:g} m"
                    )
            at = [pl.position_m for pl in self.planes]
            if len(set(at)) != len(at):
                raise ValueError("two [[rotor.planes]] at the same place")
        return self

    def beam(self) -> Any:
        """The shaft's beam model (:class:`stand.core.beam.BeamRotor`), or None without a
        ``[rotor.shaft]`` table (a rigid rotor); the ``[[rotor.planes]]`` get nodes."""
        if self.shaft is None:
            return None

        return beam_rotor(
            *self.shaft.core_args(), extra_positions_m=[pl.position_m for pl in self.planes]
        )
