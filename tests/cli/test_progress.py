"""The progress line of long work (``stand.cli.panel.ProgressLine``) and the integrators
that feed it.

The line must stay silent for a short job, never come closer than its interval, and say
how far the work has come; the integrators must tell it the simulated time, increasing
and never past the end.  The clock is a fake one: no test here waits or times anything.
"""

from __future__ import annotations

import io
import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from stand.cli.panel import AFTER_S, EVERY_S, ProgressLine
from stand.core.balls import Balls, integrate_balls
from stand.core.model import StandParameters
from stand.core.transient import PROGRESS_EVERY, integrate
from stand.sim.physics import SceneSpeed

DEMO = StandParameters(M1=8.0, M2=9.0, C1=4.5e4, C2=5.2e4, H1=40.0, H2=60.0, M3=60.0,
                       J3=21.0, a=0.15, b=0.85, c=0.70, d=0.20, R1=0.09, R2=0.08)  # fmt: skip
U = np.array([5e-3, 3e-3j])


class Clock:
    """A clock the test moves by hand [s]."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_silent_first_then_one_line_per_interval() -> None:
    clock, out = Clock(), io.StringIO()
    line = ProgressLine("simulating demo-balls", stream=out, clock=clock)
    for t in (0.5, 1.0, 2.9):
        clock.now = t
        line.simulated(10 * t, 60.0)
    assert out.getvalue() == ""  # a job done within AFTER_S prints nothing more
    clock.now = AFTER_S
    line.simulated(24.2, 60.0)
    clock.now = AFTER_S + EVERY_S - 0.01
    line.simulated(40.0, 60.0)  # too soon after the first
    clock.now = AFTER_S + EVERY_S
    line.count(3, 200, "rotor")
    assert out.getvalue().splitlines() == [
        "simulating demo-balls: 24 of 60 s simulated (3 s)",
        "simulating demo-balls: rotor 3 of 200 done (6 s)",
    ]


@given(st.lists(st.floats(0.0, 5.0), min_size=1, max_size=60))
def test_lines_never_closer_than_the_interval(steps: list[float]) -> None:
    """Whatever the pace of the calls, no line before AFTER_S and none within EVERY_S of
    the one before; a call at or past both gives a line (nothing is swallowed for good)."""
    clock, out = Clock(), io.StringIO()
    line = ProgressLine("w", stream=out, clock=clock)
    printed: list[float] = []
    for dt in steps:
        clock.now += dt
        before = line.lines
        line.say("x")
        due = clock.now >= AFTER_S and (not printed or clock.now - printed[-1] >= EVERY_S)
        assert (line.lines > before) == due
        if due:
            printed.append(clock.now)
    assert len(out.getvalue().splitlines()) == len(printed)


def test_the_stand_integration_tells_increasing_times_within_the_run() -> None:
    told: list[float] = []
    t = np.linspace(0.0, 2.0, 2001)
    run = integrate(DEMO, SceneSpeed(900 * math.pi / 30, 10.0, ramp_s=1.0), U, t,
                    progress=told.append)  # fmt: skip
    assert len(told) == run.nfev // PROGRESS_EVERY >= 1
    assert told == sorted(told) and 0.0 <= told[0] and told[-1] <= 2.0


def test_the_balls_integration_tells_increasing_times_within_the_run() -> None:
    told: list[float] = []
    balls = Balls(plane=1, n=2, mass_kg=0.05, radius_m=0.06, drag_n_s_m=0.5)
    t = np.linspace(0.0, 2.0, 2001)
    run = integrate_balls(DEMO, SceneSpeed(900 * math.pi / 30, 10.0), U, balls, t,
                          np.array([0.4, 2.9]), progress=told.append)  # fmt: skip
    assert len(told) == run.nfev // PROGRESS_EVERY >= 1
    assert told == sorted(told) and 0.0 <= told[0] and told[-1] <= 2.0
