"""Tolerances (ISO 21940-11) and corrections."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from strategies import DEMO, stands

from stand.core import StandParameters
from stand.core.balance import correction, static_couple
from stand.core.tolerance import bearing_shares, permissible_unbalance, plane_tolerances


def test_permissible_unbalance_is_iso_s_formula() -> None:
    # ISO 21940-11: U_per = 1000 G m / Omega [g mm], G in mm/s, m in kg, Omega in rad/s
    for G, m, rpm in ((6.3, 60.0, 1500.0), (2.5, 2000.0, 3000.0), (0.4, 0.05, 30000.0)):
        omega = rpm * 2 * math.pi / 60
        assert permissible_unbalance(m, G * 1e-3, omega) * 1e6 == pytest.approx(
            1000 * G * m / omega, rel=1e-12
        )


def test_lever_rule_with_the_30_70_limits() -> None:
    centred = dataclasses.replace(DEMO, a=0.0, b=0.5, c=0.5, d=0.0)
    assert bearing_shares(centred, 1.0) == pytest.approx((0.5, 0.5))
    near1 = dataclasses.replace(DEMO, a=0.0, b=0.1, c=0.9, d=0.0)  # CM close to support 1
    assert bearing_shares(near1, 1.0) == pytest.approx((0.7, 0.3))  # 0.9 / 0.1 held to 70/30
    mid = dataclasses.replace(DEMO, a=0.0, b=0.4, c=0.6, d=0.0)
    assert bearing_shares(mid, 1.0) == pytest.approx((0.6, 0.4))


@given(stands())
def test_plane_tolerances_keep_both_bearings_within_theirs(p: StandParameters) -> None:
    """Whatever the phases, residuals at the plane tolerances load each bearing plane by at
    most its share (equality on the binding one), to rounding (1e-12)."""
    s = np.array(bearing_shares(p, 1.0))
    u = np.array(plane_tolerances(p, 1.0))
    L = p.L
    x = np.array([p.a, p.a + p.b + p.c])
    load = np.abs(np.array([(L - x) / L, x / L])) @ u
    assert np.all(load <= s * (1 + 1e-12))
    assert np.max(load / s) == pytest.approx(1.0, rel=1e-12)
    assert u[0] / u[1] == pytest.approx(s[0] / s[1], rel=1e-12)


def test_an_overhung_plane_gets_a_stricter_tolerance() -> None:
    inside = dataclasses.replace(DEMO, a=0.0, b=0.5, c=0.5, d=0.0)
    overhung = dataclasses.replace(DEMO, a=-0.3, b=0.8, c=0.5, d=0.0)  # same CM split
    assert plane_tolerances(inside, 1.0) == pytest.approx((0.5, 0.5))
    t = plane_tolerances(overhung, 1.0)
    assert t[0] < 0.5 and t[1] < 0.5


unbalances = st.builds(
    lambda m, a: m * np.exp(-1j * math.radians(a)), st.floats(1e-7, 10.0), st.floats(0.0, 360.0)
)


@given(unbalances, st.floats(0.01, 2.0), st.booleans())
def test_a_free_correction_cancels_the_unbalance(U: complex, R: float, remove: bool) -> None:
    c = correction(U, R, remove=remove)
    (w,) = c.weights
    assert w.mass_kg == pytest.approx(abs(U) / R, rel=1e-12)
    phi = -math.degrees(np.angle(U)) % 360
    want = phi if remove else (phi + 180) % 360
    assert min(abs(w.angle_deg - want), 360 - abs(w.angle_deg - want)) < 1e-9
    assert abs(c.residual_kg_m) <= 1e-12 * abs(U)


@given(unbalances, st.integers(3, 36), st.floats(0.0, 360.0), st.booleans())
def test_a_split_onto_two_positions_is_exact(U: complex, n: int, p0: float, remove: bool) -> None:
    c = correction(U, 0.1, remove=remove, positions=n, position0_deg=p0)
    assert 1 <= len(c.weights) <= 2 and all(w.mass_kg >= 0 for w in c.weights)
    pitch = 360 / n
    for w in c.weights:
        off = ((w.angle_deg - p0) / pitch - w.position) % n
        assert min(off, n - off) < 1e-9
    if len(c.weights) == 2:
        assert (c.weights[1].position - c.weights[0].position) % n == 1  # neighbours
    assert abs(c.residual_kg_m) <= 1e-9 * abs(U)


@given(unbalances, st.integers(1, 2), st.floats(0.0, 360.0))
def test_one_or_two_positions_correct_what_lies_on_their_axis(
    U: complex, n: int, p0: float
) -> None:
    c = correction(U, 0.1, positions=n, position0_deg=p0)
    axis = np.exp(-1j * math.radians(p0))  # position 0's direction, in the seed's sense
    along = (U * np.conj(axis)).real
    if n == 1:  # only what points at the one position can be taken away
        expect = abs(U) ** 2 - max(along, 0.0) ** 2
    else:
        expect = abs(U) ** 2 - along**2
    assert abs(c.residual_kg_m) ** 2 == pytest.approx(expect, abs=1e-9 * abs(U) ** 2)


def test_rounding_to_available_weights_reports_what_it_leaves() -> None:
    U = 5e-3 * np.exp(-1j * math.radians(30.0))  # 55.6 g at 90 mm
    c = correction(U, 0.09, steps_kg=[0.01, 0.02, 0.05])  # 55.6 g: 50 + 10 is nearer than 50
    assert [w.pieces_kg for w in c.weights] == [(0.05, 0.01)]
    assert c.weights[0].mass_kg == pytest.approx(0.06)
    assert abs(c.residual_kg_m) == pytest.approx(0.06 * 0.09 - 5e-3, rel=1e-9)
    c = correction(U, 0.09, step_kg=0.002)
    assert c.weights[0].mass_kg == pytest.approx(0.056)  # nearest 2 g multiple of 55.6 g
    assert abs(c.residual_kg_m) == pytest.approx(abs(5e-3 - 0.056 * 0.09), rel=1e-9)


@given(unbalances, unbalances)
def test_static_plus_couple_give_back_the_planes(U1: complex, U2: complex) -> None:
    s, c = static_couple(DEMO, [U1, U2])
    assert abs(s / 2 + c - U1) <= 1e-12 * (abs(U1) + abs(U2))
    assert abs(s / 2 - c - U2) <= 1e-12 * (abs(U1) + abs(U2))


@settings(max_examples=200, deadline=None)
@given(
    mass_g=st.floats(0.0, 400.0),
    stock=st.lists(st.sampled_from([0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0]), min_size=1, max_size=5),
)
def test_a_stack_is_the_nearest_sum_of_stock_weights(mass_g: float, stock: list[float]) -> None:
    """Against brute force over every count of each size up to what the mass needs: no
    sum of stock weights is nearer (1e-9 g: the sums are in the weights' common unit)."""
    import itertools

    from stand.core.balance import stack

    sizes = sorted(set(stock))
    got = sum(stack(mass_g * 1e-3, [x * 1e-3 for x in sizes])) * 1e3
    limits = [range(int(mass_g // x) + 2) for x in sizes]
    if math.prod(len(r) for r in limits) > 20_000:
        limits = [range(int(mass_g // x) + 2) if x >= 5 else range(0, 12) for x in sizes]
    best = min(abs(sum(k * x for k, x in zip(ks, sizes, strict=True)) - mass_g)
               for ks in itertools.product(*limits))  # fmt: skip
    assert abs(got - mass_g) <= best + 1e-9
