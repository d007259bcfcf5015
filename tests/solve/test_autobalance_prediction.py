"""`stand autobalance`: the prediction from the CLI, its JSON as the issue names it, the
config's table and the flags alike, and bad input in one line."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from stand.cli import main
from stand.config import load_config
from stand.core import rad_s_to_rpm
from stand.core.autobalance import with_balls
from stand.core.model import natural_frequencies

ROOT = Path(__file__).resolve().parents[2]
DEMO = (ROOT / "examples" / "demo-stand.toml").read_text()
BALLS = "\n[autobalancer]\nplane = 1\nballs = 2\nball_g = 50.0\nradius_mm = 60.0\n"


def _json(argv: list[str], capsys: pytest.CaptureFixture[str]) -> dict:
    capsys.readouterr()
    assert main(["autobalance", *argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def _cfg(tmp_path: Path, extra: str = BALLS) -> str:
    path = tmp_path / "stand.toml"
    path.write_text(DEMO + extra)
    return str(path)


def test_the_json_names_windows_speeds_and_the_balanced_state(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The demo stand with 2 x 50 g on 60 mm in plane 1, the demo's 5000 g mm at 30 deg and
    3000 at 200 deg, at 900 rpm (above both modes): in the open window; the natural speeds
    those of the stand with the balls' mass (to the rounding of 1e-3 rpm); two balls
    symmetric about U_b, each 3000 g mm, summing to it; plane 2 untouched."""
    argv = ["--config", _cfg(tmp_path), "--rpm", "900", "--unbalance", "1:5000@30",
            "--unbalance", "2:3000@200"]  # fmt: skip
    doc = _json(argv, capsys)
    p = load_config(_cfg(tmp_path))[1]
    want = [float(rad_s_to_rpm(w)) for w in natural_frequencies(with_balls(p, 1, 0.1))]
    assert doc["natural_rpm"] == pytest.approx(want, abs=1e-3)
    (lo1, hi1), (lo2, hi2) = doc["windows_rpm"]
    assert hi2 is None and lo1 == pytest.approx(want[0], abs=1e-3)
    assert lo2 == pytest.approx(want[1], abs=1e-3) and hi1 == doc["antiresonance_rpm"]
    b = doc["balanced"]
    assert b["in_window"] is True and 0 < b["capacity_ratio"] <= 1
    assert b["balls_g_mm"] == pytest.approx(6000 * b["capacity_ratio"], rel=1e-5)
    a1, a2 = b["ball_angles_deg"]
    mid = math.degrees(
        math.atan2(
            math.sin(math.radians(a1)) + math.sin(math.radians(a2)),
            math.cos(math.radians(a1)) + math.cos(math.radians(a2)),
        )
    )
    assert (mid - b["balls_angle_deg"] + 180) % 360 - 180 == pytest.approx(0, abs=1e-3)
    half = math.radians(((a2 - a1) % 360) / 2)
    assert 2 * 3000 * math.cos(half) == pytest.approx(b["balls_g_mm"], rel=1e-5)
    assert b["residual"][1] == {"plane": 2, "unbalance_g_mm": 3000.0, "angle_deg": 200.0}
    assert set(b["residual"][0]) == {"plane", "unbalance_g_mm", "angle_deg"}


def test_flags_and_the_config_s_table_agree_and_the_scene_gives_its_unbalance(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    by_table = _json(["--config", _cfg(tmp_path), "--rpm", "900", "--unbalance", "1:5000@30",
                      "--unbalance", "2:3000@200"], capsys)  # fmt: skip
    by_scene = _json(["--scene", "demo", "--plane", "1", "--balls", "2", "--ball-g", "50",
                      "--radius-mm", "60", "--rpm", "900"], capsys)  # fmt: skip
    assert by_table == by_scene


def test_in_the_gap_between_the_windows_the_balls_do_not_balance(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    doc = _json(["--config", _cfg(tmp_path), "--rpm", "430", "--unbalance", "1:5000@30"], capsys)
    (_, hi1), (lo2, _) = doc["windows_rpm"]
    assert hi1 < 430 < lo2
    assert doc["balanced"]["in_window"] is False and "gather" in doc["balanced"]["note"]
    assert "residual" not in doc["balanced"]


@pytest.mark.parametrize(
    ("extra", "argv", "says"),
    [
        (BALLS.replace("balls = 2", "balls = 0"), [], "[autobalancer.balls]"),
        (BALLS.replace("radius_mm = 60.0", "radius_mm = 0.0"), [], "[autobalancer.radius_mm]"),
        (BALLS.replace("radius_mm = 60.0", "radius_mm = -5.0"), [], "[autobalancer.radius_mm]"),
        (BALLS.replace("plane = 1", "plane = 3"), [], "[autobalancer.plane]"),
        (BALLS, ["--max-rpm", "200"], "no speed up to 200 rpm"),
        (BALLS.replace("ball_g = 50.0", "ball_g = nan"), [], "[autobalancer.ball_g]"),
        (BALLS + "start_deg = [0.0]\n", [], "one per ball"),
        ("", [], "has no [autobalancer]"),
    ],
)  # fmt: skip
def test_bad_input_is_one_line_naming_the_key(
    tmp_path: Path, extra: str, argv: list[str], says: str, capsys: pytest.CaptureFixture[str]
) -> None:
    capsys.readouterr()
    assert main(["autobalance", "--config", _cfg(tmp_path, extra), *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("stand: error: ") and says in err[0], err


def test_a_rotor_with_negative_inertia_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cfg = tmp_path / "neg.toml"
    cfg.write_text((DEMO + BALLS).replace("J3 = 21.0", "J3 = -21.0"))
    capsys.readouterr()
    assert main(["autobalance", "--config", str(cfg)]) == 2
    assert "J3" in capsys.readouterr().err
