"""A rotor described by its shaft ([rotor.shaft]): rigid-body values and the first free-free
bending frequency, and the rigid model's limit judged from them."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from shafts import shaft_config

from stand.cli import main
from stand.core.shaft import PointMass, Section, free_free_bending_hz, rigid_values, shaft_rotor

ROOT = Path(__file__).resolve().parents[2]
E, RHO = 2.11e11, 7810.0
BETA1 = 4.730040744862704
"""First root of cos(x) cosh(x) = 1: the free-free beam's first bending mode."""


def _exact_hz(L: float, D: float) -> float:
    second, A = math.pi / 64 * D**4, math.pi / 4 * D**2
    return BETA1**2 / (2 * math.pi * L**2) * math.sqrt(E * second / (RHO * A))


@pytest.mark.parametrize(("elements", "tol"), [(10, 5e-5), (20, 3e-6), (60, 3e-8)])
def test_the_beam_elements_converge_on_the_exact_free_free_frequency(
    elements: int, tol: float
) -> None:
    """Cubic Hermite elements converge as h^4: the error falls 16-fold per halving (measured:
    3.4e-5 with 10, 2.2e-6 with 20, 2.4e-8 with 60 elements on the 1.7 m shaft)."""
    for L, D in ((1.7, 0.060), (1.0, 0.060), (3.0, 0.150)):
        got = free_free_bending_hz([Section(L, D)], E, RHO, elements=elements)
        assert got == pytest.approx(_exact_hz(L, D), rel=tol)


def test_split_sections_and_a_bore_are_the_same_shaft() -> None:
    one = free_free_bending_hz([Section(1.7, 0.06, 0.02)], E, RHO)
    three = free_free_bending_hz(
        [Section(0.5, 0.06, 0.02), Section(0.7, 0.06, 0.02), Section(0.5, 0.06, 0.02)], E, RHO
    )
    assert three == pytest.approx(one, rel=1e-6)
    # a hollow shaft is stiffer for its mass: f scales as sqrt(I/A) = sqrt(D^2 + d^2) / 4
    assert one / _exact_hz(1.7, 0.06) == pytest.approx(math.hypot(0.06, 0.02) / 0.06, rel=1e-6)


def test_rigid_values_of_a_shaft_with_a_disc() -> None:
    M, x, J = rigid_values([Section(2.0, 0.05)], RHO)
    m = RHO * math.pi / 4 * 0.05**2 * 2.0
    assert (M, x) == (pytest.approx(m), pytest.approx(1.0))
    assert J == pytest.approx(m * (3 * 0.025**2 + 2.0**2) / 12)
    M2, x2, J2 = rigid_values([Section(2.0, 0.05)], RHO, [PointMass(1.5, m, 0.3)])
    assert M2 == pytest.approx(2 * m) and x2 == pytest.approx(1.25)
    assert J2 == pytest.approx(J + m * 0.25**2 + m * 0.25**2 + 0.3)


def test_a_shaft_table_gives_the_rotor_and_its_bending_frequency(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg = shaft_config(tmp_path, 1.7, 12.0)
    got = shaft_rotor([Section(1.7, 0.06, 0.0, 12.0)], E, RHO, (0.0, 1.7), (0.17, 1.53))
    assert main(["advise", "--config", str(cfg), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["bending_hz"] == pytest.approx(got.bending_hz) == pytest.approx(77.32, abs=0.01)
    assert got.M3 == pytest.approx((RHO * math.pi * 0.03**2 + 12.0) * 1.7)
    assert (got.a, got.b, got.c, got.d) == pytest.approx((0.17, 0.68, 0.68, 0.17))


@pytest.mark.parametrize(("length", "added", "limit"), [(1.7, 12.0, 299.5), (1.0, 0.0, 1075.2)])
def test_with_a_shaft_advise_gives_the_rigid_limit_and_the_answer_is_the_flexible_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], length: float, added: float, limit: float
) -> None:
    """The shaft's f_ff gives the rigid limit; the answer itself is the flexible stand's, so
    the rigid model's warning (tests/core/test_rigid_limit.py, for bending_hz alone) falls away."""
    cfg = str(shaft_config(tmp_path, length, added))
    assert main(["advise", "--config", cfg, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["rigid_limit_rpm"] == pytest.approx(limit, abs=0.1)
    argv = ["forward", "--config", cfg, "--rpm", "900", "--unbalance", "5000@30"]
    assert main([*argv, "--unbalance", "3000@200", "--json"]) == 0
    codes = [w["code"] for w in json.loads(capsys.readouterr().out)["warnings"]]
    assert "flexible_rotor" not in codes


@pytest.mark.parametrize(
    ("extra", "key", "says"),
    [
        ("M3 = 60.0\n", "[rotor.M3]", "60 given, the shaft gives 57.9398"),
        ("b = 0.5\n", "[rotor.b]", "0.5 given, the shaft gives 0.68"),
        ("bending_hz = 90.0\n", "[rotor.bending_hz]", "90 given, the shaft gives 77.3"),
    ],
)
def test_values_given_beside_the_shaft_must_agree_within_1_percent(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: str, key: str, says: str
) -> None:
    assert main(["advise", "--config", str(shaft_config(tmp_path, 1.7, 12.0, extra=extra))]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and key in err and says in err, err
    ok = shaft_config(tmp_path, 1.7, 12.0, extra="M3 = 58.0\n")  # 0.1 % off: taken
    assert main(["advise", "--config", str(ok)]) == 0


def test_without_a_shaft_every_rotor_value_is_needed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (ROOT / "examples" / "demo-stand.toml").read_text().replace("J3 = 21.0", "")
    (tmp_path / "no-j3.toml").write_text(text)
    assert main(["advise", "--config", str(tmp_path / "no-j3.toml")]) == 2
    err = capsys.readouterr().err
    assert "[rotor.J3]" in err and "[rotor.shaft]" in err


def test_with_a_shaft_advise_judges_speeds_through_the_bending_stand(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The auger's bending mode in the stand (56.18 Hz) ends the recommended range a factor
    1.25 below it; the rigid-body modes and the stiffness sensitivity are the flexible
    stand's (its modes 5.66 and 8.23 Hz, against the rigid twin's)."""
    cfg = str(shaft_config(tmp_path, 1.7, 12.0))
    assert main(["advise", "--config", cfg, "--max-rpm", "6000", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["bending_in_stand_hz"] == pytest.approx(56.18, abs=0.01)
    assert out["natural_frequencies_hz"] == pytest.approx([5.657, 8.227], abs=1e-3)
    assert out["recommended_rpm"][1] == pytest.approx(56.18 * 60 / 1.25, abs=1)
    above = [s for s in out["speeds"] if abs(s["rpm"] / 60 / 56.18 - 1) < 0.2]
    assert above and all(s["near_resonance"] for s in above)
    assert main(["advise", "--config", cfg]) == 0
    text = capsys.readouterr().out
    assert "first bending mode in the stand: 56.18 Hz" in text
    assert "the answer is the bending rotor's" in text
