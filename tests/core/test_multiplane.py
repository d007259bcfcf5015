"""N planes from M readings: the published cases and the solver's properties."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

import hypothesis.strategies as st
import numpy as np
import pytest
from hypothesis import given, settings

from stand.core.multiplane import POLYGON, significance_factors, solve_multiplane
from stand.errors import ModelError

CASES = tomllib.loads(
    (Path(__file__).resolve().parents[1] / "data" / "published_balancing.toml").read_text()
)


def phasor(pair: list[float]) -> complex:
    return pair[0] * complex(math.cos(math.radians(pair[1])), math.sin(math.radians(pair[1])))


def case(name: str) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    c = CASES[name]
    alpha = np.array([[phasor(z) for z in row] for row in c["alpha"]])
    return np.array([phasor(z) for z in c["A"]]), alpha, c


def angle_gap(a: complex, b: complex) -> float:
    """The angle between two phasors [deg], 0..180."""
    return abs((math.degrees(np.angle(a) - np.angle(b)) + 180) % 360 - 180)


def rounded_inputs(A: np.ndarray, alpha: np.ndarray, rng: np.random.Generator) -> Any:
    """The papers' inputs within their printed rounding: amplitude to the last digit printed
    (+- half a unit of it: 0.005 for 3.16, 0.05 for 5), phase +- 0.5 deg."""

    def jitter(z: np.ndarray) -> np.ndarray:
        mag = np.abs(z)
        unit = np.where(np.isclose(mag, np.round(mag)), 0.5, 0.005)
        return (mag + rng.uniform(-unit, unit, z.shape)) * np.exp(
            1j * (np.angle(z) + np.radians(rng.uniform(-0.5, 0.5, z.shape)))
        )

    return jitter(A), jitter(alpha)


def test_goodman_1964_least_squares() -> None:
    """Goodman's three readings and two planes: 0.81 and 1.48 at 0 deg, to the paper's two
    digits."""
    A, alpha, c = case("goodman")
    sol = solve_multiplane(A, alpha)
    for got, want in zip(sol.W, c["W"], strict=True):
        assert abs(got) == pytest.approx(want[0], abs=0.005)
        assert angle_gap(got, phasor(want) if want[0] else 1) < 0.5
    # the normal equations: alpha^H (A + alpha W) = 0
    assert np.allclose(alpha.conj().T @ (A + alpha @ sol.W), 0, atol=1e-12)


def test_darlow_case_1_three_independent_planes() -> None:
    """Darlow's first case (no dependent plane): the paper's corrections within 0.025 in
    amplitude (2 %) and 4 deg, what its three-digit inputs allow (below)."""
    A, alpha, c = case("darlow1")
    sol = solve_multiplane(A, alpha)
    assert sol.dependent == ()
    for got, want in zip(sol.W, c["W"], strict=True):
        assert abs(got) == pytest.approx(want[0], abs=0.025)
        assert angle_gap(got, phasor(want)) < 4.0


def test_darlow_case_2_is_within_the_rounding_of_the_paper() -> None:
    """Darlow's second case, plain least squares with a near-copy plane: the answer moves
    with the inputs' last printed digit; the paper's figures lie inside what the rounded
    inputs give (200 draws within the rounding)."""
    A, alpha, c = case("darlow2")
    rng = np.random.default_rng(7)
    draws = []
    for _ in range(200):
        a, al = rounded_inputs(A, alpha, rng)
        draws.append(np.linalg.lstsq(al, -a, rcond=None)[0])
    W = np.array(draws)
    for j, want in enumerate(c["W"]):
        mags = np.abs(W[:, j])
        assert mags.min() <= want[0] <= mags.max()
        gaps = [angle_gap(w, phasor(want)) for w in W[:, j]]
        assert min(gaps) < 1.0


def test_darlow_case_3_finds_and_drops_the_dependent_plane() -> None:
    """Darlow's test: plane 2's significance factor is below 0.2; it is left out (zero) and
    the two others match the paper's 0.51 at 46 and 1.13 at -155 deg (0.02, 2 deg)."""
    A, alpha, c = case("darlow3")
    sig = significance_factors(alpha)
    assert sig[1] <= 0.2 < min(sig[0], sig[2])
    sol = solve_multiplane(A, alpha)
    assert sol.dependent == tuple(j - 1 for j in c["dependent"])
    assert sol.W[1] == 0
    assert [d.code for d in sol.diagnostics] == ["dependent_plane"]
    for j in (0, 2):
        assert abs(sol.W[j]) == pytest.approx(c["W"][j][0], abs=0.02)
        assert angle_gap(sol.W[j], phasor(c["W"][j])) < 2.0


@pytest.mark.parametrize(("capped", "key"), [(False, "W_minmax"), (True, "W_minmax_capped")])
def test_foiles_min_max(capped: bool, key: str) -> None:
    """Foiles, Allaire & Gunter's eleven readings, four planes: min-max takes a third off
    least squares' worst reading for a little more rms; its worst residual is no more than
    the paper's correction leaves (on the paper's rounded inputs), and the corrections agree
    within 0.06 (4 %) and 5 deg."""
    A, alpha, c = case("foiles")
    caps = [c["cap"]] * 4 if capped else None
    ls = solve_multiplane(A, alpha)
    mm = solve_multiplane(A, alpha, "minmax", caps=caps)
    paper = np.array([phasor(z) for z in c[key]])
    assert mm.worst <= np.max(np.abs(A + alpha @ paper)) + 1e-9
    assert mm.worst < 0.72 * ls.worst
    assert mm.rms < 1.1 * ls.rms
    for got, want in zip(mm.W, c[key], strict=True):
        assert abs(got) == pytest.approx(want[0], abs=0.06)
        assert angle_gap(got, phasor(want)) < 5.0
    if capped:
        assert np.all(np.abs(mm.W) <= c["cap"] + 1e-12)
        assert mm.at_cap[0]


@st.composite
def problems(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Readings and matrices over 12 decades of scale, 1..5 planes, 1..4 extra readings."""
    n = draw(st.integers(1, 5))
    m = n + draw(st.integers(1, 4))
    seed = draw(st.integers(0, 2**32 - 1))
    scale = 10.0 ** draw(st.floats(-6, 6))
    rng = np.random.default_rng(seed)
    alpha = scale * (rng.normal(size=(m, n)) + 1j * rng.normal(size=(m, n)))
    A = rng.normal(size=m) + 1j * rng.normal(size=m)
    w = 10.0 ** rng.uniform(-1, 1, m)
    return A, alpha, w


@settings(max_examples=60)
@given(problems(), st.floats(0, 2 * math.pi))
def test_least_squares_is_the_normal_equations_and_min_max_never_worse(
    prob: tuple[np.ndarray, np.ndarray, np.ndarray], turn: float
) -> None:
    """LS solves the normal equations (to 1e-9 of the scale of their terms: double
    precision through a matrix of condition up to ~1e3); min-max's worst residual is never
    above LS's (exact: LS is one of its candidates); weighted LS solves its weighted
    normal equations; all are unchanged by a common rotation of every phase (1e-6 relative:
    the min-max polish stops at 1e-15 in t^2, and the LP's polygon turns with the data)."""
    A, alpha, w = prob
    if (
        min(significance_factors(alpha).min(), significance_factors(alpha * w[:, None]).min())
        <= 0.2
    ):
        return  # a dependent plane changes the problem (tested above)
    ls = solve_multiplane(A, alpha)
    grad = alpha.conj().T @ ls.residual
    assert np.linalg.norm(grad) <= 1e-9 * np.linalg.norm(alpha) * np.linalg.norm(A)
    mm = solve_multiplane(A, alpha, "minmax")
    assert mm.worst <= ls.worst * (1 + 1e-12)
    wls = solve_multiplane(A, alpha, "wls", weights=w)
    g = (alpha * w[:, None]).conj().T @ (w * wls.residual)
    assert np.linalg.norm(g) <= 1e-9 * np.linalg.norm(alpha * w[:, None]) * np.linalg.norm(w * A)
    r = complex(math.cos(turn), math.sin(turn))
    for sol, kw in ((ls, {}), (mm, {"method": "minmax"}), (wls, {"method": "wls", "weights": w})):
        turned = solve_multiplane(A * r, alpha * r, **kw)
        assert np.allclose(turned.W, sol.W, rtol=1e-6, atol=1e-6 * np.max(np.abs(sol.W)))


@settings(max_examples=40)
@given(problems(), st.floats(0.05, 0.9))
def test_caps_hold_and_cost_what_they_must(
    prob: tuple[np.ndarray, np.ndarray, np.ndarray], share: float
) -> None:
    """A cap below the free answer holds exactly, and the capped answer is no better than
    the free one (on its own criterion) and no worse than the free one scaled into the
    caps (1e-9: SLSQP's tolerance on the scaled problem)."""
    A, alpha, _ = prob
    if np.any(significance_factors(alpha) <= 0.2):
        return
    free = solve_multiplane(A, alpha)
    caps = np.maximum(share * np.abs(free.W), 1e-300)
    for method, cost in (
        ("ls", lambda r: np.linalg.norm(r)),
        ("minmax", lambda r: np.max(np.abs(r))),
    ):
        sol = solve_multiplane(A, alpha, method, caps=caps)
        assert np.all(np.abs(sol.W) <= caps * (1 + 1e-12))
        assert cost(sol.residual) >= cost(free.residual) * (1 - 1e-9) or method == "minmax"
        scaled = free.W * np.minimum(1, caps / np.maximum(np.abs(free.W), 1e-300))
        assert cost(sol.residual) <= cost(A + alpha @ scaled) * (1 + 1e-6)


def test_min_max_on_the_polygon_is_within_its_bound_before_polishing() -> None:
    """The program's polygon: 128 sides, at most 0.03 % above the circle."""
    assert 1 / math.cos(math.pi / POLYGON) - 1 < 3.1e-4


@pytest.mark.parametrize(
    ("A", "alpha", "kw", "words"),
    [
        ([1, 2], [[1, 0], [0, 1], [1, 1]], {}, "do not match"),
        ([1, 2, 3], [[1, 0], [0, 1], [1, 1]], {"method": "wls"}, "weight per reading"),
        ([1, 2, 3], [[1, 0], [0, 1], [1, 1]], {"weights": [1, 1, 1]}, "use wls"),
        (
            [1, 2, 3],
            [[1, 0], [0, 1], [1, 1]],
            {"method": "wls", "weights": [1, -1, 1]},
            "positive weights",
        ),
        ([1, 2, 3], [[1, 0], [0, 1], [1, 1]], {"caps": [1]}, "positive caps"),
        ([1, 2, 3], [[1, 0], [0, 1], [1, float("nan")]], {}, "finite"),
        ([1, 2, 3], [[0, 0], [0, 0], [0, 0]], {}, "is zero"),
        ([1, 2, 3], [[1, 0], [0, 1], [1, 1]], {"method": "median"}, "one of ls"),
    ],
)
def test_bad_problems_are_refused_with_what_is_wrong(
    A: Any, alpha: Any, kw: Any, words: str
) -> None:
    with pytest.raises(ModelError, match=words):
        solve_multiplane(np.asarray(A, complex), np.asarray(alpha, complex), **kw)


def test_more_planes_than_readings_leaves_out_what_the_readings_cannot_tell_apart() -> None:
    """Two readings cannot place three corrections: Darlow's test leaves one plane out (its
    part outside the others' span is nil), with the warning, and the two kept cancel both
    readings."""
    alpha = np.array([[1, 0.5j, 1 + 1j], [0.2, 1, -1]])
    sol = solve_multiplane(np.array([1.0, 2.0j]), alpha)
    assert len(sol.dependent) == 1
    assert sol.worst < 1e-12
    assert "not independent" in sol.diagnostics[0].message
