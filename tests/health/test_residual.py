"""The residual-unbalance check (API annex B): on 20 simulated rotors, from recorded trial
runs, and the check that refuses to judge on fewer points than it needs."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from stand.cli import main
from stand.health.residual import scene_check
from stand.sim import load_scene, shipped_scenes

PER = (1098.142e-6, 1220.158e-6)
"""The demo's plane limits [kg m] (G 6.3 at 1500 rpm, carried to the correction planes)."""


def residual_scene(
    tmp_path: Path, U_g_mm: tuple[float, float], angles: tuple[float, float]
) -> Path:
    text = Path(str(shipped_scenes()["demo"])).read_text().replace("seconds = 8.0", "seconds = 2.0")
    text = text.replace(
        "plane1 = { g_mm = 5000.0, angle_deg = 30.0 }",
        f"plane1 = {{ g_mm = {U_g_mm[0]}, angle_deg = {angles[0]} }}",
    )
    text = text.replace("plane2 = { g_mm = 3000.0, angle_deg = 200.0 }",
                        f"plane2 = {{ g_mm = {U_g_mm[1]}, angle_deg = {angles[1]} }}")  # fmt: skip
    path = tmp_path / "rotor.toml"
    path.write_text(text)
    return path


def test_twenty_rotors_with_half_their_permissible_left(tmp_path: Path) -> None:
    """A residual of 0.5 U_per at a random angle, a trial of 1.5 U_per at 6 positions, 20
    rotors: every fitted residual within 5 % of U_per of the truth (the issue's figure; the
    demo's noise gives about 0.2 %), and each rotor passes."""
    rng = np.random.default_rng(21)
    worst = 0.0
    for k in range(20):
        angles = tuple(float(a) for a in rng.uniform(0, 360, 2))
        U = (0.5 * PER[0] * 1e6, 0.5 * PER[1] * 1e6)
        scene, p, _ = load_scene(str(residual_scene(tmp_path, U, angles)))  # type: ignore[arg-type]
        scene = scene.model_copy(update={"run": scene.run.model_copy(update={"seed": 500 + k})})
        checks = scene_check(scene, p, PER, 1.5, 6)
        for i, c in enumerate(checks):
            truth = U[i] * 1e-6 * np.exp(-1j * math.radians(angles[i]))
            assert c.residual_kg_m is not None
            err = abs(c.residual_kg_m - truth) / PER[i]
            worst = max(worst, err)
            assert c.state == "pass", (k, i, c)
    assert worst < 0.05, worst
    print(f"worst error over 20 rotors: {100 * worst:.3f} % of U_per")


def _record(tmp_path: Path, scene: Path, plane: int, grams: float, n: int) -> list[dict]:  # type: ignore[type-arg]
    runs = []
    for k in range(n):
        angle = 360.0 * k / n
        out = tmp_path / f"p{plane}-{k:02d}.h5"
        argv = ["simulate", str(scene), "--out", str(out), "--seed", str(k + 10 * plane),
                "--add", f"{plane}:{grams}@{angle}"]  # fmt: skip
        assert main(argv) == 0
        runs.append(
            {"file": out.name, "masses": [{"plane": plane, "mass_g": grams, "angle_deg": angle}]}
        )
    return runs


def _toml(runs: list[dict]) -> str:  # type: ignore[type-arg]
    lines = []
    for r in runs:
        (m,) = r["masses"]
        lines += ["[[runs]]", f'file = "{r["file"]}"',
                  f"masses = [{{plane = {m['plane']}, mass_g = {m['mass_g']}, "
                  f"angle_deg = {m['angle_deg']}}}]", ""]  # fmt: skip
    return "\n".join(lines)


def test_recorded_trial_runs_and_the_refusals(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Trial runs recorded with a 1.5 U_per trial (18.3 g at 90 mm in plane 1; 22.9 g at 80
    mm in plane 2): the file gives the residual of the scene; a position left out, or a run
    that cannot be read, leaves its plane not judged (exit 3); a trial of 0.5 U_per is
    refused (exit 2)."""
    scene = residual_scene(tmp_path, (549.07, 610.08), (130.0, 300.0))
    g1, g2 = 1.5 * PER[0] / 0.09 * 1e3, 1.5 * PER[1] / 0.08 * 1e3
    runs = _record(tmp_path, scene, 1, g1, 6) + _record(tmp_path, scene, 2, g2, 6)
    spec = tmp_path / "runs.toml"
    spec.write_text(_toml(runs))
    capsys.readouterr()
    assert main(["residual", str(spec), "--json", "--report", str(tmp_path / "r.html")]) == 0
    out = json.loads(capsys.readouterr().out)
    got = [p["residual_g_mm"] for p in out["planes"]]
    assert got == pytest.approx([549.07, 610.08], abs=0.05 * 1098)
    assert [p["residual_angle_deg"] for p in out["planes"]] == pytest.approx([130, 300], abs=3)
    assert (
        "fitted circle" in (tmp_path / "r.html").read_text()
        or "data:image/png" in (tmp_path / "r.html").read_text()
    )
    spec.write_text(_toml(runs[:3] + runs[4:]))  # plane 1's fourth position left out
    assert main(["residual", str(spec), "--json"]) == 3
    out = json.loads(capsys.readouterr().out)
    assert out["planes"][0]["verdict"] == "not judged" and out["planes"][1]["verdict"] == "pass"
    (tmp_path / runs[7]["file"]).write_bytes(b"not a run")
    spec.write_text(_toml(runs))
    assert main(["residual", str(spec), "--json"]) == 3
    out = json.loads(capsys.readouterr().out)
    assert "could not be read" in out["planes"][1]["why"]
    small = [dict(r, masses=[dict(r["masses"][0], mass_g=r["masses"][0]["mass_g"] / 3)])
             for r in runs[:6]]  # fmt: skip
    spec.write_text(_toml(small))
    assert main(["residual", str(spec)]) == 2
    assert "the check takes 1 to 2 x" in capsys.readouterr().err


def _off_by(cfg_text: str, factor: float) -> str:
    """The scene's stand and rotor with every mass, inertia and stiffness times ``factor``:
    the software's model reads every unbalance ``factor`` times its true value."""
    out = []
    for line in cfg_text.splitlines():
        key = line.split("=")[0].strip()
        if key == "description":  # a scene's, not a config's
            continue
        if key in ("M1", "M2", "C1", "C2", "M3", "J3"):
            value = float(line.split("=")[1].split("#")[0])
            line = f"{key} = {value * factor!r}"
        out.append(line)
    return "\n".join(out) + "\n"


def test_a_stand_calibrated_off_is_put_right_by_the_trial(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The software's model 7.7 % short (every mass and stiffness x 0.923): the readings are
    7.7 % short, and so is the circle; API's ratio (the trial's known effect over the fitted
    radius) gives the residual within 1 % of the truth (550 and 300 g mm; the noise gives
    about 0.1 %), and the 95 % error holds the truth."""
    scene = residual_scene(tmp_path, (550.0, 300.0), (40.0, 250.0))
    belief = tmp_path / "believed.toml"
    text = scene.read_text()
    belief.write_text(_off_by(text[: text.index("[run]")], 0.923))
    capsys.readouterr()
    code = main(["residual", "--scene", str(scene), "--config", str(belief), "--json"])
    out = json.loads(capsys.readouterr().out)
    for p, truth, angle in zip(out["planes"], (550.0, 300.0), (40.0, 250.0), strict=True):
        assert p["fit"]["trial_read_share"] == pytest.approx(0.923, abs=0.003)
        assert p["residual_g_mm"] == pytest.approx(truth, rel=0.01)
        U = p["residual_g_mm"] * np.exp(-1j * math.radians(p["residual_angle_deg"]))
        assert abs(U - truth * np.exp(-1j * math.radians(angle))) <= p["error95_g_mm"]
    assert code == 0  # 550 of 1013.5 and 300 of 1126.2 permissible (the model's M3 x 0.923)


def test_one_recording_for_every_position_and_shuffled_positions_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One file named for all six positions: refused in one line (its digest twice), not a
    0.5 g mm PASS.  The six runs named for the wrong positions: the readings do not go round
    the circle in the trial's order, the plane not judged (exit 3)."""
    scene = residual_scene(tmp_path, (300.0, 300.0), (40.0, 250.0))
    g1 = 1.5 * PER[0] / 0.09 * 1e3
    runs = _record(tmp_path, scene, 1, g1, 6)
    one = [dict(r, file=runs[0]["file"]) for r in runs]
    spec = tmp_path / "runs.toml"
    spec.write_text(_toml(one))
    capsys.readouterr()
    assert main(["residual", str(spec)]) == 2
    err = capsys.readouterr().err.strip()
    assert "same recording as runs[0]" in err and len(err.splitlines()) == 1
    order = [0, 3, 1, 4, 2, 5]
    shuffled = [dict(r, file=runs[order[k]]["file"]) for k, r in enumerate(runs)]
    spec.write_text(_toml(shuffled))
    assert main(["residual", str(spec), "--json"]) == 3
    (p,) = json.loads(capsys.readouterr().out)["planes"]
    assert p["verdict"] == "not judged" and "do not go round the circle" in p["why"]


def test_a_residual_within_its_error_of_zero_has_no_angle() -> None:
    """0.5 g mm +- 0.6: the interval holds the origin, so every angle; 0.7 +- 0.6 has one."""
    from stand.cli.residual import to_json
    from stand.health.residual import PlaneCheck

    def check(residual_g_mm: float) -> PlaneCheck:
        U = residual_g_mm * 1e-6 * np.exp(-1j * math.radians(80.0))
        return PlaneCheck(1, (), 1.5 * PER[0], complex(U), 0.6e-6, PER[0], "pass")

    inside, outside = to_json((check(0.5), check(0.7)))["planes"]
    assert inside["residual_angle_deg"] is None
    assert outside["residual_angle_deg"] == pytest.approx(80.0)
