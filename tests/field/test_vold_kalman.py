"""The Vold-Kalman filter (``stand runup --vold-kalman HZ``): its passband and noise as its
transfer function says, a lost sample bridged exactly, the steady 1x as today's measurement gives
it, a run-up's modes as the revolution blocks read them, and a filter too narrow for the
sweep said."""

from __future__ import annotations

import cmath
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from stand.cli import main
from stand.core import vold_kalman as vk

RATE = 4000.0


def _json(args: list[str], capsys: pytest.CaptureFixture[str]) -> dict:
    capsys.readouterr()
    assert main([*args, "--json"]) == 0
    out: dict = json.loads(capsys.readouterr().out)
    return out


@settings(max_examples=20, deadline=None)
@given(st.floats(0.3, 20.0), st.floats(-0.45, 0.45))
def test_an_envelope_changing_at_the_half_power_frequency_keeps_half_its_power(
    half_power_hz: float, share: float
) -> None:
    """A 1x at 15 Hz whose envelope beats at ``f`` (the constant part 1, the beat 0.3):
    far from the record's ends the beat comes through with ``|H(f)|``, ``1 / sqrt(2)`` of
    its amplitude at the half-power frequency (within 2 %: the ends' remains, and the
    average over a stretch that is no whole number of beats), and the constant part whole
    (within 1e-3)."""
    f = half_power_hz * (1 + share) if abs(share) > 0.05 else half_power_hz
    n = int(RATE * max(8.0, 40 / half_power_hz))
    t = np.arange(n) / RATE
    theta = 2 * math.pi * 15.0 * t
    A = 1.0 + 0.3 * np.exp(2j * math.pi * f * t)
    y = (A * np.exp(1j * theta)).real
    got = vk.envelope(y, theta, np.ones(n), vk.weight_for(half_power_hz, RATE))
    mid = slice(n // 4, 3 * n // 4)
    beat = np.mean((got[mid] - 1.0) * np.exp(-2j * math.pi * f * t[mid]))
    wc, w = 2 * math.pi * half_power_hz / RATE, 2 * math.pi * f / RATE
    r = 1 / (2 * math.sin(wc / 2)) ** 2
    H = 1 / (1 + r * r * (2 * math.sin(w / 2)) ** 4)
    assert abs(abs(beat) / 0.3 - H) <= 0.02, (abs(beat) / 0.3, H)
    assert abs(np.mean(got[mid] - beat * np.exp(2j * math.pi * f * t[mid])) - 1) <= 1e-3


def test_white_noise_keeps_the_share_its_noise_gain_says_and_a_gap_is_bridged() -> None:
    """Noise alone: the envelope's spread per component is ``sigma sqrt(2 sum h^2)`` within
    10 % (40 s of samples: some hundred independent stretches of the 2 Hz envelope); a
    constant 1x with every tenth sample and one stretch of 200 missing comes back to 1e-9
    everywhere, the record's ends and the gap included (the real samples' equation fits
    the order's mirror, so a lost sample costs only its own information), and at 0.2 Hz,
    the narrowest the solve keeps to float precision at 4 kHz, within 1e-5."""
    rng = np.random.default_rng(5)
    n, sigma, r = 160_000, 0.01, vk.weight_for(2.0, RATE)
    theta = 2 * math.pi * 15.0 * np.arange(n) / RATE
    got = vk.envelope(sigma * rng.normal(size=n), theta, np.ones(n), r)
    settle = vk.settle_samples(2.0, RATE)
    want = sigma * math.sqrt(2 * vk.noise_gain(r))
    for part in (got[settle:-settle].real, got[settle:-settle].imag):
        assert abs(np.std(part) / want - 1) <= 0.10
    A = 0.8 * cmath.exp(0.4j)
    y = (A * np.exp(1j * theta)).real
    weight = np.ones(n)
    weight[::10], weight[50_000:50_200] = 0.0, 0.0
    y[weight == 0] = 1e6  # never read
    assert np.abs(vk.envelope(y, theta, weight, r) - A).max() <= 1e-9
    assert vk.narrowest_hz(RATE) < 0.2
    assert np.abs(vk.envelope(y, theta, weight, vk.weight_for(0.2, RATE)) - A).max() <= 1e-5


def test_the_steady_1x_is_todays_measurement_within_its_interval(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The demo's steady run: the filter's 1x (1 Hz) averaged over the run holds each
    support's phasor as ``stand solve`` measures it, within its 95 % interval."""
    from stand.measuring.track import track_1x_vk
    from stand.solve.recordings import read_run

    run = tmp_path / "d.h5"
    assert main(["simulate", "demo", "--out", str(run)]) == 0
    solved = _json(["solve", str(run)], capsys)
    got = read_run(str(run), None)
    for sup in solved["supports"]:
        _, A, _ = track_1x_vk(got.streams.nodes[sup["node"]], 0.0, 1.0, 1)
        want = sup["amplitude_m_s2"] * cmath.exp(1j * math.radians(sup["phase_deg"]))
        assert abs(A.mean() - want) <= sup["uncertainty_m_s2"], (A.mean(), want)


def test_a_run_ups_modes_read_through_the_filter(
    runup: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """At 20 rpm/s a 2 Hz filter reads both modes within 1 % of the model's and their
    damping within 10 % (as the revolution blocks: 0.05 % and 0.7 % measured), and says
    nothing; a 0.2 Hz filter is narrower than the sweep crosses the first mode's band
    (0.40 Hz) and says so, naming both."""
    out = _json(["runup", str(runup), "--vold-kalman", "2"], capsys)
    assert out["tracking"] == "Vold-Kalman" and out["vold_kalman_hz"] == 2.0
    assert len(out["modes"]) == 2 and not out["warnings"], out["warnings"]
    for m in out["modes"]:
        assert abs(m["rpm"] / m["model_rpm"] - 1) <= 0.01, m
        assert abs(m["zeta"] / m["model_zeta"] - 1) <= 0.10, m
    narrow = _json(["runup", str(runup), "--vold-kalman", "0.2"], capsys)
    said = [w for w in narrow["warnings"] if "narrower than the 0.40 Hz" in w]
    assert said and "339 rpm" in said[0] and "widen" in said[0], narrow["warnings"]


@pytest.mark.parametrize("hz", ["0", "-1", "nan", "inf", "5000", "x"])
def test_a_bandwidth_out_of_range_is_one_line(
    hz: str, runup: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    capsys.readouterr()
    assert main(["runup", str(runup), "--vold-kalman", hz]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--vold-kalman" in err, err


def test_a_filter_too_narrow_or_a_run_too_short_is_one_line(
    runup: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """0.01 Hz is narrower than a 4 kHz run is solved for (0.18 Hz): refused, naming both;
    the demo's 4 s is shorter than a 0.2 Hz filter settles at its two ends (4.8 s each)."""
    from stand.errors import MeasurementError
    from stand.measuring.track import track_1x_vk
    from stand.solve.recordings import read_run

    capsys.readouterr()
    assert main(["runup", str(runup), "--vold-kalman", "0.01"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "narrower than 0.18 Hz" in err, err
    run = tmp_path / "d.h5"
    assert main(["simulate", "demo", "--out", str(run)]) == 0
    got = read_run(str(run), None)
    with pytest.raises(MeasurementError, match=r"too short for a Vold-Kalman filter of 0\.2 Hz"):
        track_1x_vk(got.streams.nodes[1], 0.0, 0.2)
