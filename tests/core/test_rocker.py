"""The rocker mode of ``stand autobalance`` against the seeds' formulas (000, 004), each
test value derived here from the equations (the seeds carry no numerical example)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from stand.cli import main
from stand.core.rocker import (
    contact_max_exact,
    contact_max_series,
    criterion,
    floquet_sigma_threshold,
    monodromy_radius,
    third_order,
)

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "grinder-rocker.toml"


def _doc(capsys: pytest.CaptureFixture[str], *extra: str) -> dict:
    assert main(["autobalance", "--rocker", str(EXAMPLE), "--json", *extra]) == 0
    return json.loads(capsys.readouterr().out)


def test_inertia_and_natural_speed_follow_000s_2_4(capsys: pytest.CaptureFixture[str]) -> None:
    """J_O = J_O^(h) + J_K + m_d l^2 + sum_i m_i (l^2 + R_i^2), the unbalance's point mass
    m_0 = m_0 R_0 / R_0 among them; omega0 = sqrt(c l^2 / J_O); the resonances omega0/i and
    2 omega0; (24)'s damping ds_u omega0* / l."""
    doc = _doc(capsys)
    arm, m0 = 0.18, 2e-5 / 0.05
    J_O = 0.012 + 0.0004 + 0.25 * arm**2 + m0 * (arm**2 + 0.05**2) + 2 * 0.004 * (arm**2 + 0.03**2)
    assert doc["J_O_kg_m2"] == pytest.approx(J_O, rel=1e-12)
    w0 = math.sqrt(2000.0 * arm**2 / J_O)
    assert doc["omega0_rad_s"] == pytest.approx(w0, rel=1e-12)
    rpm = 60 * w0 / (2 * math.pi)
    assert doc["onset_rpm"] == pytest.approx(rpm, rel=1e-12)
    assert doc["forced_resonances_rpm"] == pytest.approx([rpm / i for i in (2, 3, 4, 5)])
    assert doc["parametric_rpm"] == pytest.approx(2 * rpm)
    w0_star = doc["cutting"]["omega0_star_rad_s"]
    assert doc["h_min_n_s_m"] == pytest.approx(2e-5 * w0_star / arm, rel=1e-12)
    assert doc["capacity_ratio"] == pytest.approx(2e-5 / (2 * 0.004 * 0.03), rel=1e-8)
    half = math.degrees(math.acos(2e-5 / (2 * 0.004 * 0.03)))
    assert doc["ball_angles_deg"] == pytest.approx([180 - half, 180 + half], abs=1e-6)


@pytest.mark.parametrize("eps", [1e-3, 0.01])
def test_onset_is_omega0(eps: float) -> None:
    """The criterion's mean (eps l / 2)(N1 + eps^2 N13) changes sign at omega0 (to the
    third-order shift, below 1e-3 here): positive a hair below, negative a hair above."""
    w0, hp, arm = 50.0, 2.0, 0.2
    assert criterion(w0 * 0.995, w0, hp, eps, arm) > 0 > criterion(w0 * 1.005, w0, hp, eps, arm)


def test_the_floquet_threshold_at_k_half_is_one_half() -> None:
    """004's (23): sigma* = 1/2 at k = 1/2; from the multipliers of (17) within 1 % for a
    small eps (0.4999 at 0.01), and the boundary is one: stable above, unstable below."""
    s = floquet_sigma_threshold(0.01, 0.5)
    assert s == pytest.approx(0.5, rel=0.01)
    assert monodromy_radius(0.01, 0.5, s * 1.05) < 1 < monodromy_radius(0.01, 0.5, s * 0.95)
    assert floquet_sigma_threshold(0.01, 0.8) == 0.0  # away from k = 1/2: stable undamped


def test_the_third_order_2x_amplitude_matches_a_simulation_of_eq_8() -> None:
    """Eq. 8 integrated (DOP853, rtol 1e-10) until its transient has died (30 time
    constants of h'), its 2x Fourier component over 40 turns against eps^2 |(M2, N2)|:
    within 2 % (the next term is O(eps^2) relative, 0.25 % at eps = 0.05)."""
    eps, w0, hp = 0.05, 20.0, 2.0
    w = 2.6 * w0

    def f(t: float, y: np.ndarray) -> list[float]:
        z, v = y
        a = (w**2 * eps * math.sin(w * t) - 2 * (hp - eps * w * math.sin(w * t)) * v
             - w0**2 * z) / (1 + 2 * eps * math.cos(w * t))  # fmt: skip
        return [v, a]

    T = 2 * math.pi / w
    settle = math.ceil(30 / hp / T) * T
    t = settle + np.linspace(0.0, 40 * T, 40 * 256, endpoint=False)
    sol = solve_ivp(f, (0.0, t[-1] + T), [0.0, 0.0], method="DOP853", t_eval=t, rtol=1e-10,
                    atol=1e-13)  # fmt: skip
    z = sol.y[0]
    c2 = 2 * np.mean(z * np.cos(2 * w * t))
    s2 = 2 * np.mean(z * np.sin(2 * w * t))
    co = third_order(w, w0, hp)
    assert math.hypot(c2, s2) == pytest.approx(eps**2 * math.hypot(co.M2, co.N2), rel=0.02)
    c1 = 2 * np.mean(z * np.cos(w * t))
    assert c1 == pytest.approx(eps * co.M1 + eps**3 * co.M13, rel=0.02, abs=1e-6)


def test_the_worst_contact_angle_series_against_the_exact_maximum() -> None:
    """004's series for theta* and max g against the numerical maximum: the error falls as
    f_n^4 (a tenth of f_n, ten thousand times smaller, within a factor 2)."""
    err = []
    for f in (0.2, 0.02):
        ts, gs = contact_max_series(0.18, 0.0625, f)
        tx, gx = contact_max_exact(0.18, 0.0625, f)
        assert ts == pytest.approx(tx, abs=2 * f**4)
        err.append(abs(gs - gx))
    assert err[1] < err[0] / 5e3


def test_cutting_bounds(capsys: pytest.CaptureFixture[str]) -> None:
    """(13)-(15): c_n below (J_O w^2 - c arm^2) / (arm max g); omega0* from the same max; the
    configured contact angle's stiffened hinge c + c_n g(theta) / arm."""
    doc = _doc(capsys, "--rpm", "11000")
    cut, J_O, arm = doc["cutting"], doc["J_O_kg_m2"], 0.18
    w = 11000 * 2 * math.pi / 60
    _, gx = contact_max_exact(arm, 0.0625, 0.3)
    assert cut["c_n_max_exact_n_m"] == pytest.approx((J_O * w**2 - 2000 * arm**2) / (arm * gx))
    assert cut["c_n_max_series_n_m"] == pytest.approx(cut["c_n_max_exact_n_m"], rel=2e-3)
    assert cut["omega0_star_rad_s"] == pytest.approx(
        math.sqrt((2000 * arm**2 + 5e4 * arm * gx) / J_O)
    )
    th = 1.41
    g = (arm * math.sin(th) + 0.3 * (0.0625 - arm * math.cos(th))) * math.sin(th)
    assert cut["c_cutting_n_m"] == pytest.approx(2000 + 5e4 * g / arm)
    assert doc["at"]["balances"] and cut["pressing"]


@pytest.mark.parametrize(
    ("change", "says"),
    [
        (("J_housing_kg_m2 = 0.012", "J_housing_kg_m2 = -0.012"), "rocker.J_housing_kg_m2"),
        (("race_radius_m = 0.03", "race_radius_m = 0.0"), "rocker.race_radius_m"),
        (("balls = 2 ", "balls = 0 "), "rocker.balls"),
        (("[rocker]\n", "[grinder]\n"), "unknown table(s) grinder"),
        (("[rocker.cutting]", "[other]"), "unknown table(s) other"),
        (("f_n = 0.3 ", "f_n = nan "), "rocker.cutting.f_n"),
    ],
)
def test_bad_rocker_files_are_one_line(
    change: tuple[str, str], says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = EXAMPLE.read_text()
    assert change[0] in text
    bad = tmp_path / "r.toml"
    bad.write_text(text.replace(change[0], change[1]))
    assert main(["autobalance", "--rocker", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err, err
