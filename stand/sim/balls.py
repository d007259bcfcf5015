"""A scene's ball balancer (``[effects.autobalancer]``): its balls free on their race,
integrated with the stand (:mod:`stand.core.balls`), and what the run's truth keeps of
them (their places on the rotor over time, the balls' unbalance).

Without a run-up the balls are let go at the record's start, the rotor at speed and the
supports on the orbit the balls held where they start would give (so an undamped stand
carries no free vibration from the start); with a run-up everything starts at rest.  The
balls start at ``start_deg`` (from the reference mark, against the direction of rotation,
as every angle the operator reads), else spread evenly round the race.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from stand.core.autobalance import with_balls
from stand.core.balls import G_M_S2, Balls, integrate_balls
from stand.core.model import StandParameters
from stand.core.transient import Progress, steady_state_initial

TRUTH_HZ = 50.0
"""How often the truth keeps the balls' places [Hz]."""


def balls_of(table: Any) -> Balls:
    """The core's balls from an ``[autobalancer]`` table (SI)."""
    return Balls(plane=table.plane, n=table.balls, mass_kg=table.ball_kg,
                 radius_m=table.radius_m, drag_n_s_m=table.drag_n_s_m,
                 gravity_m_s2=G_M_S2 if table.gravity else 0.0, rolling=table.rolling)  # fmt: skip


def start_places(table: Any) -> np.ndarray:
    """Where the balls start on the rotor [rad, direction of rotation]."""
    if table.start_deg is None:
        even: np.ndarray = np.arange(table.balls) * 2 * math.pi / table.balls
        return even
    given: np.ndarray = -np.radians(np.asarray(table.start_deg, dtype=float))
    return given


def free_balls(table: Any, p: StandParameters, speed: Any, U: np.ndarray, seen: list[Any],
               rtol: float, from_speed: bool, truth: dict[str, object],
               progress: Progress | None = None) -> tuple[list[Any], int]:  # fmt: skip
    """Each support's acceleration at the times its sensor sees [m/s^2] and the
    integrator's evaluations; the balls' places and unbalance into ``truth``."""
    balls = balls_of(table)
    phi0 = start_places(table)
    y0 = None
    if from_speed:
        Ub = balls.mass_kg * balls.radius_m * np.exp(1j * phi0).sum()
        locked = U + np.array([Ub, 0.0]) if balls.plane == 1 else U + np.array([0.0, Ub])
        pb = with_balls(p, balls.plane, balls.n * balls.mass_kg)
        y0 = steady_state_initial(pb, speed.omega0_rad_s, locked, speed.theta0_rad)
    both = np.concatenate(seen)
    grid = np.arange(0.0, float(both.max()) if len(both) else 0.0, 1.0 / TRUTH_HZ)
    t_all, back = np.unique(np.concatenate((np.maximum(both, 0.0), grid)), return_inverse=True)
    run = integrate_balls(p, speed, U, balls, t_all, phi0, y0=y0, rtol=rtol, progress=progress)
    a = run.a_m_s2[back[: len(both)]]
    at_grid = back[len(both) :]
    truth["balls_t_s"] = grid
    truth["balls_phi_rad"] = run.phi_rad[at_grid]
    truth["balls_kg_m"] = run.balls_kg_m(balls)[at_grid]
    n0 = len(seen[0])
    return [a[:n0, 0], a[n0:, 1]], run.nfev
