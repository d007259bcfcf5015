"""Every simulated run draws its own noise: a check run after a correction never replays
the noise of the run it checks (it read exactly 0.0 g mm, URR 100.0 %, before), and a
residual within its own 95 % circle is printed without an angle."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import pytest

from stand.cli import main
from stand.sim import Mass, load_scene
from stand.sim.scene import run_seed, with_masses


def test_masses_give_the_run_a_seed_of_its_own() -> None:
    scene, _, _ = load_scene("demo")
    put = [Mass(1, -55.5, 30.0), Mass(2, -37.5, 200.0)]
    a, b = with_masses(scene, put), with_masses(scene, put[:1])
    assert a.run.seed == run_seed(scene.run.seed, put) != scene.run.seed
    assert b.run.seed not in (a.run.seed, scene.run.seed)
    assert with_masses(scene, put).run.seed == a.run.seed  # the same rotor: the same run
    assert with_masses(scene).run.seed == scene.run.seed


def test_a_simulated_check_run_reads_its_own_noise_and_no_angle_within_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The demo corrected as read: the check run's residual is the first run's error plus
    the check's own noise, so neither exactly zero nor more than a few 95 % radii; its
    seed is in the file; a plane whose 95 % circle holds zero prints no angle."""
    first, second = tmp_path / "r1.h5", tmp_path / "r2.h5"
    assert main(["simulate", "demo", "--out", str(first)]) == 0
    assert main(["simulate", "demo", "--out", str(second), "--apply", str(first)]) == 0
    with h5py.File(second) as f:
        source = str(f.attrs.get("source", ""))
    assert "seed 0)" not in source and "seed" in source
    capsys.readouterr()
    assert main(["solve", str(second), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    for p in out["planes"]:
        assert 0.0 < p["unbalance_g_mm"] < 4 * p["uncertainty_g_mm"]
        assert p["within_noise"] == (p["unbalance_g_mm"] <= p["uncertainty_g_mm"])
    assert main(["solve", str(second)]) == 0
    text = capsys.readouterr().out
    for p in out["planes"]:
        line = next(x for x in text.splitlines() if x.startswith(f"  {p['plane']}  "))
        assert (f"{p['angle_deg']:.2f}" not in line) == p["within_noise"]
