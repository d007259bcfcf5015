"""Tolerance forms and ISO 21940-14 acceptance (stand.core.tolerance), against hand values."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from strategies import DEMO

from stand.core.tolerance import (
    api_permissible,
    bearing_criteria,
    judge,
    key_mass,
    key_unbalance,
    overall,
    plane_tolerances,
    static_couple_criteria,
    static_couple_limits,
    transfer,
)

phasors = st.builds(
    lambda m, a: m * np.exp(1j * math.radians(a)), st.floats(0.0, 10.0), st.floats(0.0, 360.0)
)
positions = st.floats(-2.0, 3.0)


def test_the_api_worked_example() -> None:
    """API 617 / 687: 500 lb (226.8 kg) per journal at 15 000 rpm is 4 W / N = 0.1333 oz in,
    96.0 g mm (6350 x 226.8 / 15000 = 96.012)."""
    assert api_permissible(226.8, 15000.0) * 1e6 == pytest.approx(96.0, abs=0.05)
    oz_in = 4 * 500 / 15000  # the imperial form with W in lb
    assert api_permissible(226.8, 15000.0) * 1e6 == pytest.approx(oz_in * 28.3495 * 25.4, rel=2e-3)


@given(phasors, phasors, positions, positions, positions, st.floats(0.05, 3.0))
def test_the_transfer_keeps_resultant_and_moment(
    U1: complex, U2: complex, x1: float, x2: float, zA: float, span: float
) -> None:
    """The bearing-plane pair has the correction planes' resultant and moment about any
    point (here the origin), to rounding."""
    U = np.array([U1, U2])
    V = transfer([x1, x2], [zA, zA + span]) @ U
    assert V.sum() == pytest.approx(U.sum(), abs=1e-9)
    assert V @ np.array([zA, zA + span]) == pytest.approx(U @ np.array([x1, x2]), abs=1e-8)


@given(st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 360.0), st.floats(0.0, 360.0))
def test_the_exact_bearing_verdict_is_never_stricter_than_the_any_phase_limits(
    f1: float, f2: float, a1: float, a2: float
) -> None:
    """Residuals within today's correction-plane limits (any phase) load the supports within
    their shares by the exact transfer too: judging at the supports never fails such a
    rotor (the demo's verdicts cannot turn to fail)."""
    per = np.array(plane_tolerances(DEMO, 1e-3))
    share = min(max((DEMO.L - DEMO.a - DEMO.b) / DEMO.L, 0.3), 0.7)
    s = np.array([share, 1 - share]) * 1e-3
    U = per * np.array([f1, f2]) * np.exp(1j * np.radians([a1, a2]))
    x = (DEMO.a, DEMO.a + DEMO.b + DEMO.c)
    for c in bearing_criteria(x, (0.0, DEMO.L), s):
        assert c.value(U) <= c.limit * (1 + 1e-9)


def test_iso_21940_14_three_states_and_two_moments() -> None:
    """Hand cases at a limit of 10 with a combined error of 1."""
    cases = [  # value, after balancing, later check
        (8.9, "pass", "pass"),
        (9.0, "pass", "pass"),  # U + dU = limit: passes
        (9.5, "undecided", "pass"),
        (10.5, "undecided", "pass"),
        (11.0, "undecided", "pass"),  # U - dU = limit: not over
        (11.1, "fail", "fail"),
    ]
    for value, after, later in cases:
        assert judge(value, 1.0, 10.0, "after_balancing") == after, value
        assert judge(value, 1.0, 10.0, "later_check") == later, value
    assert overall(["pass", "undecided", "pass"]) == "undecided"
    assert overall(["undecided", "fail"]) == "fail"
    assert overall(["pass", "pass"]) == "pass"


@given(st.floats(0, 100), st.floats(0, 10), st.floats(0.1, 100))
def test_the_later_check_is_never_stricter(value: float, error: float, limit: float) -> None:
    after, later = judge(value, error, limit, "after_balancing"), judge(value, error, limit,
                                                                        "later_check")  # fmt: skip
    assert not (after == "pass" and later != "pass")
    assert not (later == "fail" and after != "fail")


@given(st.floats(-1.0, 0.2), st.floats(0.8, 2.0), st.floats(0.3, 0.7))
def test_static_couple_limits_hold_at_any_phase(x1: float, x2: float, cm: float) -> None:
    """Equal plane limits from a resultant and a moment limit keep both at any phase
    (here: in phase for the resultant, in opposition for the moment, the worst cases)."""
    S, P = 2e-3, 1e-3
    k, _ = static_couple_limits([x1, x2], cm, S, P)
    res, mom = static_couple_criteria([x1, x2], cm, S, P)
    assert res.value([k, k]) <= S * (1 + 1e-12)
    opposed = [k * np.sign(x1 - cm), k * np.sign(x2 - cm)]
    assert mom.value(opposed) <= P * (1 + 1e-12)
    assert max(res.value([k, k]) / S, mom.value(opposed) / P) == pytest.approx(1.0)


def test_the_half_key_is_half_the_key_at_its_centroid() -> None:
    """A 10 x 8 x 240 mm steel key (7850 kg/m^3: 150.7 g) with its centroid at 40 mm: the
    half-key's unbalance is m r / 2 = 3014.4 g mm, at the keyway's angle, to 0.1 %."""
    m = key_mass(10e-3, 8e-3, 240e-3, 7850.0)
    assert m == pytest.approx(0.150720, rel=1e-9)
    U = key_unbalance(m, 0.040, 30.0, 0.5)
    hand = 150.72 * 40.0 / 2  # g mm
    assert abs(U) * 1e6 == pytest.approx(hand, rel=1e-3)
    assert math.degrees(-np.angle(U)) == pytest.approx(30.0, abs=1e-9)
