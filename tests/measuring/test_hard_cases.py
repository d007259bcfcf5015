"""The named hard cases of the inverse, each with its documented behaviour."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from reference import exact_forward, exact_terms
from strategies import DEMO

from stand.core import (
    StandParameters,
    forward,
    inverse_matrix,
    natural_frequencies,
    propagate_covariance,
    rpm_to_rad_s,
    solve_unbalance,
    split_condition,
    static_resultant,
    unbalance_from_polar,
)
from stand.core.model import plane_matrix, support_determinant
from stand.errors import PlanesTooCloseError, StandError

EPS = float(np.finfo(float).eps)
U_DEMO = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
W900 = float(rpm_to_rad_s(900.0))


def with_(**change: float) -> StandParameters:
    return StandParameters(**{**DEMO.__dict__, **change})


# -- planes close together -------------------------------------------------------------


@given(log_sep=st.floats(-12, -3.2))
def test_planes_too_close_refused_with_conditioning_and_static_resultant(log_sep: float) -> None:
    """b + c from 1e-12 to ~6e-4 of the span: refused (limit 1e3), the static resultant exact."""
    sep = 10.0**log_sep * DEMO.L
    p = with_(b=0.85, c=-0.85 + sep, d=0.20 + 0.85 + 0.70 - sep)  # same span, planes close
    A = forward(p, W900, U_DEMO)
    with pytest.raises(PlanesTooCloseError) as err:
        solve_unbalance(p, W900, A)
    e = err.value
    assert isinstance(e, StandError) and isinstance(e, ValueError)
    assert e.split_condition == pytest.approx(split_condition(p))
    # nearly singular 2x2: kappa = sigma_max^2 / |det| -> (2 + (b/L)^2 + (c/L)^2) L / (b + c)
    assert e.split_condition == pytest.approx(
        (2 + (p.b / p.L) ** 2 + (p.c / p.L) ** 2) * p.L / p.plane_separation, rel=1e-3
    )
    # the static resultant does not suffer: it comes from the force equation alone
    assert abs(e.static_unbalance_kg_m - (U_DEMO[0] + U_DEMO[1])) <= 1e-13 * np.sum(np.abs(U_DEMO))
    assert "\n" not in str(e) and "condition number" in str(e)


def test_coinciding_planes_give_infinite_conditioning_and_the_static_resultant() -> None:
    p = with_(b=0.85, c=-0.85, d=0.20 + 1.55)
    assert p.plane_separation == 0
    A = forward(p, W900, U_DEMO)  # the forward needs no split: it still works
    with pytest.raises(PlanesTooCloseError) as err:
        solve_unbalance(p, W900, A)
    assert math.isinf(err.value.split_condition)
    assert err.value.static_unbalance_kg_m == pytest.approx(U_DEMO[0] + U_DEMO[1], rel=1e-13)


def test_planes_close_but_usable_warn_and_solve() -> None:
    p = with_(b=0.10, c=0.05, d=0.20 + 0.65, a=0.15 + 0.75)  # planes 150 mm apart on 1.9 m
    sol = solve_unbalance(p, W900, forward(p, W900, U_DEMO))
    codes = [d.code for d in sol.diagnostics]
    assert codes == ["planes_close"]
    assert sol.split_condition > 10
    assert np.allclose(sol.U_kg_m, U_DEMO, rtol=1e-12)
    # a stricter caller refuses the same stand
    with pytest.raises(PlanesTooCloseError):
        solve_unbalance(p, W900, forward(p, W900, U_DEMO), max_split_condition=10.0)


def test_demo_has_no_warnings() -> None:
    sol = solve_unbalance(DEMO, W900, forward(DEMO, W900, U_DEMO))
    assert sol.diagnostics == []
    assert sol.split_condition == pytest.approx(2.4562, rel=1e-4)


# -- speed against the natural frequencies ----------------------------------------------


@pytest.mark.parametrize(("mode", "ratio"), [(0, 1.0001), (0, 0.85), (1, 1.2), (1, 0.9)])
def test_near_resonance_warns_with_the_frequency(mode: int, ratio: float) -> None:
    w = float(natural_frequencies(DEMO)[mode]) * ratio
    sol = solve_unbalance(DEMO, w, forward(DEMO, w, U_DEMO))
    (d,) = sol.diagnostics
    assert d.code == "near_resonance"
    f_hz = natural_frequencies(DEMO)[[0, 1]] / (2 * math.pi)
    assert any(f"{f:.3g} Hz" in d.message for f in f_hz)
    # the inverse stays exact, but its conditioning says how much A-errors grow
    assert np.allclose(sol.U_kg_m, U_DEMO, rtol=1e-9)


def test_at_resonance_the_inverse_is_ill_conditioned_and_says_so() -> None:
    w = float(natural_frequencies(DEMO)[1]) * (1 + 1e-9)
    sol = solve_unbalance(DEMO, w, forward(DEMO, w, U_DEMO))
    assert sol.condition_number > 1e6
    assert sol.diagnostics[0].code == "near_resonance"


def test_below_the_support_resonance_warns() -> None:
    w = float(natural_frequencies(DEMO)[0]) * 0.5
    sol = solve_unbalance(DEMO, w, forward(DEMO, w, U_DEMO))
    assert [d.code for d in sol.diagnostics] == ["below_support_resonance"]
    assert sol.diagnostics[0].value == pytest.approx(w / natural_frequencies(DEMO)[1])


# -- very low speed: noise grows as C / omega^4 ------------------------------------------


def test_low_speed_noise_gain_grows_as_c_over_omega_to_the_fourth() -> None:
    stiff = with_(C1=4.5e8, C2=5.2e8)  # natural frequencies ~560 and ~780 Hz
    w1, w2 = float(rpm_to_rad_s(60.0)), float(rpm_to_rad_s(120.0))
    g1 = solve_unbalance(stiff, w1, forward(stiff, w1, U_DEMO)).noise_gain
    g2 = solve_unbalance(stiff, w2, forward(stiff, w2, U_DEMO)).noise_gain
    # G ~ -(C/w^4) [lever terms] + O(M / w^2): ratio 16 up to (w/w_n)^2 ~ 1e-5
    assert g1 / g2 == pytest.approx(16.0, rel=1e-3)
    assert g1 == pytest.approx(np.linalg.norm(inverse_matrix(stiff, w1), 2), rel=1e-12)
    # ... and the propagated covariance grows by 16^2
    cov = np.eye(2) * 1e-6
    c1 = propagate_covariance(inverse_matrix(stiff, w1), cov)
    c2 = propagate_covariance(inverse_matrix(stiff, w2), cov)
    assert np.trace(c1).real / np.trace(c2).real == pytest.approx(256.0, rel=2e-3)
    # the round trip is still exact at 60 rpm
    sol = solve_unbalance(stiff, w1, forward(stiff, w1, U_DEMO))
    assert np.allclose(sol.U_kg_m, U_DEMO, rtol=1e-12)


# -- cancellation and wildly different scales --------------------------------------------


@pytest.mark.parametrize("k", [1.0, 1 + 1e-15, 1 - 1e-12, 1 + 1e-8])
def test_support_resonance_cancellation_m_omega2_equals_c(k: float) -> None:
    """At w^2 = C1/M1 the apparent mass g1 = C1/w^2 - M1 is ~0; nothing degrades."""
    p = with_(M1=8.0, C1=4.5e4, M3=0.2, J3=0.02)  # light rotor: g1 dominates its entries
    w = math.sqrt(p.C1 / p.M1) * k
    N_ex, det_ex, _ = exact_terms(p, w)
    N = plane_matrix(p, w)
    for i in range(2):
        for j in range(2):
            assert abs(N[i, j].real - float(N_ex[i][j])) <= 2 * EPS * abs(float(N_ex[i][j]))
    assert abs(support_determinant(p, w).real - float(det_ex)) <= 2 * EPS * abs(float(det_ex))
    A = forward(p, w, U_DEMO)
    assert np.linalg.norm(A - exact_forward(p, w, U_DEMO)) <= 8 * EPS * np.linalg.norm(A) * (
        np.linalg.cond(inverse_matrix(p, w))
    )
    sol = solve_unbalance(p, w, A)
    assert np.linalg.norm(sol.U_kg_m - U_DEMO) <= 8 * EPS * sol.condition_number * np.linalg.norm(
        U_DEMO
    )


@pytest.mark.parametrize(
    "change",
    [
        {"d": 1e-9, "c": 0.70},  # plane 2 a nanometre inside support 2
        {"a": 1e-12},  # plane 1 on support 1
        {"M1": 1e-9, "M2": 5e4, "C1": 1.0, "C2": 1e10},  # supports of 1 ug and 50 t
        {"M3": 5e4, "J3": 1e-6},  # 50 t rotor with almost no inertia
        {"M3": 0.05, "J3": 1e5},  # 50 g rotor with a huge one
        {"a": -0.8, "d": -0.6},  # both planes far outside the supports
    ],
)
def test_wildly_different_scales_lose_no_precision(change: dict[str, float]) -> None:
    p = with_(**change)
    for rpm in (60.0, 900.0, 30000.0):
        w = float(rpm_to_rad_s(rpm))
        _, _, G_ex = exact_terms(p, w)
        G = inverse_matrix(p, w)
        for i in range(2):
            for j in range(2):
                assert abs(G[i, j].real - float(G_ex[i][j])) <= 8 * EPS * abs(float(G_ex[i][j]))
        A = forward(p, w, U_DEMO)
        kap = np.linalg.cond(G)
        assert np.linalg.norm(A - exact_forward(p, w, U_DEMO)) <= 8 * EPS * kap * np.linalg.norm(A)
        assert np.linalg.norm(G @ A - U_DEMO) <= 8 * EPS * kap * np.linalg.norm(U_DEMO)


def test_static_resultant_direct() -> None:
    A = forward(DEMO, W900, U_DEMO)
    assert static_resultant(DEMO, W900, A) == pytest.approx(U_DEMO[0] + U_DEMO[1], rel=1e-14)
