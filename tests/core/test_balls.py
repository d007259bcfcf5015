"""The balls of a ball balancer free on their race, coupled to the stand
(``stand.core.balls``), held to the truths they must meet: locked, they are the stand
model with their unbalance and mass added; free in a window they settle where the closed
form (``stand.core.autobalance.balanced``) says, the race plane still; below the window
and in the gap they gather on the heavy side; beyond their capacity they leave the closed
form's residual; the drive's work is what the supports and the race dissipate plus the
change of energy."""

from __future__ import annotations

import cmath
import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stand.core.autobalance import balanced, receptance, with_balls
from stand.core.balls import G_M_S2, Balls, integrate_balls
from stand.core.model import StandParameters
from stand.core.transient import fit_1x, integrate, steady_state_initial
from stand.sim.physics import SceneSpeed

DEMO = StandParameters(M1=8.0, M2=9.0, C1=4.5e4, C2=5.2e4, H1=40.0, H2=60.0, M3=60.0,
                       J3=21.0, a=0.15, b=0.85, c=0.70, d=0.20, R1=0.09, R2=0.08)  # fmt: skip
"""The demo stand, damped (40 and 60 N s/m) so that a start's free vibration dies away."""
U = np.array([5000e-6 * cmath.exp(-1j * math.radians(30)),
              3000e-6 * cmath.exp(-1j * math.radians(200))])  # fmt: skip
BALLS = Balls(plane=1, n=2, mass_kg=0.05, radius_m=0.06, drag_n_s_m=0.5)


def _w(rpm: float) -> float:
    return rpm * math.pi / 30


def _race_1x(run, p: StandParameters, revs: int = 20) -> complex:  # type: ignore[no-untyped-def]
    """The race plane's 1x displacement over the run's last ``revs`` revolutions [m]."""
    z = p.a
    xP = (1 - z / p.L) * run.x_m[:, 0] + z / p.L * run.x_m[:, 1]
    keep = run.theta_rad >= run.theta_rad[-1] - revs * 2 * math.pi
    return complex(fit_1x(run.theta_rad[keep], xP[keep]))


def test_locked_balls_are_the_stand_with_their_unbalance_and_mass() -> None:
    """Held at their start, the balls' coupling terms must reduce to an unbalance m R
    e^{i phi} at their plane and their mass on the rotor: the stand model integrated with
    those, from the same state, agrees to the integrators' tolerance (rtol 1e-10: 1e-7 of
    the acceleration's amplitude, with margin for two integrators' own errors)."""
    phi0 = np.array([0.4, 2.9])
    Ub = BALLS.mass_kg * BALLS.radius_m * np.exp(1j * phi0).sum()
    speed = SceneSpeed(_w(900), 10.0, ramp_s=0.5)
    t = np.linspace(0.0, 1.5, 3001)
    run = integrate_balls(DEMO, speed, U, BALLS, t, phi0, rtol=1e-10, locked=True)
    ref = integrate(with_balls(DEMO, 1, 0.1), speed, U + np.array([Ub, 0]), t, rtol=1e-10)
    scale = np.max(np.abs(ref.a_m_s2))
    assert np.max(np.abs(run.a_m_s2 - ref.a_m_s2)) < 1e-7 * scale


@pytest.mark.parametrize(("n", "seconds"), [(2, 25.0), (3, 45.0)])
def test_free_balls_settle_where_the_closed_form_says(n: int, seconds: float) -> None:
    """At 900 rpm (in the upper window) the balls make the closed form's U_b to 1e-4 of
    it and the race plane's 1x falls below a thousandth of its motion without balls.
    Three balls of a third of the mass settle slower (their error falls by e every 5 s,
    measured): 45 s."""
    balls = dataclasses.replace(BALLS, n=n, mass_kg=0.1 / n)
    w = _w(900)
    pb = with_balls(DEMO, 1, 0.1)
    phi0 = np.linspace(0.2, 2.2, n)
    Ub0 = balls.mass_kg * balls.radius_m * np.exp(1j * phi0).sum()
    y0 = steady_state_initial(pb, w, U + np.array([Ub0, 0.0]))
    t = np.linspace(0.0, seconds, round(seconds * 1000) + 1)
    run = integrate_balls(DEMO, SceneSpeed(w, 60.0), U, balls, t, phi0, y0=y0, rtol=1e-9)
    want = balanced(pb, 1, U, w, balls=n, ball_kg=balls.mass_kg, radius_m=balls.radius_m)
    got = run.balls_kg_m(balls)[-1]
    assert abs(got - want.balls_kg_m) < 1e-4 * abs(want.balls_kg_m), (got, want.balls_kg_m)
    no_balls = abs(receptance(pb, w)[0] @ U) * w**2  # the race plane's motion [m]
    assert abs(_race_1x(run, DEMO)) < 1e-3 * no_balls
    if n == 2:  # symmetric about U_b, where the closed form puts them
        angles = sorted((-np.degrees(run.phi_rad[-1])) % 360)
        assert np.allclose(angles, sorted(want.ball_angles_deg), atol=0.01)


@pytest.mark.parametrize("rpm", [300.0, 430.0])
def test_below_the_window_and_in_the_gap_the_balls_gather_on_the_heavy_side(rpm: float) -> None:
    """At 300 rpm (below the first natural speed, 339) and at 430 rpm (between the
    antiresonance, 398, and the second natural speed, 468), where ``Re H_PP > 0``: the
    balls end together (to 0.5 deg) at full capacity on the race plane's high spot (their
    unbalance along its motion, to 0.5 deg), and that motion grows (x2.8 and x1.5)."""
    w = _w(rpm)
    pb = with_balls(DEMO, 1, 0.1)
    t = np.linspace(0.0, 40.0, 401)
    run = integrate_balls(DEMO, SceneSpeed(w, 50.0), U, BALLS, t, [0.3, 3.0], rtol=1e-8)
    phi = run.phi_rad[-1]
    gap = abs((phi[0] - phi[1] + math.pi) % (2 * math.pi) - math.pi)
    assert gap < math.radians(0.5), math.degrees(gap)
    H = receptance(pb, w)
    Ub = run.balls_kg_m(BALLS)[-1]
    moved = H[0] @ (U + np.array([Ub, 0.0]))  # the race plane's motion with the balls
    assert abs(Ub) > 0.9999 * BALLS.capacity_kg_m
    assert abs(cmath.phase(Ub / moved)) < math.radians(0.5), math.degrees(cmath.phase(Ub / moved))
    assert abs(moved) > 1.4 * abs(H[0] @ U)


def test_beyond_capacity_they_gather_opposite_and_leave_the_closed_form_residual() -> None:
    """The race plane's own unbalance twice the balls' capacity: at 900 rpm they gather
    where the closed form says (opposite what moves the plane, turned by the damped
    receptance's phase: 0.75 deg here) and the stand still measures its residual there.
    To 1e-3: the race plane still moves, so the gathered balls ripple at 2x (about
    |x_P| / 4R rad) and their mean place shifts at second order (measured: 5.0e-4)."""
    big = U * 2.4
    w = _w(900)
    pb = with_balls(DEMO, 1, 0.1)
    want = balanced(pb, 1, big, w, balls=2, ball_kg=0.05, radius_m=0.06)
    assert want.capacity_ratio > 1
    y0 = steady_state_initial(pb, w, big + np.array([0.006 * cmath.exp(2j), 0]))
    t = np.linspace(0.0, 25.0, 5001)
    run = integrate_balls(DEMO, SceneSpeed(w, 30.0), big, BALLS, t, [1.0, 1.0], y0=y0,
                          rtol=1e-9)  # fmt: skip
    got = run.balls_kg_m(BALLS)[-1]
    assert abs(got - want.balls_kg_m) < 1e-3 * abs(want.balls_kg_m)
    residual = big[0] + got
    assert abs(residual - want.residual_kg_m[0]) < 1e-3 * abs(want.residual_kg_m[0])


@pytest.mark.parametrize(("gravity", "ramp_s", "tol"), [(0.0, 0.0, 1e-8), (G_M_S2, 0.0, 1e-8),
                                                        (G_M_S2, 1.0, 1e-4)])  # fmt: skip
def test_the_drives_work_is_what_is_dissipated_plus_the_energy_gained(
    gravity: float, ramp_s: float, tol: float
) -> None:
    """Over 2 s (three balls, from rest or on the way up), the drive's work equals the
    supports' and the race's dissipation plus the change of energy, to 1e-8 of the
    largest at constant speed (Simpson's rule on 40 000 points of an integration at rtol
    1e-10) and 1e-4 through a run-up (the speed's corner at the ramp's end costs the
    quadrature its order there)."""
    from scipy.integrate import simpson

    balls = dataclasses.replace(BALLS, n=3, gravity_m_s2=gravity)
    t = np.linspace(0.0, 2.0, 40001)
    run = integrate_balls(DEMO, SceneSpeed(_w(900), 5.0, ramp_s=ramp_s), U, balls, t,
                          [0.3, 2.0, 4.0], rtol=1e-10)  # fmt: skip
    work = simpson(run.drive_w, x=t)
    lost = simpson(run.dissipated_w, x=t)
    gained = run.energy_j[-1] - run.energy_j[0]
    assert abs(work - lost - gained) < tol * max(abs(work), abs(lost), abs(gained))


def test_held_balls_do_not_creep_and_their_race_forces_balance_the_energy() -> None:
    """With a rolling resistance that holds them (0.5 of the force pressing them onto the
    race, gravity on), the balls never move on the race: their places are the start's
    exactly (a true stick, no creep); the drive's work balances to 1e-8 with the holding
    forces counted."""
    from scipy.integrate import simpson

    balls = dataclasses.replace(BALLS, rolling=0.5, gravity_m_s2=G_M_S2)
    t = np.linspace(0.0, 2.0, 40001)
    phi0 = np.array([1.5, 2.0])
    run = integrate_balls(DEMO, SceneSpeed(_w(900), 5.0), U, balls, t, phi0, rtol=1e-10)
    assert np.all(run.phi_rad == phi0) and np.all(run.phi_rate_rad_s == 0.0)
    work, lost = simpson(run.drive_w, x=t), simpson(run.dissipated_w, x=t)
    gained = run.energy_j[-1] - run.energy_j[0]
    assert abs(work - lost - gained) < 1e-8 * max(abs(work), abs(lost), abs(gained))


def test_a_little_rolling_resistance_leaves_the_balls_short_of_their_place() -> None:
    """At 1e-4 the balls stick and roll (about 45 switches a second: the force on them
    swings every revolution) and come to rest within a few degrees of the closed form's
    places, not on them: a dead band.  The drive's work balances to 2e-3: the power jumps
    at every switch, and Simpson's rule on 40 000 points carries a first-order error at
    each (measured 1e-4; held balls alone balance to 1e-10, above)."""
    from scipy.integrate import simpson

    balls = dataclasses.replace(BALLS, rolling=1e-4)
    w, pb = _w(900), with_balls(DEMO, 1, 0.1)
    phi0 = np.array([1.5, 2.0])
    y0 = steady_state_initial(pb, w, U + np.array([0.003 * np.exp(1j * phi0).sum(), 0.0]))
    t = np.linspace(0.0, 20.0, 40001)
    run = integrate_balls(DEMO, SceneSpeed(w, 30.0), U, balls, t, phi0, y0=y0, rtol=1e-10)
    assert np.all(run.phi_rate_rad_s[-1] == 0.0)  # at rest on the race
    want = balanced(pb, 1, U, w, balls=2, ball_kg=0.05, radius_m=0.06)
    off = np.abs(np.sort((-np.degrees(run.phi_rad[-1])) % 360) - np.sort(want.ball_angles_deg))
    assert np.all(off < 5.0) and np.any(off > 0.5), off
    work, lost = simpson(run.drive_w, x=t), simpson(run.dissipated_w, x=t)
    gained = run.energy_j[-1] - run.energy_j[0]
    assert abs(work - lost - gained) < 2e-3 * max(abs(work), abs(lost), abs(gained))


@settings(max_examples=60, deadline=None)
@given(
    t=st.floats(0.0, 5.0),
    y=st.lists(st.floats(-1.0, 1.0), min_size=8, max_size=8),
    held=st.lists(st.booleans(), min_size=2, max_size=2),
    slip=st.lists(st.sampled_from([-1.0, 0.0, 1.0]), min_size=2, max_size=2),
)
def test_one_instant_on_scalars_is_the_same_as_a_column_of_instants(
    t: float, y: list[float], held: list[bool], slip: list[float]
) -> None:
    """The integrator's call (a float time, a 1-D state) and the vectorised one (times
    (1,), states (8, 1)) are one formula: equal to the last bits (rtol 1e-12: the same
    operations in the same order on scalars and on one-element arrays)."""
    from stand.core.balls import _System

    speed = SceneSpeed(_w(900), 5.0, ramp_s=1.0, ripple=0.01, ripple_hz=2.0, drift_per_s=0.001)
    sys = _System(DEMO, dataclasses.replace(BALLS, rolling=0.01, gravity_m_s2=G_M_S2), U, speed)
    z = np.array(y) * np.array([1e-4, 1e-4, 1e-2, 1e-2, 3.0, 3.0, 10.0, 10.0])
    h, sl = np.array(held), np.array(slip)
    one = sys.accel(t, z, h, sl)
    col = sys.accel(np.array([t]), z[:, None], h, sl)
    for a, b in zip(one, col, strict=True):
        assert a.shape == b[:, 0].shape
        np.testing.assert_allclose(a, b[:, 0], rtol=1e-12, atol=1e-300)
