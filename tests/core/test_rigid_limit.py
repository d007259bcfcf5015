"""The rigid model's limit, stated: a rotor's first bending frequency ([rotor] bending_hz)
against the balancing speed (issue 13's table as the reference)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from stand.cli import main
from stand.core.flexible import (
    KAPPA_HIGH,
    RIGID_TOLERANCE,
    free_free_hz,
    rigid_error_range,
    rigid_limit_rpm,
)

ROOT = Path(__file__).resolve().parents[2]
SHAFT_KG_M = 7810 * math.pi * 0.030**2
"""A 60 mm steel shaft's mass per metre (22.1 kg/m): flights of 12 kg/m lower f_ff by
sqrt(22.1 / 34.1)."""
AUGER_HZ = free_free_hz(0.060, 1.7) * math.sqrt(SHAFT_KG_M / (SHAFT_KG_M + 12.0))

# what the rigid inverse computed from an independent rotordynamics package's support
# motion (issue 13): rotor -> (f_ff [Hz], {rpm: relative error})
TABLE = {
    "bare 1.7 m": (free_free_hz(0.060, 1.7), {900: 0.039, 1500: 0.084, 3000: 0.62}),
    "auger 1.7 m": (AUGER_HZ, {900: 0.072, 1500: 0.18, 3000: 2.17}),
    "bare 1.0 m": (free_free_hz(0.060, 1.0), {900: 0.0036, 1500: 0.0048, 3000: 0.014}),
}


@pytest.mark.parametrize("rotor", sorted(TABLE))
def test_the_rule_of_thumb_brackets_the_independent_figures(rotor: str) -> None:
    """kappa (f / f_ff)^2 with kappa from 0.2 to 2.4 holds each figure of the table but one:
    the auger at 3000 rpm, 12 % below its bending mode in the stand (57 Hz), where the
    response is resonant and no quadratic rule holds (README says so)."""
    f_ff, errors = TABLE[rotor]
    for rpm, err in errors.items():
        lo, hi = rigid_error_range(rpm / 60, f_ff)
        if rotor == "auger 1.7 m" and rpm == 3000:
            assert err > hi
            continue
        assert lo <= err <= hi, (rotor, rpm, lo, err, hi)


@given(st.floats(1.0, 1e4))
def test_at_the_rigid_limit_the_safe_bound_is_one_percent(f_ff: float) -> None:
    lo, hi = rigid_error_range(rigid_limit_rpm(f_ff) / 60, f_ff)
    assert hi == pytest.approx(RIGID_TOLERANCE, rel=1e-12)
    assert lo == pytest.approx(RIGID_TOLERANCE / KAPPA_HIGH * 0.2, rel=1e-12)


def _config(tmp_path: Path, bending_hz: float | str) -> Path:
    text = (ROOT / "examples" / "demo-stand.toml").read_text()
    path = tmp_path / f"bends-{bending_hz}.toml"
    path.write_text(text.replace("[rotor]\n", f"[rotor]\nbending_hz = {bending_hz}\n", 1))
    return path


@pytest.mark.parametrize(("rotor", "fires"), [("auger 1.7 m", True), ("bare 1.0 m", False)])
def test_the_warning_fires_on_the_long_auger_at_900_rpm_and_not_on_the_short_shaft(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], demo_run: Path, rotor: str, fires: bool
) -> None:
    cfg = str(_config(tmp_path, round(TABLE[rotor][0], 1)))
    argv = ["forward", "--config", cfg, "--rpm", "900", "--unbalance", "5000@30"]
    assert main([*argv, "--unbalance", "3000@200", "--json"]) == 0
    codes = [w["code"] for w in json.loads(capsys.readouterr().out)["warnings"]]
    assert ("flexible_rotor" in codes) == fires
    assert main(["solve", str(demo_run), "--config", cfg, "--json"]) == 0
    warnings = json.loads(capsys.readouterr().out)["warnings"]
    said = [w for w in warnings if "the rotor bends" in w]
    assert bool(said) == fires
    if fires:
        assert "may be off by 0.8 to 9.0 %" in said[0] and "needs a flexible model" in said[0]


def test_advise_names_the_bending_mode_and_the_rigid_limit(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg = str(_config(tmp_path, 277.6))
    assert main(["advise", "--config", cfg, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["bending_hz"] == 277.6 and out["rigid_limit_rpm"] == pytest.approx(1075.1, abs=0.1)
    assert main(["advise", "--config", cfg]) == 0
    assert "stays within 1 % up to 1075 rpm: balance between 1050 and 1075 rpm" in (
        capsys.readouterr().out
    )


@pytest.mark.parametrize("bad", ["0.0", "-5.0", '"96"'])
def test_a_bending_frequency_that_is_no_frequency_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], bad: str
) -> None:
    assert main(["advise", "--config", str(_config(tmp_path, bad))]) == 2
    err = capsys.readouterr().err
    assert "[rotor.bending_hz]" in err and err.count("\n") == 1
