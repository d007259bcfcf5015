"""Stand identification: simulated proving-rotor runs give the stand back within its errors."""

from __future__ import annotations

import cmath
import json
import math
import tomllib
from pathlib import Path
from typing import Any

import pytest

from stand.cli import main
from stand.sim import shipped_scenes

TRUE = {
    "C1": 4.5e4,
    "M1": 8.0,
    "H1": 60.0,
    "C2": 5.2e4,
    "M2": 9.0,
    "H2": 80.0,
    "gain1": 1.03,
    "gain2": 0.97,
    "delay1_s": 2e-4,
    "delay2_s": 3e-4,
}


def _scene(tmp: Path, name: str, rpm: float, u1: complex, u2: complex, seed: int) -> Path:
    text = Path(str(shipped_scenes()["demo"])).read_text()
    text = (
        text.replace("H1 = 0.0", "H1 = 60.0")
        .replace("H2 = 0.0", "H2 = 80.0")
        .replace("reference_angle_deg = 0.0", "reference_angle_deg = 10.0")
        .replace("rpm = 900.0", f"rpm = {rpm}")
        .replace("seconds = 8.0", "seconds = 4.0")
        .replace("seed = 0", f"seed = {seed}")
    )
    for old, u in (
        ("g_mm = 5000.0, angle_deg = 30.0", u1),
        ("g_mm = 3000.0, angle_deg = 200.0", u2),
    ):
        text = text.replace(
            old, f"g_mm = {abs(u) * 1e6!r}, angle_deg = {-math.degrees(cmath.phase(u)) % 360!r}"
        )
    text += "\n[effects.sensor]\ngain = [1.03, 0.97]\ndelay_s = [0.0002, 0.0003]\n"
    path = tmp / f"{name}.toml"
    path.write_text(text)
    run = tmp / f"{name}.h5"
    assert main(["simulate", str(path), "--out", str(run)]) == 0
    return run


def _proving_runs(tmp: Path, scene: Any) -> None:
    """The proving rotor bare and with 20 g in each plane, at 700 and 1100 rpm, simulated
    by ``scene(tmp, name, rpm, u1, u2, seed)``; their list in ``calib.toml``."""
    u1 = 2e-3 * cmath.exp(-1j * math.radians(70))  # the proving rotor's own unbalance
    u2 = 1.5e-3 * cmath.exp(-1j * math.radians(250))
    t1 = 0.020 * 0.09 * cmath.exp(-1j * math.radians(90))  # 20 g at 90 deg, plane 1
    t2 = 0.020 * 0.08 * cmath.exp(-1j * math.radians(300))  # 20 g at 300 deg, plane 2
    lines, seed = [], 0
    for rpm in (700.0, 1100.0):
        for name, (a, b), masses in (
            ("bare", (u1, u2), "[]"),
            ("t1", (u1 + t1, u2), "[{ plane = 1, mass_g = 20.0, angle_deg = 90.0 }]"),
            ("t2", (u1, u2 + t2), "[{ plane = 2, mass_g = 20.0, angle_deg = 300.0 }]"),
        ):
            seed += 1
            run = scene(tmp, f"{name}{int(rpm)}", rpm, a, b, seed)
            lines.append(f'[[runs]]\nfile = "{run.name}"\nmasses = {masses}\n')
    (tmp / "calib.toml").write_text("\n".join(lines))


def test_calibrate_recovers_the_stand_within_its_standard_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _proving_runs(tmp_path, _scene)
    # the starting config: the demo's, wrong in every stand parameter, gamma 0 instead of 10
    start = (Path(__file__).resolve().parents[2] / "examples" / "demo-stand.toml").read_text()
    start = start.replace("M1 = 8.0 ", "M1 = 5.0 ").replace("C2 = 5.2e4", "C2 = 7e4")
    (tmp_path / "start.toml").write_text(start)
    out = tmp_path / "calibrated.toml"
    capsys.readouterr()
    assert (
        main(
            [
                "calibrate",
                str(tmp_path / "calib.toml"),
                "--config",
                str(tmp_path / "start.toml"),
                "--out",
                str(out),
                "--json",
                "--archive",
                f"sqlite:///{tmp_path / 'a.sqlite'}",
                "--reason",
                "yearly calibration",
            ]
        )
        == 0
    )
    res = json.loads(capsys.readouterr().out)
    from stand.archive.audit import entries, file_sha256

    (entry,) = entries(f"sqlite:///{tmp_path / 'a.sqlite'}")  # one audit entry: old -> new
    assert (entry["action"], entry["reason"]) == ("calibration", "yearly calibration")
    assert entry["old_sha256"] == file_sha256(tmp_path / "start.toml")
    assert entry["new_sha256"] == file_sha256(out)
    v, se = res["values"], res["std_errors"]
    for name, truth in TRUE.items():
        # 4 standard errors: a 1-in-16,000 miss per parameter if the errors are right
        assert abs(v[name] - truth) <= 4 * se[name], (name, v[name], truth, se[name])
        assert se[name] < 0.25 * abs(truth), name  # and they say something
    assert res["reference_angle_deg"] == pytest.approx(
        10.0, abs=4 * math.degrees(se["reference_angle_error_rad"])
    )
    cfg = tomllib.loads(out.read_text())
    assert cfg["sensors"]["gain"][0] == pytest.approx(1.03, abs=0.01)
    # the calibrated config solves the demo's own run right, sensors corrected
    run = _scene(
        tmp_path,
        "check",
        900.0,
        5e-3 * cmath.exp(-1j * math.radians(30)),
        3e-3 * cmath.exp(-1j * math.radians(200)),
        99,
    )
    assert main(["solve", str(run), "--config", str(out), "--json"]) == 0
    planes = json.loads(capsys.readouterr().out)["planes"]
    assert planes[0]["unbalance_g_mm"] == pytest.approx(5000, rel=0.01)
    assert planes[0]["angle_deg"] == pytest.approx(30.0, abs=0.5)
    assert planes[1]["unbalance_g_mm"] == pytest.approx(3000, rel=0.01)
    assert planes[1]["angle_deg"] == pytest.approx(200.0, abs=0.5)


def test_calibrate_needs_two_speeds(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    run = _scene(tmp_path, "one", 900.0, 2e-3 + 0j, 1e-3 + 0j, 1)
    (tmp_path / "c.toml").write_text(
        "\n".join(f'[[runs]]\nfile = "{run.name}"\n' for _ in range(4))
    )
    cfg = Path(__file__).resolve().parents[2] / "examples" / "demo-stand.toml"
    assert (
        main(
            [
                "calibrate",
                str(tmp_path / "c.toml"),
                "--config",
                str(cfg),
                "--out",
                str(tmp_path / "o.toml"),
            ]
        )
        == 2
    )
    assert "need runs at two speeds or more" in capsys.readouterr().err
    assert not (tmp_path / "o.toml").exists()


def test_calibrate_rotor_finds_mass_inertia_and_centre_of_mass(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A new rotor (45 kg, 14 kg m^2, centre of mass 0.75 m from support 1) on the demo stand,
    one speed, the bare rotor and a 20 g trial per plane; the config still holds the old
    rotor type (60 kg, 21 kg m^2, 1.00 m)."""
    lines = []
    for k, (masses, t1, t2) in enumerate(
        (
            ("[]", 0, 0),
            ("[{ plane = 1, mass_g = 20.0, angle_deg = 90.0 }]", 1, 0),
            ("[{ plane = 2, mass_g = 20.0, angle_deg = 300.0 }]", 0, 1),
        )
    ):
        u1 = 1e-3 * cmath.exp(-1j * math.radians(10)) + t1 * 0.02 * 0.09 * cmath.exp(
            -1j * math.radians(90)
        )
        u2 = 2e-3 * cmath.exp(-1j * math.radians(130)) + t2 * 0.02 * 0.08 * cmath.exp(
            -1j * math.radians(300)
        )
        text = Path(str(shipped_scenes()["demo"])).read_text()
        text = (
            text.replace("M3 = 60.0", "M3 = 45.0")
            .replace("J3 = 21.0", "J3 = 14.0")
            .replace("b = 0.85", "b = 0.60")
            .replace("c = 0.70", "c = 0.95")
            .replace("seconds = 8.0", "seconds = 4.0")
            .replace("seed = 0", f"seed = {k}")
        )
        for old, u in (
            ("g_mm = 5000.0, angle_deg = 30.0", u1),
            ("g_mm = 3000.0, angle_deg = 200.0", u2),
        ):
            text = text.replace(
                old, f"g_mm = {abs(u) * 1e6!r}, angle_deg = {-math.degrees(cmath.phase(u)) % 360!r}"
            )
        (tmp_path / f"r{k}.toml").write_text(text)
        assert (
            main(["simulate", str(tmp_path / f"r{k}.toml"), "--out", str(tmp_path / f"r{k}.h5")])
            == 0
        )
        lines.append(f'[[runs]]\nfile = "r{k}.h5"\nmasses = {masses}\n')
    (tmp_path / "rotor.toml").write_text("\n".join(lines))
    cfg = Path(__file__).resolve().parents[2] / "examples" / "demo-stand.toml"
    capsys.readouterr()
    assert (
        main(
            [
                "calibrate",
                str(tmp_path / "rotor.toml"),
                "--config",
                str(cfg),
                "--rotor",
                "--out",
                str(tmp_path / "new.toml"),
                "--json",
            ]
        )
        == 0
    )
    res = json.loads(capsys.readouterr().out)
    v, se = res["values"], res["std_errors"]
    for name, truth in (("M3", 45.0), ("J3", 14.0), ("x_cm_m", 0.75)):
        assert abs(v[name] - truth) <= 4 * se[name], (name, v[name], se[name])
    new = tomllib.loads((tmp_path / "new.toml").read_text())
    assert new["rotor"]["b"] == pytest.approx(0.60, abs=0.005)


def test_calibrate_reports_the_reference_angle_in_degrees_as_the_config_takes_it() -> None:
    """It printed `reference_angle_error_rad` while `[stand] reference_angle_deg` is degrees."""
    from stand.cli.calibrate import _estimate_line

    assert _estimate_line("reference_angle_error_rad", math.radians(2.5), math.radians(0.1)) == (
        "#   reference_angle_error_deg = 2.5 +- 0.1"
    )
    assert _estimate_line("C1", 45000.0, 120.0) == "#   C1 = 45000 +- 1.2e+02"


def _auger_scene(tmp: Path, name: str, rpm: float, u1: complex, u2: complex, seed: int) -> Path:
    """As :func:`_scene`, with the 1.7 m auger (shaft and flights) as the proving rotor."""
    from shafts import SHAFT

    run = _scene(tmp, name, rpm, u1, u2, seed)
    text = (tmp / f"{name}.toml").read_text()
    head, rest = text.split("[rotor]\n", 1)
    rotor, after = rest.split("\n\n", 1)
    kept = [ln for ln in rotor.splitlines() if ln.split("=")[0].strip() in ("R1", "R2")]
    (tmp / f"{name}.toml").write_text(head + "[rotor]\n" + "\n".join(kept) + "\n\n" + SHAFT + after)
    run.unlink()
    assert main(["simulate", str(tmp / f"{name}.toml"), "--out", str(run)]) == 0
    return run


def test_calibrate_with_a_bending_proving_rotor(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The proving rotor is the 1.7 m auger, which bends: described by its shaft, the stand
    comes out within 4 standard errors (as with a rigid rotor); with the rigid model of the
    same mass, inertia and geometry the masses, stiffnesses and gains come out 5 to 9
    standard errors off and the misfit is 17 times larger."""
    from shafts import SHAFT, rigid_twin

    _proving_runs(tmp_path, _auger_scene)
    demo = (Path(__file__).resolve().parents[2] / "examples" / "demo-stand.toml").read_text()
    head, rest = demo.split("[rotor]\n", 1)
    kept = [ln for ln in rest.splitlines() if ln.split("=")[0].strip() not in "M3 J3 a b c d"]
    configs = {
        "shaft": head + "[rotor]\n" + "\n".join(kept) + "\n" + SHAFT,
        "rigid": rigid_twin(tmp_path).read_text(),
    }
    found = {}
    for kind, text in configs.items():
        start = tmp_path / f"start-{kind}.toml"
        start.write_text(text.replace("M1 = 8.0 ", "M1 = 5.0 ").replace("C2 = 5.2e4", "C2 = 7e4"))
        capsys.readouterr()
        argv = ["calibrate", str(tmp_path / "calib.toml"), "--config", str(start)]
        assert main([*argv, "--out", str(tmp_path / f"cal-{kind}.toml"), "--json"]) == 0
        found[kind] = json.loads(capsys.readouterr().out)
    v, se = found["shaft"]["values"], found["shaft"]["std_errors"]
    for name, truth in TRUE.items():
        assert abs(v[name] - truth) <= 4 * se[name], (name, v[name], truth, se[name])
    v, se = found["rigid"]["values"], found["rigid"]["std_errors"]
    for name in ("M1", "M2", "C1", "C2", "gain1", "gain2"):
        assert abs(v[name] - TRUE[name]) > 4 * se[name], name
    ratio = found["rigid"]["residual_rms_m_s2"] / found["shaft"]["residual_rms_m_s2"]
    assert ratio > 10
    # --rotor has nothing to identify when the shaft describes the rotor
    argv = [
        "calibrate",
        str(tmp_path / "calib.toml"),
        "--config",
        str(tmp_path / "start-shaft.toml"),
    ]
    assert main([*argv, "--rotor", "--out", str(tmp_path / "r.toml")]) == 2
    assert "describes the rotor already" in capsys.readouterr().err
