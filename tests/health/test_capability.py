"""The measurement capability for the vector unbalance: the circle radii against Monte Carlo
and hand values, the indices on known spreads, and the command on a scene and on runs."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from stand.cli import main
from stand.core.capability import MIN_RUNS, capability, radius_holding, runs_needed
from stand.sim import shipped_scenes


@pytest.mark.parametrize(
    ("cov", "offset"),
    [(np.eye(2), 0j), (np.diag([4.0, 1.0]), 0j), (np.array([[2.0, 0.9], [0.9, 1.0]]), 1.5 - 2j),
     (np.eye(2) * 1e-4, 0.3 + 0j)],
)  # fmt: skip
def test_the_circle_holds_99_73_percent(cov: np.ndarray, offset: complex) -> None:
    """2 000 000 normal draws: the share inside the circle is 99.73 % to 0.02 % (the
    binomial standard error at this share is 0.004 %)."""
    r = radius_holding(cov, offset)
    rng = np.random.default_rng(7)
    x = rng.multivariate_normal([0.0, 0.0], cov, size=2_000_000)
    inside = np.mean(np.hypot(x[:, 0] - offset.real, x[:, 1] - offset.imag) <= r)
    assert inside == pytest.approx(0.9973, abs=2e-4)
    if offset == 0 and cov[0, 1] == 0 and cov[0, 0] == cov[1, 1]:
        # 96-point Gauss-Legendre over the overlap: the closed form to 1e-6
        assert r == pytest.approx(math.sqrt(cov[0, 0] * -2 * math.log(0.0027)), rel=1e-6)


def test_indices_on_a_known_spread_and_bias() -> None:
    """A round spread of s = 2 g mm per axis about a bias of 10 g mm, tolerance 500 g mm:
    Cg_v = 100 / (3.4393 s) = 14.5 and Cgk_v = 100 / r(bias) (r = 16.2 g mm), each inside
    its 95 % interval; 24 readings are refused."""
    rng = np.random.default_rng(11)
    ref = 1e-3 + 0j
    z = ref + 10e-6 + 2e-6 * (rng.normal(size=200) + 1j * rng.normal(size=200))
    c = capability(z, ref, 500e-6)
    want_cg = 100e-6 / (3.4393 * 2e-6)
    want_cgk = 100e-6 / radius_holding(np.eye(2) * 4e-12, -10e-6 + 0j)
    assert c.cg_interval[0] <= want_cg <= c.cg_interval[1]
    assert c.cgk_interval[0] <= want_cgk <= c.cgk_interval[1]
    assert abs(c.bias_kg_m - 10e-6) < 1e-6 and c.capable
    with pytest.raises(ValueError, match="at least 25"):
        capability(z[: MIN_RUNS - 1], ref, 500e-6)
    assert runs_needed(1.2) is None and runs_needed(3.0) == MIN_RUNS
    n = runs_needed(1.6)
    assert n is not None and n > MIN_RUNS


def test_the_demo_stand_is_capable_and_says_a_scene_is_noise_only(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    capsys.readouterr()
    plot = tmp_path / "c.png"
    assert main(["capability", "--scene", "demo", "--count", "30", "--json", "--plot",
                 str(plot)]) == 0  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    assert out["verdict"] == "capable" and out["simulated_runs_differ_by_noise_only"]
    for p in out["planes"]:
        assert p["runs"] == 30 and p["cg_v"] >= p["cgk_v"] > 1.33
        assert p["cg_v_interval95"][0] < p["cg_v"] < p["cg_v_interval95"][1]
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_recorded_runs_against_the_master(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """25 recorded runs of the demo rotor against its known unbalance (5000 g mm at 30 deg,
    3000 g mm at 200 deg): capable, the bias within a reading's noise; the master given
    wrongly by 3 deg in plane 1 makes a bias of 2 sin(1.5 deg) 5000 = 262 g mm, beyond the
    band (0.2 U_per = 220 g mm): not capable (exit 1)."""
    scene = (
        Path(str(shipped_scenes()["demo"])).read_text().replace("seconds = 8.0", "seconds = 2.0")
    )
    (tmp_path / "s.toml").write_text(scene)
    runs = []
    for k in range(MIN_RUNS):
        out = tmp_path / f"m{k:02d}.h5"
        assert (
            main(["simulate", str(tmp_path / "s.toml"), "--out", str(out), "--seed", str(k)]) == 0
        )
        runs.append(str(out))
    capsys.readouterr()
    assert (
        main(["capability", *runs, "--master", "1:5000@30", "--master", "2:3000@200", "--json"])
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    assert out["verdict"] == "capable" and all(p["bias_g_mm"] < 5 for p in out["planes"])
    assert (
        main(["capability", *runs, "--master", "1:5000@33", "--master", "2:3000@200", "--json"])
        == 1
    )
    off = json.loads(capsys.readouterr().out)["planes"][0]
    assert off["bias_g_mm"] == pytest.approx(2 * math.sin(math.radians(1.5)) * 5000, rel=0.02)
    assert not off["capable"]
    assert main(["capability", *runs[:24], "--master", "1:5000@30", "--master", "2:3000@200"]) == 2
    assert "at least 25" in capsys.readouterr().err
    assert main(["capability", *runs, "--master", "1:5000"]) == 2
    assert "PLANE:G_MM@DEG" in capsys.readouterr().err
    master = ["--master", "1:5000@30", "--master", "2:3000@200"]
    copies = []  # one run, copied 25 times under other names
    for k in range(MIN_RUNS):
        copies.append(str(tmp_path / f"copy{k:02d}.h5"))
        Path(copies[-1]).write_bytes(Path(runs[0]).read_bytes())
    assert main(["capability", *copies, *master]) == 2
    err = capsys.readouterr().err.strip()
    assert "same recording as" in err and len(err.splitlines()) == 1
    other = tmp_path / "other.toml"  # another stand: its supports' springs differ
    other.write_text(scene.replace("C1 = 4.5e4", "C1 = 5.0e4"))
    odd = tmp_path / "other.h5"
    assert main(["simulate", str(other), "--out", str(odd), "--seed", "99"]) == 0
    assert main(["capability", *runs[:-1], str(odd), *master]) == 2
    assert "another stand's run" in capsys.readouterr().err


def test_readings_that_do_not_spread_are_refused_not_an_internal_error() -> None:
    """25 identical readings (one run measured 25 times, under other recordings' names):
    no spread to judge, refused in one line (it raised ValueError from the root finder)."""
    from stand.errors import UsageError
    from stand.health.capability import study

    readings = np.tile(np.array([5e-3 + 1e-3j, 3e-3 - 2e-3j]), (MIN_RUNS, 1))
    with pytest.raises(UsageError, match="plane 1: the 25 readings do not spread"):
        study(readings, readings[0], (1.1e-3, 1.2e-3))
