"""A run-up read as the stand's frequency response (``stand runup``): the modes the
order-tracked 1x shows against the model's eigenvalues, the sweep's bias stated and
holding, the separation margins, the plots; runs that are no run-up refused in one line."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
from scenes import edited_scene

from stand.cli import main
from stand.core.model import natural_frequencies
from stand.core.resonance import (
    modal_fit,
    model_modes,
    separation_margin_required,
)
from stand.sim import load_scene, shipped_scenes

RPM = 30 / math.pi


def _json(args: list[str], capsys: pytest.CaptureFixture[str]) -> dict:
    capsys.readouterr()
    assert main([*args, "--json"]) == 0
    out: dict = json.loads(capsys.readouterr().out)
    return out


def test_both_modes_within_1_pct_of_the_models_and_their_damping_within_10_pct(
    runup: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """At 20 rpm/s the modes fitted as the sweep gives them are the model's eigenvalues
    within 1 % (0.07 % measured) and their damping within 10 % (0.7 %); read as steady
    states the same points put each mode high (3.2 % and 1.6 %: the sweep's lag), which
    the answer gives beside, never as, the mode; the balancing speed 600 rpm clears both by
    API 684's margin; the plots are PNGs, not written over without --force."""
    plots = tmp_path / "plots"
    out = _json(["runup", str(runup), "--plots", str(plots)], capsys)
    assert out["direction"] == "run-up" and abs(out["sweep_rpm_per_s"] - 20) < 1, out
    assert len(out["modes"]) == 2 and not out["warnings"], out
    for m in out["modes"]:
        assert abs(m["rpm"] / m["model_rpm"] - 1) <= 0.01, m
        assert abs(m["zeta"] / m["model_zeta"] - 1) <= 0.10, m
        assert m["steady_reading_rpm"] > m["model_rpm"] * 1.01, m  # the lag, 1.6 % at least
        assert m["below_balancing_speed"] and m["margin_pct"] > m["required_pct"], m
    assert out["fit_residual"] < 3, out  # the points' own noise, about
    for name in ("bode.png", "polar.png", "waterfall.png"):
        assert (plots / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    capsys.readouterr()
    assert main(["runup", str(runup), "--plots", str(plots)]) == 2
    assert "--force" in capsys.readouterr().err
    assert main(["runup", str(runup), "--plots", str(plots), "--force"]) == 0


def test_a_coast_down_reads_the_same_modes_and_its_steady_reading_lies_low(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The shipped demo-coastdown (600 rpm let go, braked at 20 rpm/s): the modes as the
    sweep gives them within 1 % of the model's eigenvalues (0.02 % measured) and damping
    within 10 % (0.7 %); read as steady states they lie low by 1 % at least (3.1 % and
    1.6 % measured: the lag runs the other way), and the text names the speeds in the order
    the run went through them."""
    run = tmp_path / "c.h5"
    assert main(["simulate", "demo-coastdown", "--out", str(run)]) == 0
    out = _json(["runup", str(run)], capsys)
    assert out["direction"] == "coast-down" and abs(out["sweep_rpm_per_s"] + 20) < 1, out
    assert len(out["modes"]) == 2 and not out["warnings"], out
    for m in out["modes"]:
        assert abs(m["rpm"] / m["model_rpm"] - 1) <= 0.01, m
        assert abs(m["zeta"] / m["model_zeta"] - 1) <= 0.10, m
        assert m["steady_reading_rpm"] < m["model_rpm"] * 0.99, m
    assert main(["runup", str(run)]) == 0
    top, low = out["range_rpm"][1], out["range_rpm"][0]
    assert capsys.readouterr().out.startswith(f"coast-down from {top:.0f} to {low:.0f} rpm")


def test_a_torque_limited_run_up_reads_the_same_modes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """demo-runup as an inverter drives it (``base_rpm = 200``: constant torque to 200 rpm,
    constant power above, 600 rpm at 30 s: the sweep falls from 40 to 13 rpm/s): the modes
    within 1 % of the model's and their damping within 10 %, the mean sweep stated."""
    scene = edited_scene(
        "demo-runup", tmp_path, {"ramp_s = 30.0": "ramp_s = 30.0\nbase_rpm = 200.0"}
    )
    run = tmp_path / "t.h5"
    assert main(["simulate", str(scene), "--out", str(run)]) == 0
    out = _json(["runup", str(run)], capsys)
    assert out["direction"] == "run-up" and len(out["modes"]) == 2, out
    for m in out["modes"]:
        assert abs(m["rpm"] / m["model_rpm"] - 1) <= 0.01, m
        assert abs(m["zeta"] / m["model_zeta"] - 1) <= 0.10, m


def test_a_coast_down_recorded_past_standstill_is_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scene = edited_scene("demo-coastdown", tmp_path, {"seconds = 28.0": "seconds = 31.0"})
    capsys.readouterr()
    assert main(["simulate", str(scene), "--out", str(tmp_path / "c.h5")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "run.seconds" in err and "stands still" in err, err
    assert not (tmp_path / "c.h5").exists()


def test_the_2x_is_tracked_beside_the_1x_and_holds_the_scenes_within_its_radius(
    runup: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """demo-runup with a 2x of 0.2 m/s^2 at 40 deg on support 1 and 0.1 at 120 deg on
    support 2 (``[effects.harmonics]``): at the balancing speed each support's 2x phasor
    holds the scene's within its 95 % radius, and every block above a third of the top
    speed within three of its radii (the sweep's 1x changing within a revolution is fitted
    with it, so it does not read as a 2x); without a 2x in the scene, none is found beyond
    its radius at the balancing speed."""
    from stand.field.runup import analyse_runup
    from stand.solve.recordings import read_run

    scene = edited_scene("demo-runup", tmp_path, {"[effects.noise]": (
        "[effects.harmonics]\nx2_m_s2 = [0.2, 0.1]\nx2_phase_deg = [40.0, 120.0]\n\n"
        "[effects.noise]")})  # fmt: skip
    run = tmp_path / "h.h5"
    assert main(["simulate", str(scene), "--out", str(run)]) == 0
    out = _json(["runup", str(run)], capsys)
    for sup, (amp, deg) in zip(out["supports"], [(0.2, 40.0), (0.1, 120.0)], strict=True):
        x2 = sup["x2"]
        got = x2["at_balancing_m_s2"] * np.exp(1j * math.radians(x2["at_balancing_phase_deg"]))
        assert abs(got - amp * np.exp(1j * math.radians(deg))) <= x2[
            "at_balancing_radius95_m_s2"], x2  # fmt: skip
        assert x2["points_at_balancing"] >= 5, x2
    got = read_run(str(run), None)
    truths = [0.2 * np.exp(1j * math.radians(40.0)), 0.1 * np.exp(1j * math.radians(120.0))]
    for c, truth in zip(analyse_runup(got.streams, got.cfg, got.params).curves, truths,
                        strict=True):  # fmt: skip
        top = c.omega_rad_s >= c.omega_rad_s.max() / 3
        miss = np.abs(c.x2_m_s2[top] - truth) / (2.448 * c.x2_se_m_s2[top])
        assert miss.max() <= 3.0, (c.support, miss.max())
    plain = _json(["runup", str(runup)], capsys)
    for sup in plain["supports"]:
        assert sup["x2"]["at_balancing_m_s2"] <= sup["x2"]["at_balancing_radius95_m_s2"], sup


def test_a_balancing_speed_near_a_mode_is_said_with_the_margin_api_684_asks(
    runup: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = _json(["runup", str(runup), "--rpm", "500"], capsys)
    second = out["modes"][1]
    assert second["margin_pct"] < second["required_pct"], second
    assert any("API 684 asks" in w for w in out["warnings"]), out["warnings"]


def test_the_modal_fit_finds_the_models_poles_from_its_steady_response() -> None:
    """The steady response of the damped demo stand to a constant unbalance at 120 speeds
    (noise 1e-6 of the largest): the fit's frequencies within 1e-4 and dampings within 1e-3
    of the model's eigenvalues (the noise's share)."""
    _, p, _ = load_scene("demo-runup")
    from stand.core.model import mass_matrix

    w = np.linspace(15.0, 70.0, 120)
    M, K, H = mass_matrix(p), np.diag([p.C1, p.C2]), np.diag([p.H1, p.H2])
    F = np.array([1.0 + 0.5j, -0.3 + 0.8j])
    X = np.array([np.linalg.solve(K - wk**2 * M + 1j * wk * H, F) for wk in w])
    rng = np.random.default_rng(3)
    se = 1e-6 * np.abs(X).max() * np.ones(len(w))
    shapes = [(X[:, i] + se * rng.normal(size=len(w)), se) for i in range(2)]
    fit = modal_fit(w, shapes, 2)
    assert fit is not None
    wn, zeta = model_modes(p)
    np.testing.assert_allclose(fit.omega_rad_s, wn, rtol=1e-4)
    np.testing.assert_allclose(fit.zeta, zeta, rtol=1e-3)


def test_the_models_modes_without_damping_are_its_natural_frequencies() -> None:
    _, p, _ = load_scene("demo")
    wn, zeta = model_modes(dataclasses.replace(p, H1=0.0, H2=0.0))
    np.testing.assert_allclose(wn, natural_frequencies(p), rtol=1e-9)
    assert np.all(np.abs(zeta) < 1e-9)


@pytest.mark.parametrize(
    ("af", "below", "want"),
    [(2.0, True, 0.0), (2.49, False, 0.0), (5.0, True, 0.16 * (1 - 1 / 3.5)),
     (5.0, False, 0.10 + 0.17 * (1 - 1 / 3.5)), (100.0, False, 0.26)],
)  # fmt: skip
def test_api_684_separation_margins(af: float, below: bool, want: float) -> None:
    assert separation_margin_required(af, below) == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize(
    ("change", "says"),
    [
        ({"ramp_s = 30.0": "ramp_s = 0.5", "seconds = 31.0": "seconds = 1.0"}, "too short"),
        ({"[effects.run_up]\nramp_s = 30.0": "[effects.speed]\nripple_pct = 40.0\nripple_hz = 0.5",
          "seconds = 31.0": "seconds = 6.0"}, "goes backwards"),
        ({"[effects.run_up]\nramp_s = 30.0": "", "seconds = 31.0": "seconds = 4.0"}, "one speed"),
    ],
    ids=["too-short", "backwards", "one-speed"],
)  # fmt: skip
def test_runs_that_are_no_run_up_are_refused_in_one_line(
    change: dict[str, str], says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "r.h5"
    scene = edited_scene("demo-runup", tmp_path, change)
    assert main(["simulate", str(scene), "--out", str(run)]) == 0
    capsys.readouterr()
    assert main(["runup", str(run)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err and str(run) in err, err


def test_a_mark_lost_mid_sweep_is_said_and_its_revolutions_left_out(
    runup: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Bursts of 60 lost frames (0.3 a second) take reference edges with them: the speeds
    about each gap are named and left out, and the modes stay where the whole run puts them
    (within 0.2 %: the blocks left out are few and away from the peaks)."""
    scene = tmp_path / "lost.toml"
    text = Path(str(shipped_scenes()["demo-runup"])).read_text()
    scene.write_text(text + "\n[effects.lost_frames]\nbursts_per_s = 0.3\nburst_frames = 60\n")
    run = tmp_path / "lost.h5"
    assert main(["simulate", str(scene), "--out", str(run)]) == 0
    lost = _json(["runup", str(run)], capsys)
    whole = _json(["runup", str(runup)], capsys)
    said = [w for w in lost["warnings"] if "reference mark was lost between" in w]
    assert said and all("left out" in w for w in said), lost["warnings"]
    for a, b in zip(lost["modes"], whole["modes"], strict=True):
        assert a["rpm"] == pytest.approx(b["rpm"], rel=2e-3), (a, b)


def test_speeds_about_a_gap_in_the_other_supports_curve_are_not_interpolated() -> None:
    """Support 2's curve is interpolated to support 1's speeds for the fit, except across
    the revolutions a lost mark took from it (more than two of its spacings from a point)."""
    from stand.field.runup import SupportCurve, _covered

    w2 = np.concatenate((np.arange(20.0, 30.0, 0.1), np.arange(31.0, 40.0, 0.1)))
    c = SupportCurve(2, w2, np.ones(len(w2), complex), np.ones(len(w2)), ())
    w1 = np.array([20.05, 29.95, 30.2, 30.5, 30.75, 31.05, 39.9])
    assert _covered(w1, c).tolist() == [True, True, False, False, False, True, True]


def test_the_waterfalls_ridge_is_the_1x_at_its_speed(runup: Path) -> None:
    """Each slice of the waterfall above 200 rpm peaks at the shaft's frequency (within one
    bin, a sixteenth of the top 1x); above the resonances (480 rpm, where the 1x changes
    slowly with speed: below, it grows as w^4 across a slice of 1.6 s) with the amplitude
    the order tracking reads at that speed (within 20 %: the Hann window's scalloping
    loses up to 15 % between bins)."""
    from stand.field.runup import analyse_runup
    from stand.solve.recordings import read_run

    got = read_run(str(runup), None)
    a = analyse_runup(got.streams, got.cfg, got.params)
    for wf, c in zip(a.waterfalls, a.curves, strict=True):
        fast = wf.omega_rad_s > 200 / RPM
        assert np.count_nonzero(fast) >= 10, wf.omega_rad_s
        bin_hz = float(wf.freq_hz[1] - wf.freq_hz[0])
        for w, spectrum in zip(wf.omega_rad_s[fast], wf.amplitude_m_s2[fast], strict=True):
            k = int(np.argmax(spectrum[1:])) + 1  # past the mean
            assert abs(wf.freq_hz[k] - w / (2 * math.pi)) <= bin_hz, (w, wf.freq_hz[k])
            one_x = abs(np.interp(w, c.omega_rad_s, np.abs(c.accel_m_s2)))
            if w * RPM > 480:
                assert abs(spectrum[k] / one_x - 1) <= 0.20, (w * RPM, spectrum[k], one_x)
        assert np.count_nonzero(wf.omega_rad_s * RPM > 480) >= 4


@pytest.mark.parametrize("zeta", [0.01, 0.05])
def test_half_power_and_circle_fit_read_one_modes_damping(zeta: float) -> None:
    """A single mode's receptance ``1 / (w_n^2 - w^2 + 2 i zeta w_n w)`` at 400 speeds:
    the half-power reading's peak is the receptance's, ``w_n sqrt(1 - 2 zeta^2)``, the
    circle fit's ``w_n`` (where the angle turns fastest), both within 0.1 %, and both
    dampings within 3 % (half-power is exact only as zeta -> 0; the speeds' spacing, 0.25 %
    of w_n, limits the rest)."""
    from stand.core.resonance import resonances

    wn = 40.0
    w = np.linspace(0.5 * wn, 1.5 * wn, 400)
    G = 1.0 / (wn**2 - w**2 + 2j * zeta * wn * w)
    (r,) = resonances(w, G)
    assert r.omega_rad_s == pytest.approx(wn * math.sqrt(1 - 2 * zeta**2), rel=1e-3)
    assert r.zeta == pytest.approx(zeta, rel=0.03) and r.amplification == pytest.approx(
        1 / (2 * zeta), rel=0.03)  # fmt: skip
    assert r.circle_omega_rad_s == pytest.approx(wn, rel=1e-3)
    assert r.circle_zeta == pytest.approx(zeta, rel=0.03)


def test_the_run_ups_page_holds_its_figures_and_plots_and_replaces_nothing(
    runup: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--report``: one self-contained page with the modes as --json gives them, each
    support's 2x, the three plots inline (PNG data, nothing loaded from outside); an
    existing page is refused before anything is read or written (the plots' folder is not
    made), and the run itself is never written over."""
    import base64
    import re

    page = tmp_path / "r.html"
    out = _json(["runup", str(runup), "--report", str(page)], capsys)
    text = page.read_text(encoding="utf-8")
    assert out["report"] == str(page)
    for m in out["modes"]:
        assert f"<td>{m['rpm']:.1f}</td>" in text and f"<td>{m['zeta']:.4f}</td>" in text
    assert text.count("2x") >= 2 and 'src="http' not in text
    pictures = re.findall(r'src="data:image/png;base64,([^"]+)"', text)
    assert len(pictures) == 3
    assert all(base64.b64decode(p)[:8] == b"\x89PNG\r\n\x1a\n" for p in pictures)
    before = page.read_bytes()
    capsys.readouterr()
    assert main(["runup", str(runup), "--report", str(page), "--plots",
                 str(tmp_path / "plots")]) == 2  # fmt: skip
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(page) in err, err
    assert page.read_bytes() == before and not (tmp_path / "plots").exists()
    assert main(["runup", str(runup), "--report", str(runup), "--force"]) == 2
    assert "input" in capsys.readouterr().err


@pytest.mark.parametrize("protocol", ["scan", "canopen"])
def test_every_acquisition_family_reads_the_run_up(
    protocol: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """demo-runup through a scan module and through CANopen modules (2 kHz, the mark on an
    analog input: its edges carry no revolution count, so a slow start's long periods must
    not be read as lost edges): both modes within 1 % of the model's, damping within 10 %."""
    nodes = {"rate_hz = 4000": f'rate_hz = 2000\nprotocol = "{protocol}"'}
    scene = edited_scene("demo-runup", tmp_path, nodes)
    run = tmp_path / "f.h5"
    assert main(["simulate", str(scene), "--out", str(run)]) == 0
    out = _json(["runup", str(run)], capsys)
    assert len(out["modes"]) == 2 and not out["warnings"], out
    for m in out["modes"]:
        assert abs(m["rpm"] / m["model_rpm"] - 1) <= 0.01, m
        assert abs(m["zeta"] / m["model_zeta"] - 1) <= 0.10, m


@pytest.mark.parametrize("lost", [[], [5], [5, 6], [40, 200]])
def test_revolutions_count_a_run_ups_lost_edges_by_their_neighbours_speed(
    lost: list[int],
) -> None:
    """Edges of a run-up from standstill (constant acceleration: revolution ``k`` at
    ``sqrt(k)``), some lost: every kept edge gets its own revolution number, and the
    missing ones are counted, where the median period would count the slow start's
    revolutions as many."""
    from drivers.one_clock import revolutions

    k = np.arange(1, 400)
    edges = 2000.0 * np.sqrt(k)
    keep = np.setdiff1d(np.arange(len(k)), lost)
    rev, missed = revolutions(edges[keep])
    assert (rev == keep - keep[0]).all() and missed == len([i for i in lost if i > keep[0]])
