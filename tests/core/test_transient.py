"""The time path: the seed's equations integrated, against the steady state."""

from __future__ import annotations

import math

import numpy as np
import pytest
from strategies import DEMO

from stand.core import (
    StandParameters,
    forward,
    natural_frequencies,
    rpm_to_rad_s,
    unbalance_from_polar,
)
from stand.core.transient import SpeedProfile, fit_1x, integrate, steady_state_initial
from stand.errors import ModelError

U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
W = float(rpm_to_rad_s(900.0))


def test_starting_on_the_steady_orbit_stays_on_it() -> None:
    """Undamped, constant speed, started on the orbit: a(t) = Re(A e^{i theta}) throughout."""
    revs = 20
    t = np.linspace(0, revs * 2 * math.pi / W, revs * 64 + 1)
    res = integrate(
        DEMO,
        SpeedProfile.constant(W, theta0_rad=0.3),
        U,
        t,
        y0=steady_state_initial(DEMO, W, U, theta0_rad=0.3),
        rtol=1e-11,
    )
    A = forward(DEMO, W, U)
    expect = (A[None, :] * np.exp(1j * res.theta_rad)[:, None]).real
    # rtol 1e-11 per step over ~1000 steps: 1e-7 of the amplitude is a wide margin
    assert np.max(np.abs(res.a_m_s2 - expect)) < 1e-7 * np.max(np.abs(A))


def test_run_up_settles_to_the_steady_state() -> None:
    """From rest, a 2 s run-up, damping ratio ~0.1: after 8 s the 1x phasor is the closed form."""
    p = StandParameters(
        **{
            **DEMO.__dict__,
            "H1": 2 * 0.1 * math.sqrt(DEMO.C1 * 38),
            "H2": 2 * 0.1 * math.sqrt(DEMO.C2 * 39),
        }
    )
    rate = 2000.0
    t = np.arange(0, 10.0, 1 / rate)
    res = integrate(p, SpeedProfile.run_up(W, ramp_s=2.0), U, t, rtol=1e-9)
    tail = t >= 8.0  # 6 s after the ramp: free vibration decayed by exp(-0.1 * 35 * 6) ~ 1e-9
    got = fit_1x(res.theta_rad[tail], res.a_m_s2[tail])
    want = forward(p, W, U)
    assert np.max(np.abs(got - want)) < 1e-6 * np.max(np.abs(want))
    # during the run-up the response passes the resonances: it differs from the steady state
    early = (t > 0.5) & (t < 1.0)
    assert np.max(np.abs(res.a_m_s2[early])) > 0
    assert res.omega_rad_s[-1] == W and res.omega_rad_s[0] == 0


def test_speed_change_moves_to_the_new_steady_state() -> None:
    p = StandParameters(**{**DEMO.__dict__, "H1": 600.0, "H2": 650.0})
    w2 = float(rpm_to_rad_s(1200.0))
    speed = SpeedProfile((0.0, 1.0, 1.5), (W, W, w2))
    t = np.arange(0, 6.0, 1 / 2000.0)
    res = integrate(p, speed, U, t, y0=steady_state_initial(p, W, U))
    tail = t >= 4.0
    got = fit_1x(res.theta_rad[tail], res.a_m_s2[tail])
    assert np.max(np.abs(got - forward(p, w2, U))) < 1e-5 * np.max(np.abs(forward(p, w2, U)))


def test_speed_profile_theta_is_the_integral_of_omega() -> None:
    sp = SpeedProfile((0.0, 1.0, 3.0), (0.0, 10.0, 4.0), theta0_rad=1.0)
    t = np.linspace(0, 5, 50001)
    om = sp.omega(t)
    integral = 1.0 + np.concatenate(([0.0], np.cumsum((om[1:] + om[:-1]) / 2 * np.diff(t))))
    np.testing.assert_allclose(sp.theta(t), integral, atol=1e-6)
    assert sp.alpha(0.5) == 10.0 and sp.alpha(2.0) == -3.0 and sp.alpha(4.0) == 0.0


@pytest.mark.parametrize(
    ("t", "w"), [((1.0,), (1.0,)), ((0.0, 0.0), (1.0, 2.0)), ((0.0,), (-1.0,))]
)
def test_bad_speed_profiles_are_refused(t: tuple[float, ...], w: tuple[float, ...]) -> None:
    with pytest.raises(ModelError):
        SpeedProfile(t, w)


def test_stiff_method_agrees() -> None:
    t = np.linspace(0, 0.5, 501)
    a = integrate(DEMO, SpeedProfile.constant(W), U, t, y0=steady_state_initial(DEMO, W, U))
    b = integrate(
        DEMO,
        SpeedProfile.constant(W),
        U,
        t,
        y0=steady_state_initial(DEMO, W, U),
        method="Radau",
        rtol=1e-8,
    )
    assert np.max(np.abs(a.a_m_s2 - b.a_m_s2)) < 1e-5 * np.max(np.abs(a.a_m_s2))
    assert natural_frequencies(DEMO)[1] < W
