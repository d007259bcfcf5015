"""The ``[rocker]`` table: a hand grinder on a rocker with a ball autobalancer on its disc,
in the seeds' symbols (``stand autobalance --rocker FILE.toml``).

::

    [rocker]
    J_housing_kg_m2 = 0.012     # J_O^(h): housing and rocker about the hinge O
    J_disc_kg_m2 = 0.0004       # J_K: the disc about its centre K
    disc_kg = 0.25              # m_d
    arm_m = 0.18                # l = |OK|
    hinge_c_n_m = 2000.0        # c, the hinge's stiffness reduced to the arm
    hinge_h_n_s_m = 5.0         # h, its viscosity reduced to the arm
    unbalance_kg_m = 2e-5       # m_0 R_0, the largest unbalance the disc may have
    unbalance_radius_m = 0.05   # R_0
    balls = 2                   # n
    ball_kg = 0.004             # m_i, each ball
    race_radius_m = 0.03        # R_i, the race
    ball_drag_n_s_m = 0.05      # h_i, drag on a ball's motion relative to the disc

    [rocker.cutting]            # optional: pressing the disc on the work
    moment_n_m = 2.0            # M_p, the pressing moment
    phi0_rad = 0.01             # phi_0, the rocker's angle at first contact
    c_n_n_m = 5e4               # c_n, the contact stiffness
    f_n = 0.3                   # cutting friction coefficient
    gamma_rad = 1.4             # gamma, contact angle (theta = gamma + phi_0)
    disc_radius_m = 0.0625      # R, the disc's radius

Every value is bounded by what a grinder can be; a bad one is one ConfigError naming the
key (``rocker.arm_m``).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

from pydantic import BaseModel, Field, FiniteFloat, model_validator

from stand.config.schema import read_toml, validate
from stand.config.tables import STRICT
from stand.errors import ConfigError

Inertia = Annotated[FiniteFloat, Field(ge=0.0, le=1e3)]
Positive = Annotated[FiniteFloat, Field(gt=0.0, le=1e6)]
Length = Annotated[FiniteFloat, Field(ge=1e-4, le=2.0)]
"""[m]: 0.1 mm to 2 m, a hand grinder's rocker."""


class CuttingTable(BaseModel):
    """``[rocker.cutting]``: the disc pressed on the work."""

    model_config = STRICT

    moment_n_m: Annotated[FiniteFloat, Field(ge=0.0, le=1e4)]
    phi0_rad: Annotated[FiniteFloat, Field(ge=-1.0, le=1.0)]
    c_n_n_m: Annotated[FiniteFloat, Field(ge=0.0, le=1e10)]
    f_n: Annotated[FiniteFloat, Field(ge=0.0, le=2.0)]
    gamma_rad: Annotated[FiniteFloat, Field(ge=0.0, le=math.pi)]
    disc_radius_m: Length


class RockerTable(BaseModel):
    """``[rocker]``: the rocker, its hinge, the disc, its unbalance and its balls."""

    model_config = STRICT

    J_housing_kg_m2: Inertia
    J_disc_kg_m2: Inertia
    disc_kg: Annotated[FiniteFloat, Field(ge=0.0, le=1e4)]
    arm_m: Length
    hinge_c_n_m: Annotated[FiniteFloat, Field(ge=1e-3, le=1e6)]
    """At least 1e-3 N m/rad: a hinge with no stiffness holds no rocker."""
    hinge_h_n_s_m: Annotated[FiniteFloat, Field(ge=0.0, le=1e6)]
    unbalance_kg_m: Annotated[FiniteFloat, Field(ge=0.0, le=10.0)]
    unbalance_radius_m: Length
    balls: Annotated[int, Field(ge=2, le=64)]
    """Two or more: one ball cannot make less than its own unbalance."""
    ball_kg: Annotated[FiniteFloat, Field(gt=0.0, le=100.0)]
    race_radius_m: Length
    ball_drag_n_s_m: Annotated[FiniteFloat, Field(ge=0.0, le=1e6)] = 0.0
    cutting: CuttingTable | None = None

    @model_validator(mode="after")
    def _on_the_disc(self) -> RockerTable:
        c = self.cutting
        if c is not None and self.race_radius_m > c.disc_radius_m:
            raise ValueError(f"race_radius_m {self.race_radius_m:g} m lies outside the disc "
                             f"(cutting.disc_radius_m {c.disc_radius_m:g} m)")  # fmt: skip
        if self.balls * self.ball_kg > self.disc_kg > 0:
            raise ValueError(f"{self.balls} balls of {self.ball_kg:g} kg weigh more than the "
                             f"disc ({self.disc_kg:g} kg, disc_kg)")  # fmt: skip
        return self

    @property
    def capacity_kg_m(self) -> float:
        """``n m R``: the most unbalance the balls can make [kg m]."""
        return self.balls * self.ball_kg * self.race_radius_m


def load_rocker(path: str | Path) -> RockerTable:
    """The ``[rocker]`` table of a TOML file (:class:`ConfigError` naming what and where)."""
    _, data = read_toml(path)
    if "rocker" not in data or not isinstance(data["rocker"], dict):
        raise ConfigError("no [rocker] table", source=str(path))
    extra = sorted(set(data) - {"rocker"})
    if extra:
        raise ConfigError(f"unknown table(s) {', '.join(extra)}: a rocker file has [rocker] "
                          "and [rocker.cutting]", source=str(path))  # fmt: skip
    return validate(RockerTable, data["rocker"], str(path), prefix="rocker.")
