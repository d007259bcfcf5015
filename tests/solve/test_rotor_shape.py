"""ISO 21940-11's simple split holds only for a rotor whose centre of mass lies between its
bearing planes and whose correction planes are not close together; an overhung or narrow
rotor is judged by resultant and moment (``docs/tolerance.md``).  The figures come from the
definitions, computed here: ``U_per = G m / Omega``, the resultant ``|U1 + U2|``, the moment
about the centre of mass ``|sum (x_i - x_cm) U_i|``."""

from __future__ import annotations

import cmath
import math
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from stand.core.tolerance import rotor_shape
from tests.solve.test_verdict import GRADE, config, simulate, solve

U_PER_G_MM = 6.3 * 60.0 / (1500 * 2 * math.pi / 60) * 1e3  # G m / Omega: 2406.4 g mm
X1, XCM, X2 = 0.15, 1.00, 1.70  # the demo's planes and centre of mass [m from support 1]


def _U(out: dict) -> list[complex]:  # type: ignore[type-arg]
    return [
        p["unbalance_g_mm"] * cmath.exp(-1j * math.radians(p["angle_deg"])) for p in out["planes"]
    ]


def test_an_overhung_rotor_is_judged_by_resultant_and_moment(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Bearing planes at 1.6 m and 2.0 m leave the centre of mass (1.0 m) outside them (lever
    shares 250 % and -150 %): not the split clamped to 70/30, but the resultant against
    U_per and the moment against U_per x 0.4 m / 2, the assumption said in the result."""
    cfg = config(tmp_path, "over", GRADE + "bearing_planes_m = [1.6, 2.0]\n")
    out = solve(simulate(tmp_path / "r.h5"), capsys, "--config", str(cfg))
    t = out["tolerance"]
    res, mom = t["criteria"]
    assert (res["name"], mom["name"]) == ("resultant", "moment")
    U = _U(out)
    assert res["permissible_g_mm"] == pytest.approx(U_PER_G_MM, rel=1e-4)
    assert res["value_g_mm"] == pytest.approx(abs(U[0] + U[1]), rel=1e-4)
    assert mom["permissible_g_mm2"] == pytest.approx(U_PER_G_MM * 400.0 / 2, rel=1e-4)
    moment = abs((X1 - XCM) * 1e3 * U[0] + (X2 - XCM) * 1e3 * U[1])
    assert mom["value_g_mm2"] == pytest.approx(moment, rel=1e-4)
    assert "outside the bearing planes" in t["allocation"] and "assumed" in t["allocation"]
    assert "250 %" in t["allocation"] and "-150 %" in t["allocation"]


def test_a_rotor_between_its_bearings_keeps_the_lever_split(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The demo: shares 47 % and 53 % by the lever rule, said, the planes judged as before."""
    out = solve(simulate(tmp_path / "r.h5"), capsys)
    t = out["tolerance"]
    assert [c["name"] for c in t["criteria"]] == ["plane 1", "plane 2"]
    assert t["allocation"].startswith("the lever rule") and "47 %" in t["allocation"]


def test_a_narrow_rotor_is_judged_by_resultant_and_moment(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Correction planes 0.55 m apart between supports 1.9 m apart: narrow (below a third,
    the product's stated assumption); the moment's limit U_per x 1.9 m / 2."""
    cfg = config(tmp_path, "narrow")
    text = cfg.read_text()
    for old, new in (("a = 0.15 ", "a = 0.60 "), ("b = 0.85 ", "b = 0.30 "),
                     ("c = 0.70 ", "c = 0.25 "), ("d = 0.20 ", "d = 0.75 ")):  # fmt: skip
        assert old in text
        text = text.replace(old, new)
    cfg.write_text(text)
    out = solve(simulate(tmp_path / "r.h5"), capsys, "--config", str(cfg))
    t = out["tolerance"]
    assert [c["name"] for c in t["criteria"]] == ["resultant", "moment"]
    assert "narrow" in t["allocation"] and "0.55 m apart" in t["allocation"]
    assert t["criteria"][1]["permissible_g_mm2"] == pytest.approx(U_PER_G_MM * 1900 / 2, rel=1e-4)


@given(
    x1=st.floats(-1.0, 1.0), gap=st.floats(0.01, 2.0), xcm=st.floats(-2.0, 3.0),
    zA=st.floats(-1.0, 1.0), span=st.floats(0.05, 3.0),
)  # fmt: skip
def test_shape_follows_the_definitions(
    x1: float, gap: float, xcm: float, zA: float, span: float
) -> None:
    """Overhung exactly when the lever share leaves [0, 1]; else narrow exactly when the
    correction planes are closer than a third of the bearing distance."""
    zB = zA + span
    share = (zB - xcm) / (zB - zA)
    shape = rotor_shape((x1, x1 + gap), xcm, (zA, zB))
    if not 0.0 <= share <= 1.0:
        assert shape == "overhung"
    else:
        assert shape == ("narrow" if (x1 + gap) - x1 < (zB - zA) / 3 else "between")


def test_a_maximum_speed_below_the_measuring_speed_is_judged_at_the_measuring_speed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``max_speed_rpm = 100`` on a 900 rpm run would make U_per nine times larger and pass
    the untouched demo rotor; it is judged at 900 rpm (U_per = G m / Omega at 900 rpm) and
    fails, the source saying why."""
    slow = GRADE.replace("max_speed_rpm = 1500.0", "max_speed_rpm = 100.0")
    cfg = config(tmp_path, "slow", slow)
    out = solve(simulate(tmp_path / "r.h5"), capsys, "--config", str(cfg))
    t = out["tolerance"]
    at_900 = 6.3 * 60.0 / (900 * 2 * math.pi / 60) * 1e3
    assert t["permissible_g_mm"] == pytest.approx(at_900, rel=2e-3)  # the run's speed, +-0.2 %
    assert "judged at the measuring speed 900 rpm" in t["source"]
    assert out["verdict"] == "fail"
