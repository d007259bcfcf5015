"""The ``[autobalancer]`` table: a ball (or roller) balancer on the rotor.

::

    [autobalancer]
    plane = 1            # the correction plane its race lies in
    balls = 2            # how many balls (2 or more)
    ball_g = 50.0        # each ball's mass [g]
    radius_mm = 60.0     # the radius the balls' centres run on [mm]
    drag_n_s_m = 0.5     # viscous drag on a ball's motion relative to the race [N s/m]
    rolling = 0.0        # rolling resistance on the force pressing a ball on its race (0: none)
    gravity = false      # gravity on the balls (a horizontal rotor)
    start_deg = [0.0, 180.0]   # where the balls start, one angle per ball [deg]

``stand autobalance`` predicts with it (closed forms); the keys of the balls' motion
(``drag_n_s_m``, ``rolling``, ``gravity``, ``start_deg``) are the simulator's.  Every value
is bounded by what a balancer can be; a bad one is one :class:`ConfigError` naming the key.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, Field, FiniteFloat, model_validator

from stand.config.tables import STRICT
from stand.errors import ConfigError

Deg = Annotated[FiniteFloat, Field(ge=-360.0, le=720.0)]


class AutobalancerTable(BaseModel):
    """``[autobalancer]``: the balls, their race, what moves them."""

    model_config = STRICT

    plane: Literal[1, 2]
    balls: Annotated[int, Field(ge=2, le=64)]
    """Two or more: one ball cannot make less than its own unbalance."""
    ball_g: Annotated[FiniteFloat, Field(ge=0.01, le=1e4)]
    """At least 10 mg: a lighter ball makes no balancer."""
    radius_mm: Annotated[FiniteFloat, Field(ge=1.0, le=5e3)]
    drag_n_s_m: Annotated[FiniteFloat, Field(ge=0.0, le=1e6)] = 0.0
    rolling: Annotated[FiniteFloat, Field(ge=0.0, le=1.0)] = 0.0
    gravity: bool = False
    start_deg: Annotated[list[Deg], Field(max_length=64)] | None = None

    @model_validator(mode="after")
    def _one_start_per_ball(self) -> AutobalancerTable:
        if self.start_deg is not None and len(self.start_deg) != self.balls:
            raise ValueError(
                f"start_deg: {len(self.start_deg)} angles for {self.balls} balls, one per ball"
            )
        return self

    @property
    def ball_kg(self) -> float:
        """One ball's mass [kg]."""
        return self.ball_g * 1e-3

    @property
    def radius_m(self) -> float:
        """The balls' running radius [m]."""
        return self.radius_mm * 1e-3

    @property
    def capacity_kg_m(self) -> float:
        """``n m R``: the most unbalance the balls can make [kg m]."""
        return self.balls * self.ball_g * 1e-3 * self.radius_mm * 1e-3


BALLS_SHARE = 0.1
"""The balls may weigh at most this share of the rotor."""
RACE_REACH = 1.5
"""The race may lie at most this many times the plane's correction radius from the axis."""


def check_autobalancer(table: AutobalancerTable | None, p: Any, source: str) -> None:
    """The balancer against the rotor it is on (``p``: the stand's parameters): the balls'
    mass against the rotor's, the race against the plane's correction radius (ConfigError
    naming the key and the figure it was judged against)."""
    if table is None:
        return
    mass = table.balls * table.ball_kg
    if mass > BALLS_SHARE * p.M3:
        raise ConfigError(
            f"{table.balls} balls of {table.ball_g:g} g weigh {mass:.3g} kg, more than "
            f"{100 * BALLS_SHARE:g} % of the rotor's {p.M3:g} kg (M3)",
            source=source, key="autobalancer.ball_g",
        )  # fmt: skip
    R = p.R1 if table.plane == 1 else p.R2
    if table.radius_m > RACE_REACH * R:
        raise ConfigError(
            f"a race of {table.radius_mm:g} mm on a rotor whose plane {table.plane} is "
            f"corrected at {R * 1e3:g} mm: beyond {RACE_REACH:g} times it",
            source=source, key="autobalancer.radius_mm",
        )  # fmt: skip
