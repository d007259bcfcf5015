"""The ball balancer's closed forms on the stand (seeds 000/004 carried to a one-direction
support): the receptance is the model's own, the windows open at the natural frequencies
and close at the race plane's antiresonance, and the balanced state holds the race plane
still in the stand model itself."""

from __future__ import annotations

import cmath
import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stand.core.autobalance import (
    antiresonance,
    balanced,
    driving_point,
    plane_positions,
    receptance,
    windows,
    with_balls,
)
from stand.core.model import StandParameters, forward, natural_frequencies
from stand.errors import ModelError

DEMO = StandParameters(M1=8, M2=9, C1=4.5e4, C2=5.2e4, M3=60, J3=21, a=0.15, b=0.85,
                       c=0.70, d=0.20, R1=0.09, R2=0.08)  # fmt: skip
DAMPED = dataclasses.replace(DEMO, H1=40.0, H2=60.0)


def _x_at_planes(p: StandParameters, w: float, U: np.ndarray) -> np.ndarray:
    """The planes' x-displacement phasors by the stand model's own forward solution:
    supports' accelerations -> displacements -> the rigid rotor's line at each plane."""
    X = -np.asarray(forward(p, w, U)) / w**2
    return np.array([(1 - z / p.L) * X[0] + (z / p.L) * X[1] for z in plane_positions(p)])


@pytest.mark.parametrize("p", [DEMO, DAMPED], ids=["undamped", "damped"])
@pytest.mark.parametrize("hz", [2.0, 6.3, 7.0, 15.0, 60.0])
def test_the_receptance_is_the_stand_model_s_own(p: StandParameters, hz: float) -> None:
    """``w^2 H U`` is what the seed's forward solution moves each plane by, to 1e-10
    relative (two routes: a 2 x 2 solve here, the seed's closed form in double-double
    there; away from the natural frequencies at 5.6 and 7.8 Hz, where both are exact)."""
    w = 2 * math.pi * hz
    H = receptance(p, w)
    for j in range(2):
        U = np.zeros(2, complex)
        U[j] = 1e-3
        x = _x_at_planes(p, w, U)
        assert np.allclose(w**2 * H[:, j] * 1e-3, x, rtol=1e-10, atol=0), (hz, j)


def test_at_rest_speed_the_receptance_is_the_static_compliance() -> None:
    """Far below the modes ``Re H_PP > 0``: the race moves with the force; no window."""
    z = plane_positions(DEMO)[0]
    n = np.array([1 - z / DEMO.L, z / DEMO.L])
    static = float(n @ np.linalg.solve(np.diag([DEMO.C1, DEMO.C2]), n))
    assert driving_point(DEMO, 1, 1e-3).real == pytest.approx(static, rel=1e-9)


@pytest.mark.parametrize("plane", [1, 2])
def test_undamped_windows_are_first_mode_to_antiresonance_and_above_the_second(
    plane: int,
) -> None:
    """Edges within 1e-6 of the closed-form natural frequencies and antiresonance; Re H_PP
    < 0 inside each window, > 0 between them (checked at each interval's middle)."""
    w1, w2 = natural_frequencies(DEMO)
    anti = antiresonance(DEMO, plane)
    assert anti is not None and w1 < anti < w2
    (lo1, hi1), (lo2, hi2) = windows(DEMO, plane, 20 * w2)
    assert hi2 is None and hi1 is not None
    for got, want in ((lo1, w1), (hi1, anti), (lo2, w2)):
        assert got == pytest.approx(want, rel=1e-6)
    for w, sign in ((0.5 * w1, 1), ((lo1 + hi1) / 2, -1), ((hi1 + lo2) / 2, 1), (3 * w2, -1)):
        assert np.sign(driving_point(DEMO, plane, w).real) == sign, w


def test_damping_moves_the_edges_a_little_and_keeps_two_windows() -> None:
    """With H1 = 40, H2 = 60 N s/m the windows stay two, their edges within 1 % of the
    undamped ones (damping ratio about 3 %)."""
    und, dam = windows(DEMO, 1, 400.0), windows(DAMPED, 1, 400.0)
    assert len(und) == len(dam) == 2
    for (a, b), (c, d) in zip(und, dam, strict=True):
        assert c == pytest.approx(a, rel=0.01)
        assert (b is None) == (d is None) and (b is None or d == pytest.approx(b, rel=0.01))


def test_the_balls_mass_keeps_mass_and_first_moment() -> None:
    q = with_balls(DEMO, 2, 0.4)
    z_com = lambda s: s.a + s.b  # noqa: E731
    assert q.M3 == pytest.approx(60.4)
    assert q.M3 * z_com(q) == pytest.approx(60 * z_com(DEMO) + 0.4 * plane_positions(DEMO)[1])
    assert plane_positions(q) == pytest.approx(plane_positions(DEMO)) and q.L == DEMO.L


@settings(max_examples=60, deadline=None)
@given(
    st.integers(1, 2),
    st.floats(60.0, 300.0),
    st.floats(0.0, 2e-3, allow_subnormal=False),
    st.floats(0.0, 360.0),
    st.floats(0.0, 2e-3, allow_subnormal=False),
    st.floats(0.0, 360.0),
)
def test_the_balanced_state_holds_the_race_plane_still(
    plane: int, w: float, u1: float, a1: float, u2: float, a2: float
) -> None:
    """Above the second mode, the balls' unbalance put on the model (with their mass)
    leaves the race plane's motion below 1e-9 of what the rotor alone makes there, while
    within capacity; the two balls' unbalances sum to U_b.  (Below 1e-30 m the motion is
    no motion: hypothesis found 2e-313 kg m, whose motion is a denormal.)"""
    q = with_balls(DAMPED, plane, 2 * 0.05)
    U = np.array([cmath.rect(u1, -math.radians(a1)), cmath.rect(u2, -math.radians(a2))])
    b = balanced(q, plane, U, w, balls=2, ball_kg=0.05, radius_m=0.05)
    alone = abs(_x_at_planes(q, w, U)[plane - 1])
    if b.capacity_ratio <= 1 and alone > 0:
        left = abs(_x_at_planes(q, w, np.array(b.residual_kg_m))[plane - 1])
        assert left <= 1e-9 * alone + 1e-30
        balls = sum(0.05 * 0.05 * cmath.exp(-1j * math.radians(t)) for t in b.ball_angles_deg)
        assert abs(balls - b.balls_kg_m) <= 1e-12


def test_beyond_capacity_the_balls_gather_and_leave_the_rest() -> None:
    """A need of twice the capacity: both balls at U_b's angle, and the race plane left
    with the unbalance the capacity could not cover (|U_b| - n m R)."""
    q = with_balls(DEMO, 1, 0.1)
    U = np.array([cmath.rect(5e-3, 0.3), 0j])
    w = 150.0
    need = balanced(q, 1, U, w, balls=2, ball_kg=0.05, radius_m=1.0)  # capacity 0.1 kg m
    assert need.capacity_ratio < 1
    short = balanced(q, 1, U, w, balls=2, ball_kg=0.0125, radius_m=0.1)  # 2.5e-3 kg m
    assert short.capacity_ratio == pytest.approx(abs(need.balls_kg_m) / 2.5e-3)
    assert abs(short.balls_kg_m) == pytest.approx(2.5e-3)
    assert short.ball_angles_deg[0] == pytest.approx(short.ball_angles_deg[1])
    gap = abs(need.balls_kg_m - short.balls_kg_m)
    assert gap == pytest.approx(abs(need.balls_kg_m) - 2.5e-3, rel=1e-12)


def test_one_ball_is_refused() -> None:
    with pytest.raises(ModelError, match="two or more"):
        balanced(DEMO, 1, [1e-3, 0], 150.0, balls=1, ball_kg=0.05, radius_m=0.05)
