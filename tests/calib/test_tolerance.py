"""The unbalance's spread from parameter tolerances: linearised against Monte Carlo."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from strategies import DEMO

from stand.calib.tolerance import Tolerances, parameter_uncertainty
from stand.cli import main
from stand.core import forward, rpm_to_rad_s, unbalance_from_polar

U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])


def test_small_tolerances_monte_carlo_equals_the_linearisation() -> None:
    """At 0.1 % tolerances the map is linear: 4,000 draws estimate a 95 % radius to about
    1.5 % (1 sigma), so they agree within 6 %."""
    w = float(rpm_to_rad_s(900.0))
    tol = Tolerances(C_rel=1e-3, M_rel=1e-3, length_m=1e-5, gain_rel=1e-3)
    r = parameter_uncertainty(DEMO, w, forward(DEMO, w, U), tol, draws=4000)
    assert np.allclose(r.radius95_monte_carlo, r.radius95_linear, rtol=0.06)
    assert np.allclose(r.U_kg_m, U, rtol=1e-9)
    for i in range(2):
        assert sum(v[i] for v in r.shares.values()) == pytest.approx(1.0, abs=1e-9)


def test_no_tolerance_no_spread_and_near_resonance_c_dominates() -> None:
    w = float(rpm_to_rad_s(900.0))
    r = parameter_uncertainty(DEMO, w, forward(DEMO, w, U), Tolerances(0, 0, 0, 0), draws=20)
    assert np.all(r.radius95_linear == 0) and np.all(r.radius95_monte_carlo < 1e-15)
    near = float(rpm_to_rad_s(520.0))  # 1.1 times the 468 rpm mode
    r = parameter_uncertainty(DEMO, near, forward(DEMO, near, U), draws=200)
    assert max(r.shares, key=lambda k: r.shares[k][0]) == "C1"
    far = parameter_uncertainty(DEMO, w, forward(DEMO, w, U), draws=200)
    assert np.all(r.radius95_linear > 3 * far.radius95_linear)


def test_solve_uncertainty_from_the_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    run = tmp_path / "demo.h5"
    assert main(["simulate", "demo", "--out", str(run)]) == 0
    capsys.readouterr()
    assert main(["solve", str(run), "--uncertainty", "--draws", "200", "--json"]) == 0
    pu = json.loads(capsys.readouterr().out)["parameter_uncertainty"]
    p1 = pu["planes"][0]
    assert 100 < p1["radius95_linear_g_mm"] < 300  # C +-5 %, M +-2 %, 1 mm, gain 1 %
    assert p1["combined_g_mm"] >= p1["radius95_monte_carlo_g_mm"]
    assert main(["solve", str(run), "--uncertainty", "--tol-c", "-1"]) == 2
    assert "--tol-c must be a finite number >= 0" in capsys.readouterr().err
    out = tmp_path / "r.html"
    assert main(["report", str(run), "-o", str(out), "--uncertainty", "--draws", "100"]) == 0
    assert "Parameter tolerances" in out.read_text()


@settings(max_examples=30, deadline=None)
@given(
    st.floats(0.2, 5.0),  # speed, times the demo's 900 rpm
    st.lists(st.floats(-0.05, 0.05), min_size=8, max_size=8),  # relative changes
    st.floats(-0.02, 0.02),
)
def test_all_stands_at_once_are_each_stand_alone_to_the_bit(
    speed: float, rel: list[float], gain: float
) -> None:
    """The changed stands solved as arrays give, row by row, the very bits of each
    stand solved alone by the model's own inverse (the same IEEE operations)."""
    import dataclasses

    from stand.calib.tolerance import _solve
    from stand.core import inverse_matrix

    w = rpm_to_rad_s(900.0) * speed
    A = np.array([0.3 + 0.1j, -0.2 + 0.4j])
    names = ("C1", "C2", "M1", "M2", "M3", "J3", "a", "d")
    changes = [{k: r * getattr(DEMO, k)} for k, r in zip(names, rel, strict=True)]
    changes += [{}, {"gain1": gain, "C1": 0.01 * DEMO.C1}]
    got = _solve(DEMO, w, A, changes)
    for row, c in zip(got, changes, strict=True):
        q = dataclasses.replace(
            DEMO, **{k: getattr(DEMO, k) + v for k, v in c.items() if not k.startswith("gain")}
        )
        g = np.array([1 + c.get("gain1", 0.0), 1 + c.get("gain2", 0.0)])
        U = inverse_matrix(q, w) @ (A / g)
        assert np.array_equal(row, [U[0].real, U[0].imag, U[1].real, U[1].imag])
