"""Faults the data reveals are refused or flagged: each check, its failing input and its twin.

The demo run (5000 g mm at 30 deg, 3000 g mm at 200 deg) with one fault put
into its frames; the twin is the same run without it.
"""

from __future__ import annotations

import functools
import json
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stand.cli import main
from stand.drivers.frames import Frames
from stand.drivers.v1.build import rebuild
from stand.drivers.v1.protocol import SAMPLES_BASE, STATUS_BASE
from stand.errors import MeasurementError, SensorFaultError
from stand.measuring.measure import measure
from stand.sim import load_scene, simulate

TRUTH = np.array([5000e-6 * np.exp(-1j * np.radians(30)), 3000e-6 * np.exp(-1j * np.radians(200))])
"""The demo scene's unbalance [kg m]: 5000 g mm at 30 deg, 3000 g mm at 200 deg."""


@functools.cache
def _demo() -> tuple[Frames, object]:
    sc, p, _ = load_scene("demo")
    return simulate(sc, p).frames, p


def _copy(run: Path, to: Path) -> Path:
    """A copy of a run file to damage (the session's demo run stays as it is)."""
    shutil.copy(run, to)
    return to


def _with(change: str) -> Frames:
    """The demo's frames with one fault in node 2's frames."""
    f, _ = _demo()
    data = f.data.copy()
    samples = f.can_id == SAMPLES_BASE + 2
    status = np.flatnonzero(f.can_id == STATUS_BASE + 2)
    if change == "dead":
        data[samples, 2:8] = 0
    elif change == "stuck":
        data[samples, 2:8] = np.array([0x10, 0x00] * 3, np.uint8)  # 16 counts, always
    elif change == "scale 0":
        data[status, 2:4] = 0
    elif change == "rate 4096":
        data[status, 0:2] = np.frombuffer(np.uint16(4096).tobytes(), np.uint8)
    elif change == "first status 8608":
        data[status[0], 0:2] = np.frombuffer(np.uint16(8608).tobytes(), np.uint8)
    return Frames(f.t_s, f.can_id, f.dlc, data, f.flags)


@pytest.mark.parametrize(
    ("fault", "says"),
    [
        ("dead", "node 2: the sensor reads a constant 0 counts"),
        ("stuck", "node 2: the sensor reads a constant 16 counts"),
        ("scale 0", "node 2: its STATUS scale is 0"),
        ("rate 4096", "nodes 1 and 2 see one shaft at different speeds"),
    ],
)
def test_a_fault_is_refused_naming_the_node_and_the_figure(fault: str, says: str) -> None:
    _, p = _demo()
    with pytest.raises(SensorFaultError, match=says):  # a fault: live stops at once on it
        measure(rebuild(_with(fault)), p)  # type: ignore[arg-type]


def test_too_little_data_yet_is_not_a_fault() -> None:
    """Live waits out "not yet" (too few edges): a plain MeasurementError, not a fault."""
    f, p = _demo()
    first = f.t_s < 0.1  # 1.5 revolutions at 900 rpm
    short = Frames(f.t_s[first], f.can_id[first], f.dlc[first], f.data[first], f.flags[first])
    with pytest.raises(MeasurementError, match="reference edges") as info:
        measure(rebuild(short), p)  # type: ignore[arg-type]
    assert not isinstance(info.value, SensorFaultError)


def test_the_twin_without_a_fault_solves_to_the_truth() -> None:
    f, p = _demo()
    m = measure(rebuild(f), p)  # type: ignore[arg-type]
    assert abs(abs(m.solution.U_kg_m[0]) - 5000e-6) <= m.radius95_kg_m[0]


def test_a_corrupt_first_status_is_outvoted_by_the_others() -> None:
    """Node 2's first STATUS says 8608 Hz, the next seven 4000: the rate is 4000."""
    _, p = _demo()
    streams = rebuild(_with("first status 8608"))
    assert streams.nodes[2].rate_hz == 4000
    m = measure(streams, p)  # type: ignore[arg-type]
    assert abs(abs(m.solution.U_kg_m[0]) - 5000e-6) <= m.radius95_kg_m[0]
    assert any(w.code == "rate_changed" for w in streams.warnings)  # and it is said


def test_the_clock_tolerance_is_configurable() -> None:
    """4096 against 4000 Hz is 2.4 %: accepted when the tolerance allows it (and then wrong)."""
    _, p = _demo()
    m = measure(rebuild(_with("rate 4096")), p, clock_tolerance=0.05)  # type: ignore[arg-type]
    assert m.omega_rad_s > 0


@pytest.mark.parametrize("unbalanced", [True, False])
def test_3x_is_judged_only_against_a_1x_that_is_there(unbalanced: bool) -> None:
    """A strong 3x warns; after a perfect correction (1x in the noise) it does not."""
    sc, p, _ = load_scene("demo")
    data = sc.model_dump()
    data["effects"]["harmonics"] = {"x3_m_s2": 0.5}
    if not unbalanced:
        data["unbalance"] = {"plane1": {"g_mm": 0.0, "angle_deg": 0.0},
                             "plane2": {"g_mm": 0.0, "angle_deg": 0.0}}  # fmt: skip
    scene = type(sc).model_validate(data, strict=False)
    m = measure(rebuild(simulate(scene, p).frames), p)
    assert any(w.code == "strong_3x" for w in m.warnings) is unbalanced


@pytest.mark.parametrize("g_mm", [0.0, 5000.0])
def test_at_the_noise_floor_no_correction_is_prescribed(g_mm: float) -> None:
    """A plane whose unbalance is inside its own interval gets no weight and no angle."""
    from stand.solve import Provenance, SolveOptions, build_result, measure_streams, to_json

    sc, p, _ = load_scene("demo")
    data = sc.model_dump()
    data["unbalance"]["plane1"] = {"g_mm": g_mm, "angle_deg": 30.0}
    scene = type(sc).model_validate(data, strict=False)
    cfg = scene.config()
    m = measure_streams(rebuild(simulate(scene, p).frames), cfg, p, SolveOptions())
    r = build_result(m, cfg, p, provenance=Provenance("t", None, "", ""))
    c1, c2 = to_json(r)["corrections"]
    assert c1["within_noise"] is (g_mm == 0.0) and c2["within_noise"] is False
    assert (c1["weights"] == []) is (g_mm == 0.0) and c2["weights"]
    assert any(w.code == "within_noise" for w in r.warnings) is (g_mm == 0.0)


def test_a_stored_config_altered_by_one_character_is_refused(
    demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """C1 45000 -> 95000 in the stored config: refused, naming the file (twin: untouched)."""
    run = _copy(demo_run, tmp_path / "altered.h5")
    with h5py.File(run, "a") as f:
        text = str(f.attrs["config_toml"])
        assert "C1 = 45000.0" in text
        f.attrs["config_toml"] = text.replace("C1 = 45000.0", "C1 = 95000.0")
    assert main(["solve", str(demo_run)]) == 0
    capsys.readouterr()
    assert main(["solve", str(run)]) == 2
    err = capsys.readouterr().err
    assert str(run) in err and "does not match its SHA-256 digest" in err


def test_a_damaged_block_of_frames_fails_its_checksum(
    demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = _copy(demo_run, tmp_path / "damaged.h5")
    with h5py.File(run, "r") as f:
        info = f["frames/data"].id.get_chunk_info(0)
    with run.open("r+b") as handle:  # flip one byte inside the first chunk of payloads
        handle.seek(info.byte_offset + 100)
        byte = handle.read(1)
        handle.seek(info.byte_offset + 100)
        handle.write(bytes([byte[0] ^ 0x01]))
    assert main(["solve", str(run)]) == 2
    err = capsys.readouterr().err
    assert str(run) in err and "fails its Fletcher32 checksum" in err


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), None])
def test_a_run_with_timestamps_that_are_no_numbers_is_refused(
    demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], bad: float | None
) -> None:
    """NaN host timestamps used to pass into the JSON; the twin (None) is the run as made."""
    run = _copy(demo_run, tmp_path / "stamps.h5")
    if bad is not None:
        with h5py.File(run, "a") as f:
            t = f["frames/t_s"][:]
            t[7:9] = bad
            f["frames/t_s"][:] = t
    code = main(["solve", str(run), "--json"])
    out, err = capsys.readouterr()
    if bad is None:
        assert code == 0 and json.loads(out, parse_constant=pytest.fail)
    else:
        assert code == 2 and out == ""
        assert f"{run}: frame 7: its timestamp is {bad}, not a number of seconds" in err


@pytest.mark.parametrize(("rpm", "refused"), [(45_000.0, True), (30_000.0, False)])
def test_a_speed_beyond_the_sample_rate_s_band_is_refused(rpm: float, refused: bool) -> None:
    """At 4 kHz, 3x passes half the sample rate above 40,000 rpm."""
    sc, p, _ = load_scene("demo")
    data = sc.model_dump()
    data["run"].update(rpm=rpm, seconds=2.0)
    for plane in (
        "plane1",
        "plane2",
    ):  # a small unbalance: at these speeds the sensor stays in range
        data["unbalance"][plane]["g_mm"] /= 3000.0
    scene = type(sc).model_validate(data, strict=False)
    streams = rebuild(simulate(scene, p).frames)
    if refused:
        with pytest.raises(MeasurementError, match=r"node 1: the shaft turns at 45000 rpm"):
            measure(streams, p)
    else:
        assert measure(streams, p).omega_rad_s > 0


def _mark_corrupted(k: int, byte: int, value: int) -> Frames:
    """The demo's frames with byte ``byte`` of node 1's ``k``-th MARK frame set to ``value``."""
    from stand.drivers.v1.protocol import MARK_BASE

    f, _ = _demo()
    data = f.data.copy()
    marks = np.flatnonzero(f.can_id == MARK_BASE + 1)
    data[marks[k], byte] = value
    return Frames(f.t_s, f.can_id, f.dlc, data, f.flags)


@pytest.mark.parametrize(("byte", "what"), [(5, "revolution counter"), (1, "sequence")])
def test_a_corrupt_mark_is_dropped_and_counted_and_the_answer_holds(byte: int, what: str) -> None:
    """One MARK frame with a garbage counter (it gave 1237.6 or 310.3 g mm for 5000 before)."""
    _, p = _demo()
    streams = rebuild(_mark_corrupted(40, byte, 0x5A))
    assert any(w.code == "edges_dropped" for w in streams.warnings), what
    m = measure(streams, p)  # type: ignore[arg-type]
    assert np.all(np.abs(m.solution.U_kg_m - TRUTH) <= 2 * m.radius95_kg_m)


@settings(max_examples=60, deadline=None)
@given(k=st.integers(0, 110), byte=st.integers(0, 7), value=st.integers(0, 255))
def test_any_single_byte_of_a_mark_gives_a_refusal_or_an_answer_near_the_truth(
    k: int, byte: int, value: int
) -> None:
    """A single corrupt MARK byte: refused, or within twice the 95 % radius of the truth.

    (Twice: the 95 % circle itself misses one run in twenty; a slot or fraction
    byte moves one edge by under a sample, which is jitter, not a fault.)
    """
    _, p = _demo()
    try:
        m = measure(rebuild(_mark_corrupted(k, byte, value)), p)  # type: ignore[arg-type]
    except MeasurementError:
        return
    assert np.all(np.abs(m.solution.U_kg_m - TRUTH) <= 2 * m.radius95_kg_m + 1e-9)


@pytest.mark.parametrize(
    ("k", "clip", "refused"),
    [(2.0, None, True), (1.0, 2.0, True), (1.0, None, False), (1.0, 3.0, False)],
)
def test_a_saturated_sensor_is_refused(k: float, clip: float | None, refused: bool) -> None:
    """Twice the demo's unbalance overruns the counts (it read 8119.9 for 10,000); a sensor
    range of 2 m/s^2 clips node 1 (2.39 m/s^2); the demo, and a range above its peaks, pass."""
    sc, p, _ = load_scene("demo")
    data = sc.model_dump()
    data["unbalance"] = {"plane1": {"g_mm": 5000.0 * k, "angle_deg": 30.0},
                         "plane2": {"g_mm": 3000.0 * k, "angle_deg": 200.0}}  # fmt: skip
    if clip is not None:
        data["effects"]["clipping"] = {"range_m_s2": clip}
    streams = rebuild(simulate(type(sc).model_validate(data, strict=False), p).frames)
    if refused:
        with pytest.raises(SensorFaultError, match=r"node 1: the sensor saturates: \d+ samples"):
            measure(streams, p)
    else:
        m = measure(streams, p)
        assert np.all(np.abs(m.solution.U_kg_m - k * TRUTH) <= m.radius95_kg_m)


@settings(max_examples=40, deadline=None)
@given(
    sigma=st.floats(0.01, 20.0),
    period=st.floats(20.0, 4000.0),
    seed=st.integers(0, 2**32 - 1),
)
def test_the_edge_jitter_estimate_finds_the_jitter_put_in(
    sigma: float, period: float, seed: int
) -> None:
    """2000 edges with Gaussian jitter of ``sigma`` samples, a speed drifting by 1 %: the
    estimate within 15 % (the MAD of 2000 correlated second differences scatters by
    about 4 % rms; 15 % is over 3.5 of those)."""
    from stand.core.dsp import edge_jitter

    rng = np.random.default_rng(seed)
    k = np.arange(2000)
    x = period * (k + 0.005 * k**2 / len(k)) + rng.normal(0, sigma, len(k))
    assert edge_jitter(x, k) == pytest.approx(sigma, rel=0.15)
    assert edge_jitter(period * k, k) < 1e-9 * period  # no jitter, steady: none found


@pytest.mark.parametrize("rms_s", [0.0, 5e-5, 2.5e-4])
def test_edge_jitter_widens_the_interval_to_hold_the_truth(rms_s: float) -> None:
    """Jitter of the reference edges (0.2 and 1 sample rms at 4 kHz) turns both phasors
    together; before it entered the uncertainty, 4 of 40 seeds fell outside plane 1's
    circle at 5e-5 s, up to 1.5 times its radius.  Six seeds each: all inside."""
    sc, p, _ = load_scene("demo")
    for seed in range(6):
        data = sc.model_dump()
        data["run"]["seed"] = seed
        if rms_s:
            data["effects"]["edge_jitter"] = {"rms_s": rms_s}
        scene = type(sc).model_validate(data, strict=False)
        m = measure(rebuild(simulate(scene, p).frames), p)
        assert np.all(np.abs(m.solution.U_kg_m - TRUTH) <= m.radius95_kg_m)
        assert any(w.code == "edge_jitter" for w in m.warnings) == (rms_s > 0)


def test_a_3x_ratio_of_two_noise_levels_never_warns(tmp_path: Path) -> None:
    """A rotor balanced to about 1 g mm per plane, only noise: the 3x and the 1x are both
    at the noise's level, their ratio anything (13 to 88 % in 3 of 8 seeds before it was
    judged with its interval); no seed of 12 warns now."""
    sc, p, _ = load_scene("demo")
    data = sc.model_dump()
    data["unbalance"] = {"plane1": {"g_mm": 1.0, "angle_deg": 30.0},
                         "plane2": {"g_mm": 1.0, "angle_deg": 200.0}}  # fmt: skip
    for seed in range(1, 13):
        data["run"]["seed"] = seed
        scene = type(sc).model_validate(data, strict=False)
        m = measure(rebuild(simulate(scene, p).frames), p)
        assert not any(w.code == "strong_3x" for w in m.warnings), seed
