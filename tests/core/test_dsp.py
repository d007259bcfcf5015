"""The 1x estimator at the limit: Cramer-Rao bound, coverage, bias; the shaft angle."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scenes import scene

from stand.core import forward, unbalance_from_polar
from stand.core.dsp import fit_1x, radius_factor, shaft_angle
from stand.drivers.v1.build import rebuild
from stand.measuring.measure import measure
from stand.sim import simulate

A_TRUE = 1.3 * np.exp(0.7j)


def _trials(revs: float, n: int, sigma: float, trials: int, seed: int, noise: str = "white"):
    rng = np.random.default_rng(seed)
    th = 2 * math.pi * revs * np.arange(n) / n + 0.3
    clean = (A_TRUE * np.exp(1j * th)).real + 0.2 * np.cos(2 * th + 1.0) + 0.05
    out = []
    for _ in range(trials):
        e = rng.normal(0.0, sigma, n)
        if noise == "ar1":  # strongly coloured: AR(1), phi = 0.9, same marginal variance
            e = _ar1(e, 0.9)
        ph = fit_1x(th, clean + e)
        out.append((ph.A_m_s2, ph.radius95_m_s2))
    return np.array([a for a, _ in out]), np.array([r for _, r in out])


def _ar1(e: np.ndarray, phi: float) -> np.ndarray:
    from scipy.signal import lfilter

    return np.asarray(lfilter([math.sqrt(1 - phi * phi)], [1, -phi], e))


@pytest.mark.parametrize("revs", [20.0, 20.37, 7.5])
def test_variance_is_within_10_percent_of_the_cramer_rao_bound(revs: float) -> None:
    """var(Re A) = var(Im A) >= 2 sigma^2 / N; var|A| the same; var(phase) that / |A|^2.

    2,000 trials: a variance is estimated to sqrt(2/2000) = 3.2 % (1 sigma), so the
    10 % margin is three standard errors.
    """
    n, sigma = 2000, 0.1
    est, _ = _trials(revs, n, sigma, 2000, seed=int(revs * 100))
    crb = 2 * sigma**2 / n
    assert np.var(est.real) / crb == pytest.approx(1.0, abs=0.10)
    assert np.var(est.imag) / crb == pytest.approx(1.0, abs=0.10)
    assert np.var(np.abs(est)) / crb == pytest.approx(1.0, abs=0.10)
    assert np.var(np.angle(est / A_TRUE)) / (crb / abs(A_TRUE) ** 2) == pytest.approx(1.0, abs=0.10)
    assert abs(np.mean(est) - A_TRUE) < 4 * math.sqrt(crb / 2000)  # unbiased


@pytest.mark.parametrize("noise", ["white", "ar1"])
def test_95_percent_circles_hold_the_truth_95_percent_of_the_time(noise: str) -> None:
    """2,000 trials: coverage is estimated to 0.5 % (1 sigma); we accept 93 .. 97 %."""
    est, radius = _trials(20.37, 2000, 0.1, 2000, seed=11, noise=noise)
    coverage = float(np.mean(np.abs(est - A_TRUE) <= radius))
    assert 0.93 <= coverage <= 0.97, coverage


def test_radius_factor_matches_the_f_distribution() -> None:
    from scipy.stats import f

    for dof in (8.0, 32.0, 200.0):
        assert radius_factor(dof) ** 2 / 2 == pytest.approx(f.ppf(0.95, 2, dof), rel=1e-9)
    assert radius_factor(math.inf) ** 2 == pytest.approx(-2 * math.log(0.05))


@settings(deadline=None)
@given(
    st.floats(0.5, 30.0),  # revolutions per 1000 samples at the start
    st.floats(-0.3, 0.3),  # relative speed change over the record (a ramp)
    st.floats(0.0, 1.0),  # sub-sample offset of the first edge
)
def test_shaft_angle_is_exact_for_a_constant_acceleration(
    rate: float, change: float, offset: float
) -> None:
    """theta(n) = w0 n + alpha n^2 / 2: cubic Hermite with three-point slopes reproduces it."""
    w0 = 2 * math.pi * rate / 1000
    alpha = w0 * change / 4000
    n = np.arange(4000)
    # the edges: theta = 2 pi k  ->  solve the quadratic for n
    k = np.arange(1, int((w0 * 3999 + alpha * 3999**2 / 2) / (2 * math.pi)) + 1)
    if len(k) < 3:
        return
    target = 2 * math.pi * k  # theta(n) = w0 (n - offset) + alpha (n - offset)^2 / 2
    pos = offset + 2 * target / (w0 + np.sqrt(w0 * w0 + 2 * alpha * target))
    inside, th, w = shaft_angle(n, pos, k)
    m = n[inside] - offset
    exact = w0 * m + alpha * m * m / 2 - 2 * math.pi * k[0]  # 0 at the first edge
    assert np.max(np.abs(th - exact)) < 1e-9 * (1 + np.max(np.abs(exact)))
    assert np.max(np.abs(w - (w0 + alpha * (n[inside] - offset)))) < 1e-9 * w0


def _phasor_errors(effects: dict, seconds: float = 4.0, **changes) -> list[tuple[float, float]]:
    sc = scene(effects, run={"seconds": seconds}, **changes)
    p = sc.config().parameters()
    m = measure(rebuild(simulate(sc, p).frames), p)
    U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
    out = []
    for i, ph in enumerate(m.supports):
        truth = forward(p, ph.omega_ref_rad_s, U)[i]
        out.append((abs(ph.A_m_s2) / abs(truth) - 1, math.degrees(np.angle(ph.A_m_s2 / truth))))
    return out


@pytest.mark.parametrize(
    ("name", "effects", "changes"),
    [
        ("speed ripple +-2 %", {"speed": {"ripple_pct": 2.0, "ripple_hz": 1.0}}, {}),
        ("ramp 1 %/s", {"speed": {"drift_pct_per_s": 1.0}}, {}),
        ("2 % lost frames", {"lost_frames": {"probability": 0.02}}, {}),
        (
            "strong 2x and 3x",
            {"harmonics": {"x2_m_s2": 3.0, "x3_m_s2": 2.0, "x2_phase_deg": 50.0}},
            {"nodes": {"scale_um_s2": 300}},
        ),
    ],
)
def test_bias_is_below_0_1_percent_and_0_05_degrees(
    name: str, effects: dict, changes: dict
) -> None:
    """Noise-free runs of 4 s (60 revolutions): what is left is bias (and the quantisation)."""
    for amp, deg in _phasor_errors(effects, **changes):
        assert abs(amp) < 1e-3, (name, amp)
        assert abs(deg) < 0.05, (name, deg)


def test_unbalance_intervals_cover_the_truth_through_the_whole_path() -> None:
    """Simulated runs (demo stand, 2 s, white noise of 0.9 m/s^2 rms, a coarse scale so that
    nothing clips), 150 seeds: the 95 % circles of both planes hold the scene's unbalance in
    90 .. 99 % of them (150 trials: 1.8 % per sigma)."""
    U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
    hits = []
    for seed in range(150):
        sc = scene(
            {"noise": {"density_m_s2_rthz": 0.02}},
            run={"seconds": 2.0, "seed": seed},
            nodes={"scale_um_s2": 300},
        )
        p = sc.config().parameters()
        m = measure(rebuild(simulate(sc, p).frames), p, gate=False)
        hits.append(np.abs(m.solution.U_kg_m - U) <= m.radius95_kg_m)
    coverage = np.mean(hits, axis=0)
    assert np.all((coverage >= 0.90) & (coverage <= 0.99)), coverage


def test_a_neighbour_inside_the_1x_bin_is_flagged_and_the_interval_widened() -> None:
    """920 rpm beside 900 rpm over 40 revolutions: 0.9 bins apart, the side bands cannot see
    it, but the 1x reading wanders from block to block (a 3 s beat)."""
    U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
    for effects, flagged in (
        ({"neighbour": {"rpm": 920.0, "amplitude_m_s2": 0.5}}, True),
        ({}, False),
    ):
        sc = scene(
            {"noise": {"density_m_s2_rthz": 0.01}, **effects},
            run={"seconds": 40 / 15 + 0.01, "seed": 3},
            nodes={"scale_um_s2": 200},  # at 100 the noise peaks overran the counts: refused
        )
        p = sc.config().parameters()
        m = measure(rebuild(simulate(sc, p).frames), p, gate=False)
        assert any(w.code == "unsteady_1x" for w in m.warnings) == flagged
        assert np.all(np.abs(m.solution.U_kg_m - U) <= m.radius95_kg_m)


def test_a_beat_is_not_mistaken_for_settling_and_lost_frames_raise_no_flag() -> None:
    U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
    beat = scene(
        {"noise": {"density_m_s2_rthz": 0.002}, "neighbour": {"rpm": 880.0, "amplitude_m_s2": 0.3}},
        run={"seconds": 8.0},
    )
    p = beat.config().parameters()
    m = measure(rebuild(simulate(beat, p).frames), p)
    assert min(w.revolutions for w in m.windows) >= 110  # the whole steady run, 119 revs
    assert np.all(np.abs(m.solution.U_kg_m - U) <= m.radius95_kg_m)
    lossy = scene(
        {
            "noise": {"density_m_s2_rthz": 0.002},
            "lost_frames": {"probability": 0.02, "bursts_per_s": 0.5},
        },
        run={"seconds": 8.0},
    )
    m = measure(rebuild(simulate(lossy, p).frames), p)
    assert not any(w.code == "unsteady_1x" for w in m.warnings)
    assert np.all(np.abs(m.solution.U_kg_m - U) <= m.radius95_kg_m)


_values = st.lists(
    st.one_of(st.floats(allow_nan=False, allow_infinity=False), st.integers(-5, 5).map(float)),
    max_size=40,
)


@given(_values, st.booleans())
def test_median_is_numpys_to_the_bit(values: list[float], with_nan: bool) -> None:
    """:func:`stand.core.dsp.median` is ``np.median`` exactly (no tolerance: the same
    partition and the same mean of the middle two), NaN in, NaN out; none: NaN."""
    from stand.core.dsp import median

    x = np.array(values + ([math.nan] if with_nan else []))
    got = median(x)
    if not len(x) or with_nan:
        assert math.isnan(got)
        return
    with np.errstate(over="ignore"):  # the mean of two huge ones overflows in both
        want = float(np.median(x))
    assert got == want, (got, want)


_intervals = st.tuples(st.floats(1.0, 1e6), st.integers(0, 3), st.booleans())


@given(st.lists(_intervals, min_size=1, max_size=40))
def test_local_period_is_the_median_of_its_neighbours(rows: list[tuple[float, int, bool]]) -> None:
    """The edges' local period is ``np.nanmedian`` of the nearby good intervals, to the bit
    (computed without it: numpy's imports ``numpy.ma``)."""
    import warnings

    from stand.drivers.v1.node_build import _local_period

    dp = np.array([r[0] for r in rows])
    dr = np.array([r[1] for r in rows], dtype=np.int64)
    ok = np.array([r[2] for r in rows], dtype=bool)
    per = np.where(ok, dp / np.maximum(dr, 1), np.nan)
    padded = np.concatenate((np.full(4, np.nan), per, np.full(4, np.nan)))
    windows = np.lib.stride_tricks.sliding_window_view(padded, 9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN windows
        want = np.nanmedian(windows, axis=1)
    assert np.array_equal(_local_period(dp, dr, ok), want, equal_nan=True)
