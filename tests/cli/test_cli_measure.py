"""`stand solve` (offline) and `stand measure` (live, until precise) from the command line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stand.cli import main


@pytest.fixture(scope="module")
def demo_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("runs") / "demo.h5"
    assert main(["simulate", "demo", "--out", str(path)]) == 0
    return path


def test_solve_json_gives_the_scene_back_within_its_interval(
    demo_run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    capsys.readouterr()
    assert main(["solve", str(demo_run), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rpm"] == pytest.approx(900.0, abs=0.01)
    for p, (u, deg, r) in zip(
        out["planes"], [(5000.0, 30.0, 90.0), (3000.0, 200.0, 80.0)], strict=True
    ):
        # the scene's unbalance lies inside the 95 % circle (3 g mm here)
        assert abs(p["unbalance_g_mm"] - u) <= p["uncertainty_g_mm"]
        assert abs(p["angle_deg"] - deg) * u * 3.1416 / 180 <= p["uncertainty_g_mm"]
        assert p["radius_mm"] == r and p["mass_g"] == pytest.approx(p["unbalance_g_mm"] / r, 1e-3)
        assert 1.0 < p["uncertainty_g_mm"] < 10.0
    assert [s["node"] for s in out["supports"]] == [1, 2]
    assert out["supports"][0]["amplitude_m_s2"] == pytest.approx(2.3904, abs=0.002)
    assert out["warnings"] == []


def test_solve_needs_a_config_for_a_plain_log(
    tmp_path: Path, demo_run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "demo.log"
    assert main(["convert", str(demo_run), str(log)]) == 0
    capsys.readouterr()
    assert main(["solve", str(log)]) == 2
    assert "carries no configuration: give --config CFG" in capsys.readouterr().err
    cfg = Path(__file__).resolve().parents[2] / "examples" / "demo-stand.toml"
    assert main(["solve", str(log), "--config", str(cfg), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["planes"][0]["unbalance_g_mm"] == pytest.approx(
        5000, abs=10
    )


@pytest.mark.realtime
def test_measure_stops_when_precise_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "m.h5"
    assert (
        main(
            [
                "measure",
                "--scene",
                "demo",
                "--out",
                str(out),
                "--target-pct",
                "1",
                "--json",
                "--quiet",
            ]
        )
        == 0
    )
    res = json.loads(capsys.readouterr().out)
    assert res["stopped_by"] == "precision" and res["elapsed_s"] < 5.0
    assert all(
        p["uncertainty_g_mm"] <= t for p, t in zip(res["planes"], res["targets_g_mm"], strict=True)
    )
    assert res["run_file"] == str(out) and out.exists()
    assert main(["solve", str(out), "--json"]) == 0  # the recording solves on its own
    assert json.loads(capsys.readouterr().out)["planes"][0]["unbalance_g_mm"] == pytest.approx(
        5000, abs=30
    )


@pytest.mark.realtime
def test_measure_stops_at_the_time_limit_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert (
        main(
            [
                "measure",
                "--scene",
                "demo",
                "--out",
                str(tmp_path / "m.h5"),
                "--target-g-mm",
                "0.001",
                "--max-seconds",
                "2.5",
                "--json",
                "--quiet",
            ]
        )
        == 0
    )
    res = json.loads(capsys.readouterr().out)
    assert res["stopped_by"] == "time limit" and 2.4 < res["elapsed_s"] < 3.5


def test_measure_refuses_bad_targets(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["measure", "--scene", "demo", "--target-pct", "0"]) == 2
    assert "--target-pct must be > 0" in capsys.readouterr().err
    assert main(["measure"]) == 2
    assert "give --config CFG" in capsys.readouterr().err


@pytest.mark.realtime
def test_a_live_sensor_fault_stops_the_measurement_at_once(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A saturating sensor is a fault more data will not cure: exit 2 at the first solve
    (about 1 s), not a wait until --max-seconds; the run so far is kept."""
    scene = (Path(__file__).resolve().parents[2] / "stand/data/scenes/demo.toml").read_text()
    path = tmp_path / "clipped.toml"
    path.write_text(scene + "\n[effects.clipping]\nrange_m_s2 = 2.0\n")
    out = tmp_path / "m.h5"
    capsys.readouterr()
    code = main(["measure", "--scene", str(path), "--out", str(out), "--max-seconds", "6"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert "node 1: the sensor saturates" in err[-1] and f"kept in {out}" in err[-1]
    after = float(err[-1].split("(after ")[1].split(" s;")[0])
    assert after < 2.5
    assert main(["inspect", str(out)]) == 0
