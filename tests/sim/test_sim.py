"""The simulated stand: the closed form to the quantisation step, each effect doing
what it should and nothing else, determinism, shipped scenes."""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np
import pytest
from fit import fit
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scenes import BASE, SCALE, run, scene
from strategies import log_uniform, stands, unbalances

from stand.config import validate
from stand.core import (
    StandParameters,
    forward,
    rpm_to_rad_s,
    unbalance_from_polar,
    unbalance_to_polar,
)
from stand.drivers.v1.build import rebuild
from stand.drivers.v1.codec import decode
from stand.drivers.v1.protocol import SAMPLES_BASE
from stand.errors import ConfigError
from stand.sim import Scene, load_scene, shipped_scenes, simulate


def A_true(sc: Scene, w: float | None = None) -> np.ndarray:
    p = sc.config().parameters()
    U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
    return np.asarray(forward(p, float(rpm_to_rad_s(sc.run.rpm)) if w is None else w, U))


def test_no_effects_reproduces_the_closed_form_to_the_quantisation_step() -> None:
    sc = scene()
    sim = run(sc)
    r = rebuild(sim.frames)
    w = float(rpm_to_rad_s(900.0))
    A = A_true(sc)
    for i in (1, 2):
        s = r.nodes[i]
        t = np.asarray(s.index) / 4000.0
        exact = (A[i - 1] * np.exp(1j * w * t)).real
        assert s.accel_m_s2 is not None
        # rounding to a count: at most half a count (plus float noise of the sum)
        assert np.max(np.abs(s.accel_m_s2 - exact)) <= 0.5 * SCALE * (1 + 1e-9)
    assert sim.physics == "closed_form" and sim.nfev == 0
    assert r.warnings == () and r.nodes[1].marks == 45


def test_same_scene_and_seed_give_identical_frames_and_another_seed_does_not() -> None:
    effects = {"noise": {"rms_m_s2": 0.01}, "lost_frames": {"probability": 0.01}}
    a, b = run(scene(effects)), run(scene(effects))
    for name in ("t_s", "can_id", "dlc", "data", "flags"):
        assert np.array_equal(getattr(a.frames, name), getattr(b.frames, name))
    c = run(scene(effects, run={"seed": 8}))
    assert len(c.frames) != len(a.frames) or not np.array_equal(c.frames.data, a.frames.data)


def test_an_effect_not_named_changes_no_byte_of_the_others() -> None:
    """Adding lost frames removes frames and changes nothing in those that remain."""
    noisy = run(scene({"noise": {"rms_m_s2": 0.01}}))
    lossy = run(scene({"noise": {"rms_m_s2": 0.01}, "lost_frames": {"probability": 0.05}}))
    ref = {(float(t), bytes(d)) for t, d in zip(noisy.frames.t_s, noisy.frames.data, strict=True)}
    got = {(float(t), bytes(d)) for t, d in zip(lossy.frames.t_s, lossy.frames.data, strict=True)}
    assert got < ref
    assert abs(1 - len(got) / len(ref) - 0.05) < 0.01  # 5 % lost, within 1 point (8,000 frames)


def test_noise_has_the_rms_asked_for_and_leaves_the_edges() -> None:
    clean = rebuild(run(scene()).frames)
    sc = scene({"noise": {"density_m_s2_rthz": 0.002}})
    noisy = rebuild(run(sc).frames)
    want = 0.002 * math.sqrt(4000 / 2)
    for i in (1, 2):
        diff = noisy.nodes[i].accel_m_s2 - clean.nodes[i].accel_m_s2  # type: ignore[operator]
        # 12,000 samples: the rms estimate is within 2 % (5 sigma is 3.2 %; quantisation adds
        # SCALE^2/6 at most to the variance, 0.1 % here)
        assert np.std(diff) == pytest.approx(want, rel=0.03)
        assert np.array_equal(noisy.nodes[i].mark_position, clean.nodes[i].mark_position)


def test_sensor_gain_and_delay_scale_and_turn_the_1x_phasor() -> None:
    sc = scene({"sensor": {"gain": [1.1, 0.9], "delay_s": [0.0, 0.001]}})
    r = rebuild(run(sc).frames)
    w = float(rpm_to_rad_s(900.0))
    A = A_true(sc)
    want = [1.1 * A[0], 0.9 * A[1] * np.exp(-1j * w * 0.001)]
    for i in (1, 2):
        got = fit(r.nodes[i])[1]
        # quantisation noise only: its 1x error is ~ SCALE/sqrt(12 N) ~ 3e-7 m/s^2
        assert abs(got - want[i - 1]) < 1e-5 * abs(want[i - 1])


def test_clock_error_and_offset_move_each_node_on_its_own_clock() -> None:
    sc = scene({"clock": {"ppm": [200.0, -100.0], "offset_s": [0.0, 0.37]}})
    sim = run(sc)
    r = rebuild(sim.frames)
    for i, ppm in ((1, 200.0), (2, -100.0)):
        s = r.nodes[i]
        # the node counts its own samples: it sees the shaft at rpm / (1 + ppm)
        assert s.rpm() == pytest.approx(900.0 / (1 + ppm * 1e-6), rel=1e-9)
        assert abs(fit(s)[1] - A_true(sc)[i - 1]) < 1e-4 * abs(A_true(sc)[i - 1])
    first = [sim.frames.t_s[sim.frames.can_id == SAMPLES_BASE + n][0] for n in (1, 2)]
    assert first[1] - first[0] == pytest.approx(0.37 + 2 / 3999.6 - 2 / 4000.8, abs=1e-12)


def test_speed_ripple_and_drift_change_the_edge_spacing_as_asked() -> None:
    sc = scene(
        {"speed": {"ripple_pct": 2.0, "ripple_hz": 0.5, "drift_pct_per_s": 1.0}},
        run={"seconds": 4.0},
    )
    sim = run(sc)
    s = rebuild(sim.frames).nodes[1]
    t_mid = (s.mark_position[1:] + s.mark_position[:-1]) / 2 / 4000
    rpm = 60 * 4000 / np.diff(s.mark_position)
    model = 900 * (1 + 0.02 * np.sin(2 * math.pi * 0.5 * t_mid) + 0.01 * t_mid)
    # a revolution's mean speed against the speed at its middle: the sine's curvature over
    # one revolution (1/15 s) is below 1e-4 of the speed
    assert np.max(np.abs(rpm / model - 1)) < 2e-4
    clean = rebuild(run(scene()).frames).nodes[1]
    assert not np.array_equal(s.mark_position[:10], clean.mark_position[:10])


def test_edge_jitter_moves_only_the_edges() -> None:
    clean = rebuild(run(scene()).frames).nodes[1]
    jit = rebuild(run(scene({"edge_jitter": {"rms_s": 20e-6}})).frames).nodes[1]
    d = (jit.mark_position - clean.mark_position) / 4000
    assert np.std(d) == pytest.approx(20e-6, rel=0.35)  # 45 edges: the estimate's spread ~ 11 %
    assert np.array_equal(jit.accel_m_s2, clean.accel_m_s2)  # type: ignore[arg-type]


def test_lost_frames_single_and_bursts_keep_true_indices() -> None:
    sim = run(
        scene({"lost_frames": {"probability": 0.02, "bursts_per_s": 2.0, "burst_frames": 25}})
    )
    clean = rebuild(run(scene()).frames).nodes[1]
    s = rebuild(sim.frames).nodes[1]
    assert s.lost_frames > 0.02 * clean.frames
    present = np.isin(clean.index, np.asarray(s.index))
    assert np.array_equal(clean.accel_m_s2[present], s.accel_m_s2)  # type: ignore[index]


def test_invalid_samples_and_clipping_and_their_flags() -> None:
    sc = scene({"invalid": {"probability": 0.01}, "clipping": {"range_m_s2": 2.0}})
    r = rebuild(run(sc).frames)
    s1 = r.nodes[1]
    assert s1.invalid_samples == pytest.approx(0.01 * s1.samples, rel=0.3)
    assert np.max(np.abs(s1.accel_m_s2)) <= 2.0 + 0.5 * SCALE  # type: ignore[arg-type]
    assert s1.flags == ("overrange", "sensor_fault")  # node 1 peaks at 2.39 m/s^2
    assert "overrange" not in r.nodes[2].flags  # node 2 stays below 2 m/s^2 (1.64)


def test_overrange_of_the_count_range_clips_and_flags() -> None:
    s = rebuild(run(scene(nodes={"scale_um_s2": 50})).frames).nodes[1]  # 2.39 m/s^2 > 1.64
    assert s.accel_m_s2.max() == pytest.approx(32767 * 50e-6)  # type: ignore[union-attr]
    assert "overrange" in s.flags


def test_harmonics_appear_at_2x_and_3x_and_leave_1x() -> None:
    sc = scene(
        {
            "harmonics": {
                "x2_m_s2": [0.5, 0.2],
                "x2_phase_deg": [10.0, 20.0],
                "x3_m_s2": 0.3,
                "x3_phase_deg": 40.0,
            }
        }
    )
    r = rebuild(run(sc).frames)
    for i, (h2, p2) in ((1, (0.5, 10.0)), (2, (0.2, 20.0))):
        f = fit(r.nodes[i])
        assert abs(f[2] - h2 * np.exp(1j * math.radians(p2))) < 1e-5
        assert abs(f[3] - 0.3 * np.exp(1j * math.radians(40.0))) < 1e-5
        assert abs(f[1] - A_true(sc)[i - 1]) < 1e-5


def test_a_neighbour_adds_its_own_frequency_and_leaves_1x() -> None:
    sc = scene({"neighbour": {"rpm": 920.0, "amplitude_m_s2": 0.8}}, run={"seconds": 6.0})
    r = rebuild(run(sc).frames)
    s = r.nodes[1]
    spec = np.abs(np.fft.rfft(s.accel_m_s2))  # type: ignore[arg-type]
    freqs = np.fft.rfftfreq(len(s.accel_m_s2), 1 / 4000)  # type: ignore[arg-type]
    near = (freqs > 14.0) & (freqs < 16.5)
    peaks = freqs[near][np.argsort(spec[near])[-2:]]
    assert sorted(np.round(peaks, 1)) == [15.0, pytest.approx(15.3, abs=0.2)]
    f = fit(s, extra_hz=920 / 60)
    assert abs(f[1] - A_true(sc)[0]) < 1e-4


def test_run_up_starts_at_rest_and_settles_to_the_closed_form() -> None:
    sc = scene({"run_up": {"ramp_s": 2.0}}, stand={"H1": 300.0, "H2": 300.0}, run={"seconds": 9.0})
    sim = run(sc)
    assert sim.physics == "integrate" and sim.nfev > 0
    s = rebuild(sim.frames).nodes[1]
    assert np.max(np.abs(s.accel_m_s2[:400])) < 0.01  # type: ignore[index]  # 0.1 s: at rest
    rpm = 60 * 4000 / np.diff(s.mark_position)
    assert rpm[0] < 300 and rpm[-1] == pytest.approx(900.0, rel=1e-6)
    # the last 3 s: transients have decayed (damping time ~ 2 M / H ~ 0.1 s for the supports)
    tail = np.asarray(s.index) >= 6 * 4000
    tail_stream = s.take(tail)
    got = fit(tail_stream)[1]
    assert abs(got - A_true(sc)[0]) < 2e-4 * abs(A_true(sc)[0])


def test_a_coast_down_is_its_speeds_exact_integral_and_stands_at_the_end() -> None:
    """Run up in 2 s, 1 s at the top, braked to standstill in 3 s: the speed and the angle
    continuous at each joint (within 1e-9 of them across 2e-9 s), ``omega`` the slope of
    ``theta`` and ``alpha`` of ``omega`` between the joints (central differences over 1 ms
    are exact on these quadratic pieces but for rounding: 1e-7 relative), and nothing moves
    once it stands."""
    from stand.sim.physics import SceneSpeed

    w0 = 900 * math.pi / 30
    sp = SceneSpeed(w0, 8.0, ramp_s=2.0, coast_at_s=3.0, coast_s=3.0)
    assert sp.omega(np.array([2.0, 3.0, 4.5, 6.0, 7.0])).tolist() == pytest.approx(
        [w0, w0, w0 / 2, 0.0, 0.0], abs=1e-12
    )
    for joint in (2.0, 3.0, 6.0):
        for law in (sp.omega, sp.theta):
            assert abs(law(joint + 1e-9) - law(joint - 1e-9)) < 1e-9 * w0 * 8
    t = np.random.default_rng(0).uniform(0.01, 7.99, 500)
    t = t[np.min(np.abs(t[:, None] - np.array([2.0, 3.0, 6.0])), axis=1) > 2e-3]
    h = 1e-3
    slope = (sp.theta(t + h) - sp.theta(t - h)) / (2 * h)
    np.testing.assert_allclose(slope, sp.omega(t), rtol=1e-7, atol=1e-7 * w0)
    slope = (sp.omega(t + h) - sp.omega(t - h)) / (2 * h)
    np.testing.assert_allclose(slope, sp.alpha(t), rtol=1e-7, atol=1e-7 * w0)
    assert sp.theta(7.9) == sp.theta(6.0) and sp.alpha(6.5) == 0.0


def test_a_torque_limited_run_up_keeps_its_power_above_the_base_speed() -> None:
    """Base speed 300 of 900 rpm, 6 s: a constant acceleration to 300 rpm, then ``w w'``
    constant (constant power) to 900 rpm at 6 s; the speed and angle continuous at the
    joints, ``omega`` the slope of ``theta`` and ``alpha`` of ``omega`` (central
    differences over 1 ms: the square root's curvature costs at most 1e-6 relative), and
    the hold after it turns at 900 rpm from where the ramp ended."""
    from stand.sim.physics import SceneSpeed

    w0, wb = 900 * math.pi / 30, 300 * math.pi / 30
    sp = SceneSpeed(w0, 10.0, ramp_s=6.0, base_omega_rad_s=wb)
    a = (wb * wb + w0 * w0) / (2 * wb * 6.0)
    tb = wb / a
    assert sp.omega(np.array([tb, 6.0, 8.0])).tolist() == pytest.approx([wb, w0, w0], rel=1e-12)
    for joint in (tb, 6.0):
        for law in (sp.omega, sp.theta):
            assert abs(law(joint + 1e-9) - law(joint - 1e-9)) < 1e-9 * w0 * 10
    t = np.random.default_rng(1).uniform(0.01, 9.99, 500)
    t = t[np.min(np.abs(t[:, None] - np.array([tb, 6.0])), axis=1) > 2e-3]
    h = 1e-3
    slope = (sp.theta(t + h) - sp.theta(t - h)) / (2 * h)
    np.testing.assert_allclose(slope, sp.omega(t), rtol=1e-6, atol=1e-7 * w0)
    slope = (sp.omega(t + h) - sp.omega(t - h)) / (2 * h)
    np.testing.assert_allclose(slope, sp.alpha(t), rtol=1e-6, atol=1e-7 * w0)
    above = (t > tb) & (t < 6.0)
    np.testing.assert_allclose(sp.omega(t[above]) * sp.alpha(t[above]), a * wb, rtol=1e-12)


@pytest.mark.parametrize("effect", ["friction", "clearance"])
def test_nonlinear_supports_at_zero_are_the_linear_stand(effect: str) -> None:
    zero = {"friction": {"force_n": 0.0}, "clearance": {"gap_m": 0.0}}[effect]
    sc = scene(
        {effect: zero}, stand={"H1": 100.0, "H2": 100.0}, run={"seconds": 2.0, "settle_s": 1.0}
    )
    sim = run(sc)
    assert sim.physics == "integrate"
    got = fit(rebuild(sim.frames).nodes[1])[1]
    assert abs(got - A_true(sc)[0]) < 1e-4 * abs(A_true(sc)[0])


@pytest.mark.parametrize(
    ("effect", "values"),
    [("friction", {"force_n": 30.0}), ("clearance", {"gap_m": 2e-5})],
)
def test_nonlinear_supports_change_the_response(effect: str, values: dict[str, float]) -> None:
    sc = scene(
        {effect: values}, stand={"H1": 100.0, "H2": 100.0}, run={"seconds": 2.0, "settle_s": 2.0}
    )
    s = rebuild(run(sc).frames).nodes[1]
    f = fit(s)
    lin = A_true(sc)[0]
    assert abs(f[1] - lin) > 0.01 * abs(lin)  # the nonlinearity moves the 1x reading
    assert abs(f[3]) > 1e-3  # and makes odd harmonics


def test_a_bus_dropout_removes_every_frame_in_its_window() -> None:
    sim = run(scene({"dropout": {"at_s": 1.0, "seconds": 0.6}}))
    t = sim.frames.t_s
    assert not np.any((t >= 1.0) & (t < 1.6))
    r = rebuild(sim.frames)
    assert r.nodes[1].segments == 1 and r.nodes[1].lost_frames > 700  # 0.6 s of 1333 frames/s


def test_a_closed_form_scene_cannot_ask_for_a_transient(tmp_path: Any) -> None:
    path = tmp_path / "s.toml"
    path.write_text(
        "\n".join(
            f"[{k}]\n" + "\n".join(f"{kk} = {vv!r}" for kk, vv in v.items())
            for k, v in BASE.items()
            if k != "unbalance"
        )
        + "\n[unbalance]\nplane1 = { g_mm = 1.0, angle_deg = 0.0 }\n"
        "plane2 = { g_mm = 1.0, angle_deg = 0.0 }\n[effects.run_up]\nramp_s = 1.0\n".replace(
            "[run]", "[run]"
        )
    )
    text = path.read_text().replace("seed = 7", 'seed = 7\nphysics = "closed_form"')
    path.write_text(text)
    with pytest.raises(ConfigError, match=r"\[run\.physics\]"):
        load_scene(path)


def test_scene_errors_name_the_file_and_key(tmp_path: Any) -> None:
    with pytest.raises(ConfigError, match="no such scene"):
        load_scene("nonexistent-scene")
    bad = copy.deepcopy(BASE)
    bad["effects"] = {"noise": {"rms_m_s2": 0.1, "density_m_s2_rthz": 0.1}}
    with pytest.raises(ConfigError, match=r"\[effects\.noise\].*one of them"):
        validate(Scene, bad, "<x>")
    bad["effects"] = {"sensor": {"gain": [1.0, 2.0, 3.0]}}
    with pytest.raises(ConfigError, match="one per node"):
        validate(Scene, bad, "<x>")
    bad["effects"] = {"smoke": {}}
    with pytest.raises(ConfigError, match=r"\[effects\.smoke\]: unknown key"):
        validate(Scene, bad, "<x>")


@pytest.mark.parametrize("name", sorted(shipped_scenes()))
def test_shipped_scenes_run_and_give_their_phasors_back(name: str) -> None:
    sc, p, _ = load_scene(name)
    sim = simulate(sc, p)
    if sc.nodes.protocol != "v1":  # a scan module's or CANopen's frames: their decoder
        from stand.solve.acquisition import acquisition_of

        r = acquisition_of(sc.config(), None).decode(sim.frames)
        assert sorted(r.nodes) == [1, 2] and r.unknown_frames == 0
        for i in (1, 2):
            got = fit(r.nodes[i], sc.stand.reference_angle_deg)[1]
            want = sim.truth["A_m_s2"][i - 1]  # type: ignore[index]
            assert abs(got - want) < 2e-3 * abs(want), (name, i)
        return
    r = rebuild(sim.frames)
    assert sorted(r.nodes) == [1, 2] and r.bad_frames == 0
    if sc.effects.sweeps or sc.effects.autobalancer:
        return  # its steady tail is checked in test_run_up_starts_at_rest..., a sweep's
        # modes in tests/field/test_runup.py, the balls' settled state in test_balls_scene.py
    for i in (1, 2):
        got = fit(r.nodes[i], sc.stand.reference_angle_deg)[1]
        want = sim.truth["A_m_s2"][i - 1]  # type: ignore[index]
        assert abs(got - want) < 2e-3 * abs(want), (name, i)
    assert len(decode(sim.frames).samples.frame) == sum(n.frames for n in r.nodes.values())


@settings(max_examples=100, deadline=None)
@given(stands(), log_uniform(60.0, 30000.0), st.data())
def test_any_stand_from_grams_to_tonnes_reaches_the_frames_within_half_a_count(
    p: StandParameters, rpm: float, data: st.DataObject
) -> None:
    """Scene -> physics -> counts -> frames -> decoded streams, against the closed form.

    The tolerance is half a count (rounding) plus 1e-9 of the amplitude for the
    arithmetic between (theta = w t at t ~ 1e4 samples, cos of it: ~1e-12 rad).
    """
    U = data.draw(unbalances(p))
    w = float(rpm_to_rad_s(rpm))
    A = np.asarray(forward(p, w, U))
    peak = float(np.max(np.abs(A)))
    scale_um = math.ceil(peak / 30000 * 1e6)
    assume(1 <= scale_um < 65536 and peak > 1e-3)  # what 16-bit nodes can represent
    q, phi = unbalance_to_polar(U)
    values = {k: getattr(p, k) for k in ("M1", "M2", "C1", "C2", "H1", "H2")}
    data_ = copy.deepcopy(BASE)
    data_["stand"].update(values)
    data_["rotor"] = {k: getattr(p, k) for k in ("M3", "J3", "a", "b", "c", "d", "R1", "R2")}
    data_["run"] = {"rpm": rpm, "seconds": max(0.25, 3 * 60 / rpm)}
    data_["unbalance"] = {
        f"plane{i + 1}": {"g_mm": float(q[i]) * 1e6, "angle_deg": float(phi[i])} for i in range(2)
    }
    data_["nodes"]["scale_um_s2"] = scale_um
    sc = validate(Scene, data_, "<hypothesis>")
    r = rebuild(simulate(sc, p).frames)
    for i in (1, 2):
        s = r.nodes[i]
        exact = (A[i - 1] * np.exp(1j * w * np.asarray(s.index) / 4000.0)).real
        err = np.max(np.abs(s.accel_m_s2 - exact))  # type: ignore[operator]
        assert err <= 0.5 * scale_um * 1e-6 * (1 + 1e-9) + 1e-9 * peak
