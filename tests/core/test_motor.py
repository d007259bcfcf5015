"""The drive's shaft (stand.core.motor): exact kinematics, floors, stops at an angle.

Tolerances: the pieces are closed forms, so angles agree to the roundoff of sums of a
few hundred radians (1e-9 rad is 1e6 times that roundoff and 1e-7 deg); a stop's angle
is checked to 1e-6 deg, the index's ±2 deg goal being 2e6 times wider.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stand.core.motor import (
    INDEX_DECEL_SHARE,
    Motor,
    at_rest,
    floors,
    nearest_stop,
    quick_stop,
    ramp_to,
    stop_at,
    stop_at_position,
    turn_to,
    wrap_deg,
)
from stand.errors import ModelError, ParameterError

DEMO = Motor(inertia_kg_m2=0.35, torque_n_m=25.0, brake_torque_n_m=40.0, friction_n_m=0.5)


def test_run_up_is_the_torque_limited_ramp() -> None:
    w = 1500 * math.pi / 30
    path = ramp_to(at_rest(0.3), 0.0, DEMO, w)
    a = (25.0 - 0.5) / 0.35
    t_reach = w / a
    assert path.omega([0.5 * t_reach, t_reach, 10.0]) == pytest.approx([0.5 * w, w, w], rel=1e-12)
    assert float(path.theta(t_reach)) == pytest.approx(0.3 + 0.5 * a * t_reach**2, abs=1e-9)
    assert float(path.theta(t_reach + 2.0)) == pytest.approx(
        0.3 + 0.5 * a * t_reach**2 + 2 * w, abs=1e-9
    )
    # the floor leaves the drag out: the real run-up is longer
    assert floors(DEMO, w).runup_s == pytest.approx(0.35 * w / 25.0)
    assert t_reach > floors(DEMO, w).runup_s


def test_quick_stop_brakes_at_full_deceleration() -> None:
    w = 100.0
    path = quick_stop(ramp_to(at_rest(), 0.0, DEMO, w), 10.0, DEMO)
    a = (40.0 + 0.5) / 0.35
    assert float(path.omega(10.0 + w / a)) == pytest.approx(0.0, abs=1e-9)
    assert float(path.omega(100.0)) == pytest.approx(0.0, abs=1e-9)
    assert path.end_s == pytest.approx(10.0 + w / a)


@settings(max_examples=200, deadline=None)
@given(
    rpm=st.floats(100.0, 3000.0),
    target_deg=st.floats(0.0, 360.0, exclude_max=True),
    start_s=st.floats(5.0, 6.0),
)
def test_stop_at_comes_to_rest_on_the_target(rpm: float, target_deg: float, start_s: float) -> None:
    w = rpm * math.pi / 30
    path = stop_at(ramp_to(at_rest(), 0.0, DEMO, w), start_s, DEMO, math.radians(target_deg))
    end = path.end_s
    assert float(path.omega(end)) == pytest.approx(0.0, abs=1e-9)
    assert float(path.omega(end + 5)) == pytest.approx(0.0, abs=1e-9)
    stopped = math.degrees(float(path.theta(end + 5))) % 360
    assert abs(wrap_deg(stopped - target_deg)) < 1e-6
    # never faster than braking allows, and at most one revolution's wait beside it
    f = floors(DEMO, w)
    brake = w / (INDEX_DECEL_SHARE * DEMO.decel_rad_s2)
    assert end - start_s <= brake + f.index_s + 1e-9
    speeds = path.omega(np.linspace(start_s, end + 1, 2000))
    assert np.all(speeds >= -1e-9) and np.all(np.diff(speeds) <= 1e-9)


@settings(max_examples=100, deadline=None)
@given(start_deg=st.floats(0.0, 360.0), target_deg=st.floats(0.0, 360.0))
def test_turn_to_from_rest_moves_forward_only(start_deg: float, target_deg: float) -> None:
    path = turn_to(at_rest(math.radians(start_deg)), 1.0, DEMO, math.radians(target_deg))
    t = np.linspace(1.0, path.end_s + 1, 500)
    assert np.all(path.omega(t) >= -1e-9)
    moved = math.degrees(float(path.theta(path.end_s + 1))) - start_deg
    assert -1e-9 <= moved < 360 + 1e-6
    assert abs(wrap_deg(start_deg + moved - target_deg)) < 1e-6


def test_stop_at_from_rest_is_a_turn() -> None:
    path = stop_at(at_rest(0.0), 0.0, DEMO, math.pi / 2)
    assert float(path.theta(path.end_s)) == pytest.approx(math.pi / 2, abs=1e-9)


def test_a_second_stop_after_a_stop_is_a_turn_not_a_creep() -> None:
    """After braking the shaft is at rest exactly: a roundoff speed of 1e-14 rad/s once
    made the next stop wait 1e14 s for its angle."""
    w = 94.24777960769379
    first = stop_at(ramp_to(at_rest(), 0.0, DEMO, w), 3.0, DEMO, 0.523)
    assert float(first.omega(first.end_s + 1)) == 0.0
    second = stop_at(first, first.end_s + 1, DEMO, 3.49)
    assert second.end_s < first.end_s + 3
    assert float(second.theta(second.end_s)) % (2 * math.pi) == pytest.approx(3.49, abs=1e-9)


@pytest.mark.parametrize(
    ("field", "value"),
    [("inertia_kg_m2", 0.0), ("torque_n_m", -1.0), ("brake_torque_n_m", math.nan),
     ("friction_n_m", 30.0), ("friction_n_m", -0.1), ("inertia_kg_m2", math.inf)],
)  # fmt: skip
def test_motor_refuses_unphysical_figures(field: str, value: float) -> None:
    figures = {"inertia_kg_m2": 0.35, "torque_n_m": 25.0, "brake_torque_n_m": 40.0}
    with pytest.raises(ParameterError, match=field):
        Motor(**{**figures, field: value})


@pytest.mark.parametrize(
    ("angle", "wrapped"), [(0.0, 0.0), (190.0, -170.0), (-190.0, 170.0), (180.0, 180.0),
                           (-180.0, 180.0), (721.0, 1.0)],
)  # fmt: skip
def test_wrap_deg(angle: float, wrapped: float) -> None:
    assert wrap_deg(angle) == pytest.approx(wrapped)


def test_a_stop_at_a_position_brakes_harder_when_nearer_and_refuses_the_impossible() -> None:
    w = 100.0
    path = ramp_to(at_rest(), 0.0, DEMO, w)
    t = 5.0
    theta = float(path.theta(t))
    full = w * w / (2 * DEMO.decel_rad_s2)
    near = stop_at_position(path, t, DEMO, theta + 1.02 * full)  # inside the share's reach
    assert float(near.theta(near.end_s)) == pytest.approx(theta + 1.02 * full, abs=1e-9)
    assert min(near.alpha_rad_s2) >= -DEMO.decel_rad_s2 * (1 + 1e-12)
    with pytest.raises(ModelError, match="nearer than braking allows"):
        stop_at_position(path, t, DEMO, theta + 0.9 * full)
    with pytest.raises(ModelError, match="turns forward only"):
        stop_at_position(at_rest(3.0), 0.0, DEMO, 2.0)
    assert nearest_stop(path, t, DEMO, 1.0) >= theta + w * w / (2 * INDEX_DECEL_SHARE
                                                                 * DEMO.decel_rad_s2)  # fmt: skip
