"""Influence coefficients: the published example, trials left on, least squares, warnings."""

from __future__ import annotations

import cmath
import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from stand.calib.influence import (
    InfluenceRun,
    Trial,
    influence_covariance,
    influence_matrix,
    initial_covariance,
    phasors,
)
from stand.cli import main
from stand.core.influence import InfluenceMap, solve_influence
from stand.errors import ModelError
from stand.sim import shipped_scenes

ROOT = Path(__file__).resolve().parents[2]


def test_bruel_kjaer_application_note_17_227_example_6(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["influence", str(ROOT / "examples" / "bk-example6-runs.toml"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    (p1, p2) = (p["weights"][0] for p in out["planes"])
    assert [p["action"] for p in out["planes"]] == ["add", "add"]  # no config: add
    # the note gives 1.979 g at 236.2 deg and 1.071 g at 121.8 deg
    assert p1["mass_g"] == pytest.approx(1.979, abs=0.001)
    assert p1["angle_deg"] == pytest.approx(236.2, abs=0.05)
    assert p2["mass_g"] == pytest.approx(1.071, abs=0.001)
    assert p2["angle_deg"] == pytest.approx(121.8, abs=0.05)
    assert out["warnings"] == []


def _synthetic(alpha: np.ndarray, V0: np.ndarray, trials: list[Trial], left_on: list[bool]):
    runs = [InfluenceRun(V0)]
    on: list[Trial] = []
    for t, keep in zip(trials, left_on, strict=True):
        V = V0 + sum(alpha[:, x.plane - 1] * x.unbalance_kg_m for x in [*on, t])
        runs.append(InfluenceRun(V, t, keep))
        if keep:
            on.append(t)
    return runs


complexes = st.builds(
    lambda r, a: r * cmath.exp(1j * a), st.floats(0.1, 10.0), st.floats(0, 2 * math.pi)
)


@given(
    st.lists(complexes, min_size=6, max_size=6),
    st.lists(complexes, min_size=3, max_size=3),
    st.lists(st.booleans(), min_size=2, max_size=2),
)
def test_trials_left_on_or_taken_off_give_the_same_matrix(
    a: list[complex], v: list[complex], left_on: list[bool]
) -> None:
    alpha = np.array(a).reshape(3, 2)  # 3 sensors, 2 planes: least squares
    # planes that act alike (rank < 2, e.g. every coefficient equal) have no one unbalance
    # to compare with (their warning is tested below); condition 1e4 amplifies the
    # matrix's 1e-15 relative error to about 1e-11, well inside rtol 1e-8
    assume(np.linalg.cond(alpha) < 1e4)
    V0 = np.array(v)
    trials = [Trial(1, 0.002, 30.0), Trial(2, 0.003, 200.0)]
    got, _ = influence_matrix(_synthetic(alpha, V0, trials, left_on))
    assert np.allclose(got, alpha, rtol=1e-9, atol=1e-12 * np.abs(alpha).max())
    U0 = solve_influence(InfluenceMap(got), V0).U_kg_m
    assert np.allclose(U0, np.linalg.lstsq(alpha, V0, rcond=None)[0], rtol=1e-8, atol=1e-12)


def test_warnings_for_a_small_trial_and_planes_that_act_alike() -> None:
    alpha = np.array([[1.0, 0.999], [1.0, 1.001]], dtype=complex) * 100
    V0 = np.array([50.0, 50.0], dtype=complex)
    runs = _synthetic(alpha, V0, [Trial(1, 0.5, 0.0), Trial(2, 0.0001, 0.0)], [False, False])
    A, notes = influence_matrix(runs)
    assert [n.code for n in notes] == ["trial_too_small"] and "plane 2" in notes[0].message
    assert [n.code for n in solve_influence(InfluenceMap(A), V0).diagnostics] == ["ill_conditioned"]


def test_refusals() -> None:
    V = np.array([1.0, 2.0], dtype=complex)
    with pytest.raises(ModelError, match="no trial run in plane"):
        influence_matrix([InfluenceRun(V), InfluenceRun(V * 2, Trial(2, 0.001, 0.0))])
    with pytest.raises(ModelError, match="first run is the initial one"):
        influence_matrix([InfluenceRun(V, Trial(1, 0.001, 0.0)), InfluenceRun(V)])
    with pytest.raises(ModelError, match="run 2 has 1 sensors"):
        influence_matrix([InfluenceRun(V), InfluenceRun(V[:1], Trial(1, 0.001, 0.0))])
    assert np.allclose(phasors([2.0], [90.0]), [-2j])  # conjugated: the model's convention


def test_recorded_runs_give_the_scene_s_unbalance_back_as_masses_to_add(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Simulated runs of the demo stand: initial, then a 20 g trial in each plane. The
    correction to add must cancel 5000 g mm at 30 deg (plane 1, R 90 mm) and 3000 g mm at
    200 deg (plane 2, R 80 mm): 55.56 g at 210 deg and 37.5 g at 20 deg."""
    demo = Path(str(shipped_scenes()["demo"])).read_text()

    def scene_with(u1: complex, u2: complex, name: str) -> Path:
        text = demo
        for old, u in (
            ("g_mm = 5000.0, angle_deg = 30.0", u1),
            ("g_mm = 3000.0, angle_deg = 200.0", u2),
        ):
            text = text.replace(
                old, f"g_mm = {abs(u) * 1e6!r}, angle_deg = {-math.degrees(cmath.phase(u)) % 360!r}"
            )
        path = tmp_path / f"{name}.toml"
        path.write_text(text)
        run = tmp_path / f"{name}.h5"
        assert main(["simulate", str(path), "--out", str(run)]) == 0
        return run

    U1 = 5e-3 * cmath.exp(-1j * math.radians(30))
    U2 = 3e-3 * cmath.exp(-1j * math.radians(200))
    T1 = 0.020 * 0.09 * cmath.exp(-1j * math.radians(90))  # 20 g at 90 deg, R1
    T2 = 0.020 * 0.08 * cmath.exp(-1j * math.radians(300))  # 20 g at 300 deg, R2
    scene_with(U1, U2, "initial")
    scene_with(U1 + T1, U2, "trial1")
    scene_with(U1, U2 + T2, "trial2")
    (tmp_path / "runs.toml").write_text(
        '[[runs]]\nfile = "initial.h5"\n'
        '[[runs]]\nfile = "trial1.h5"\ntrial = { plane = 1, mass_g = 20.0, angle_deg = 90.0 }\n'
        '[[runs]]\nfile = "trial2.h5"\ntrial = { plane = 2, mass_g = 20.0, angle_deg = 300.0 }\n'
    )
    capsys.readouterr()
    assert (
        main(
            [
                "influence",
                str(tmp_path / "runs.toml"),
                "--json",
                "--save",
                str(tmp_path / "matrix.json"),
            ]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    p1, p2 = out["planes"]  # the initial run's unbalance, its interval holding the truth
    for p, (g_mm, deg) in zip(out["planes"], [(5000.0, 30.0), (3000.0, 200.0)], strict=True):
        U = p["unbalance_g_mm"] * cmath.exp(-1j * math.radians(p["angle_deg"]))
        assert abs(U - g_mm * cmath.exp(-1j * math.radians(deg))) <= p["uncertainty_g_mm"]
    assert p1["mass_g"] == pytest.approx(55.56, rel=0.01)
    assert p2["mass_g"] == pytest.approx(37.5, rel=0.01)
    # the demo config removes material: at the unbalance's own angle
    c1, c2 = (c["weights"][0] for c in out["corrections"])
    assert out["correction_mode"] == "remove"
    assert c1["angle_deg"] == pytest.approx(30.0, abs=0.5)
    assert c2["angle_deg"] == pytest.approx(200.0, abs=0.5)
    assert out["condition_number"] > 1 and len(out["influence_per_g_mm"]) == 2
    # permanent calibration: the stored matrix and one run of the next rotor
    (tmp_path / "one.toml").write_text('[[runs]]\nfile = "initial.h5"\n')
    assert (
        main(
            [
                "influence",
                str(tmp_path / "one.toml"),
                "--matrix",
                str(tmp_path / "matrix.json"),
                "--json",
            ]
        )
        == 0
    )
    again = json.loads(capsys.readouterr().out)
    for a, b in zip(again["planes"], out["planes"], strict=True):  # the same unbalance ...
        assert a["unbalance_g_mm"] == b["unbalance_g_mm"]
        assert a["uncertainty_g_mm"] < b["uncertainty_g_mm"]  # ... the run's noise counted once
    assert again["provenance"]["influence_matrix"] == str(tmp_path / "matrix.json")


def test_advise_recommends_speeds_above_the_modes(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["advise", "--config", str(ROOT / "examples" / "demo-stand.toml"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    f1, f2 = out["natural_frequencies_hz"]
    assert f1 == pytest.approx(5.6469, abs=1e-4) and f2 == pytest.approx(7.7993, abs=1e-4)
    low, high = out["recommended_rpm"]
    assert low > 1.25 * f2 * 60 and high == 1500.0  # above the modes, up to the service speed
    rows = out["speeds"]
    ok = [r for r in rows if low <= r["rpm"] <= high]
    assert ok and all(r["unbalance_shift_pct_for_5pct_C"] < 1.0 for r in ok)
    assert all(not r["near_resonance"] for r in ok)
    # the noise gain falls as the speed rises above the modes
    gains = [r["noise_gain_g_mm_per_m_s2"] for r in rows if r["ratio_to_top_mode"] > 1.5]
    assert gains == sorted(gains, reverse=True)


def _noisy_runs(rng: np.random.Generator, alpha, U0, trials, sigma, draws):
    """``draws`` sets of runs: initial + one trial per plane, each reading with white
    complex noise of ``sigma`` per real part; the runs carry that covariance."""
    s = alpha.shape[0]
    clean = [alpha @ U0] + [alpha @ U0 + alpha[:, t.plane - 1] * t.unbalance_kg_m for t in trials]
    cov = sigma**2 * np.eye(2 * s)
    for _ in range(draws):
        noisy = [A + sigma * (rng.normal(size=s) + 1j * rng.normal(size=s)) for A in clean]
        yield [InfluenceRun(noisy[0], None, False, cov)] + [
            InfluenceRun(A, t, False, cov) for A, t in zip(noisy[1:], trials, strict=True)
        ]


def _re_im(z: np.ndarray) -> np.ndarray:
    return np.column_stack([z.real, z.imag]).ravel()


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_matrix_and_initial_run_covariances_match_monte_carlo(seed: int) -> None:
    """2000 noisy sets of trial runs: the empirical covariance of the matrix and of the
    initial run's unbalance against :func:`influence_covariance` and
    :func:`initial_covariance`, with trials of the suggested size (a 30 % change) and noise
    at 0.5 % of the readings (the demo's is 0.05 %).  Tolerance: a sample covariance of 2000
    draws scatters by about sqrt(2/2000) = 3 % per entry; the first-order propagation is
    off by about the squared relative error of the matrix, (0.5 % / 30 %)^2 * 2 < 0.1 %;
    15 % of the largest entry is 5 sigma of the scatter.  (With noise at 2 % and trials
    moving the larger reading by 10 and 15 %, the prediction fell up to 35 % short: hence
    the warning for trials under 25 %.)"""
    rng = np.random.default_rng(seed)
    alpha = rng.normal(size=(2, 2)) + 1j * rng.normal(size=(2, 2))
    U0 = rng.normal(size=2) + 1j * rng.normal(size=2)
    A0 = float(np.abs(alpha @ U0).max())  # trials of the suggested size: a 30 % change
    trials = [Trial(j + 1, 0.3 * A0 / np.abs(alpha[:, j]).max(), 40.0 + 210 * j) for j in range(2)]
    sigma = 0.005 * A0
    a_draws, u_draws = [], []
    for runs in _noisy_runs(rng, alpha, U0, trials, sigma, 2000):
        a, _ = influence_matrix(runs)
        a_draws.append(_re_im(a.ravel()))
        u_draws.append(_re_im(solve_influence(InfluenceMap(a), runs[0].readings).U_kg_m))
    runs = next(_noisy_runs(np.random.default_rng(0), alpha, U0, trials, 0.0, 1))
    for r in runs:  # the prediction at the clean readings with the noise's covariance
        object.__setattr__(r, "cov", sigma**2 * np.eye(4))
    pred_a = influence_covariance(runs)
    pred_u = initial_covariance(runs, alpha, U0)
    for emp, pred in ((np.cov(np.array(a_draws).T), pred_a), (np.cov(np.array(u_draws).T), pred_u)):
        assert pred is not None
        assert np.abs(emp - pred).max() <= 0.15 * np.abs(pred).max()


def test_a_stored_matrix_s_own_error_enters_a_later_run_s_interval() -> None:
    """A matrix with a covariance, applied to a new run: ``solve_influence``'s covariance
    against 4000 draws of matrix and run (tolerance as above: 3 % scatter, 15 % bound)."""
    rng = np.random.default_rng(7)
    alpha = np.array([[2.0 + 1j, 0.5], [0.3 - 0.2j, 1.5 - 1j]])
    U = np.array([0.8 - 0.3j, -0.4 + 0.9j])
    cov_alpha = np.diag(rng.uniform(0.5, 2.0, 8)) * 1e-3
    cov_A = np.eye(4) * 2e-3
    draws = []
    L_a, L_A = np.linalg.cholesky(cov_alpha), np.linalg.cholesky(cov_A)
    for _ in range(4000):
        da = L_a @ rng.normal(size=8)
        a = alpha + (da[0::2] + 1j * da[1::2]).reshape(2, 2)
        dA = L_A @ rng.normal(size=4)
        A = alpha @ U + dA[0::2] + 1j * dA[1::2]
        draws.append(_re_im(solve_influence(InfluenceMap(a), A).U_kg_m))
    sol = solve_influence(InfluenceMap(alpha, cov_alpha), alpha @ U, cov_A)
    pred = np.asarray(sol.cov_U)
    emp = np.cov(np.array(draws).T)
    assert np.abs(emp - pred).max() <= 0.15 * np.abs(pred).max()
    without = np.asarray(solve_influence(InfluenceMap(alpha), alpha @ U, cov_A).cov_U)
    assert np.trace(pred) > 1.5 * np.trace(without)  # the matrix's share is not negligible here
