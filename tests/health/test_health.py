"""The stand keeps itself honest: a simulated production series, the alarm, the refit."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "stand" / "data" / "scenes"


def run_json(args: list[str], capsys: pytest.CaptureFixture[str]) -> dict:
    capsys.readouterr()
    assert main([*args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def series(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """140 rotors on the demo stand (4 s runs), support 1 8 % softer from rotor 100 on,
    each correction put on within 2 % and 2 deg (the shipped scene production-drift; its
    description's 200 rotors are the docs' demo: 40 after the change are what the alarm
    and the refit need, and 60 fewer spare the suite 20 s)."""
    import fcntl
    import os
    import shutil

    # built once for the session, under a lock, by the first xdist worker that needs it
    # (70 s: the suite's longest fixture); each worker's tests get a copy of its archive
    base = tmp_path_factory.getbasetemp()
    shared = (base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base) / "health-series"
    with open(f"{shared}.lock", "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (shared / "built").exists():
            (shared / "runs").mkdir(parents=True, exist_ok=True)
            url = f"sqlite:///{shared / 'a.sqlite'}"
            args = ["simulate", "production-drift", "--series", "140", "--out-dir",
                    str(shared / "runs"), "--archive", url]  # fmt: skip
            assert main(args) == 0
            (shared / "built").touch()
    d = tmp_path_factory.mktemp("series")
    shutil.copy(shared / "a.sqlite", d / "a.sqlite")
    shutil.copytree(shared / "runs", d / "runs")
    return d, f"sqlite:///{d / 'a.sqlite'}"


def test_support_1_softening_is_raised_within_20_rotors_and_named(
    series: tuple[Path, str], capsys: pytest.CaptureFixture[str]
) -> None:
    """The alarm comes after rotor 100 and within 20 rotors of it; the change is placed near
    rotor 100; support 1 is named, and its stiffness change holds the true -8 % within its
    95 % interval."""
    _, url = series
    out = run_json(["health", "--archive", url], capsys)
    (g,) = out["groups"]
    assert out["alarm"] is True and g["data"] == 140
    assert 100 <= g["alarm_at"] <= 120, g
    assert abs(g["change_at"] - 100) <= 10, g
    m = g["moved"]
    assert m["parameter"] == "C1" and m["part"].startswith("support 1")
    assert abs(m["change"] - -8.0) <= m["interval95"], m
    assert [o["parameter"] for o in g["or"]] == ["M1"]


def test_recalibration_from_production_recovers_c1_and_the_answers(
    series: tuple[Path, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`stand calibrate --from-archive` writes the config beside the old one (never over it
    without --force) with C1 within 1 % of the true 41400 N/m; a run on the softened stand
    solved with it holds the scene's 5000 and 3000 g mm within its interval, where the old
    calibration is off by more than its interval."""
    from stand.config import config_toml
    from stand.sim import load_scene

    _, url = series
    scene, _, _ = load_scene("production-drift")
    cfg = tmp_path / "stand.toml"
    cfg.write_text(config_toml(scene.config()))
    capsys.readouterr()
    assert main(["calibrate", "--from-archive", "--config", str(cfg), "--out", str(cfg),
                 "--archive", url]) == 2  # fmt: skip
    assert "add --force" in capsys.readouterr().err
    out = run_json(["calibrate", "--from-archive", "--config", str(cfg), "--archive", url], capsys)
    new = tmp_path / "stand-recalibrated.toml"
    assert out["config"] == str(new) and new.is_file()
    from stand.config import load_config

    C1 = load_config(str(new))[1].C1
    assert C1 == pytest.approx(45000 * 0.92, rel=0.01), C1
    assert any(line.startswith("+C1 = ") for line in out["diff"])
    soft = tmp_path / "soft.toml"
    soft.write_text((SCENES / "demo.toml").read_text().replace("C1 = 4.5e4", "C1 = 41400.0"))
    run = tmp_path / "soft.h5"
    assert main(["simulate", str(soft), "--out", str(run), "--seed", "7"]) == 0
    (fit,) = [f for f in out["fits"] if f["parameter"] == "C1"]
    assert abs(C1 / 41400 - 1) <= fit["interval95_pct"] / 100  # the truth in its interval
    errors = {}
    for config in (new, cfg):
        p1 = run_json(["solve", str(run), "--config", str(config)], capsys)["planes"][0]
        errors[config] = (abs(p1["unbalance_g_mm"] - 5000), p1["uncertainty_g_mm"])
    # the old calibration misses 5000 g mm beyond its measurement's radius; the new one
    # within the radius plus what C1's own interval allows (0.1 % of U per 0.1 % of C1,
    # bounded here by 10 % of the old one's miss: the series draws its own noise per run)
    assert errors[cfg][0] > errors[cfg][1], errors
    assert errors[new][0] <= errors[new][1] + 0.1 * errors[cfg][0], errors


def test_groups_keep_rotor_types_speeds_and_calibrations_apart() -> None:
    from stand.health.data import groups

    rng = np.random.default_rng(1)

    def row(rt: str, rpm: float, cfg: str = "a") -> dict:
        pairs = lambda: rng.normal(size=(2, 2)).tolist()  # noqa: E731
        datum = {
            "omega_rad_s": rpm * np.pi / 30,
            "A0": pairs(),
            "A1": pairs(),
            "cov0": np.eye(4).tolist(),
            "cov1": np.eye(4).tolist(),
            "dU_kg_m": pairs(),
        }
        return {"id": len(rt) + rpm, "stand_id": "s", "rotor_type": rt, "rpm": rpm,
                "config_sha256": cfg, "datum_json": json.dumps(datum)}  # fmt: skip

    rows = [row("A", 900), row("B", 900), row("A", 1200), row("A", 910), row("A", 900, "b")]
    got = [(g.rotor_type, round(g.rpm), g.config_sha256, len(g.rows)) for g in groups(rows)]
    assert got == [("A", 900, "a", 2), ("B", 900, "a", 1), ("A", 1200, "a", 1), ("A", 900, "b", 1)]


def test_health_without_data_and_bad_options(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    capsys.readouterr()
    assert main(["health", "--archive", url]) == 0
    assert "no calibration data yet" in capsys.readouterr().out
    assert run_json(["health", "--archive", url], capsys) == {
        "alarm": False,
        "false_alarm": "at most 1 % chance of an alarm within 1000 corrected rotors of a "
        "stable stand",
        "groups": [],
        "evaluations": [
            {
                "stand": None,
                "state": "never",
                "line": "machine evaluation: never "
                "evaluated: run stand evaluate on the proving rotor's runs",
            }
        ],
    }
    cfg = str(ROOT / "examples" / "demo-stand.toml")
    out = tmp_path / "x.toml"
    assert (
        main(["calibrate", "--from-archive", "--config", cfg, "--out", str(out), "--archive", url])
        == 2
    )
    assert "no correction data made with this calibration" in capsys.readouterr().err
    assert (
        main(["calibrate", "--from-archive", "--config", cfg, "--fit", "C9", "--archive", url]) == 2
    )
    assert "--fit: C9" in capsys.readouterr().err
    assert main(["balance", "--scene", "demo", "--applied"]) == 2
    assert "go with --check" in capsys.readouterr().err


@pytest.mark.realtime
def test_a_confirmed_check_is_a_datum_and_an_unconfirmed_one_is_not(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    b1, b2, b3 = (str(tmp_path / f"b{i}.h5") for i in (1, 2, 3))
    base = ["balance", "--scene", "demo", "--archive", url, "--json"]
    assert main([*base, "--out", b1]) == 0
    assert main([*base, "--apply", b1, "--check", b1, "--out", b2]) == 0
    assert "not a calibration datum: confirm" in capsys.readouterr().err
    assert main([*base, "--apply", b1, "--check", b1, "--applied", "--out", b3]) == 0
    capsys.readouterr()
    out = run_json(["health", "--archive", url], capsys)
    assert [g["data"] for g in out["groups"]] == [1] and out["alarm"] is False


def test_the_issue_s_demo_case_is_flagged_within_10_rotors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The demo stand with support 1's spring 10 % softer and its mass 5 % heavier from the
    first rotor (the stored calibration unchanged: plane 1 reads 5 % off): stand health
    raises the alarm within 10 corrected rotors and names support 1."""
    text = (SCENES / "production-drift.toml").read_text()
    text = text.replace("from_rotor = 100", "from_rotor = 1").replace(
        "step_pct = { C1 = -8.0 }", "step_pct = { C1 = -10.0, M1 = 5.0 }"
    )
    scene = tmp_path / "aged.toml"
    scene.write_text(text)
    (tmp_path / "runs").mkdir()
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    args = ["simulate", str(scene), "--series", "12", "--out-dir", str(tmp_path / "runs")]
    assert main([*args, "--archive", url]) == 0
    (g,) = run_json(["health", "--archive", url], capsys)["groups"]
    assert g["alarm"] and g["alarm_at"] <= 10, g
    assert g["moved"]["part"].startswith("support 1"), g


def test_every_answer_carries_the_calibration_s_own_interval(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The demo run on the aged stand (C1 -10 %, M1 +5 %) solved with the stored
    calibration: plane 1 is about 5 % off, far outside the measurement's own interval; the
    calibration's interval from [calibration] bands that admit such an age (C 10 %, M 5 %)
    holds the truth, and the verdict says the calibration limits it.  The default bands
    (C 5 %, M 2 %) do not hold it: they are what a fresh calibration is known to."""
    aged = tmp_path / "aged.toml"
    text = (SCENES / "demo.toml").read_text()
    aged.write_text(text.replace("C1 = 4.5e4", "C1 = 40500.0").replace("M1 = 8.0", "M1 = 8.4"))
    run = tmp_path / "aged.h5"
    assert main(["simulate", str(aged), "--out", str(run)]) == 0
    stored = (ROOT / "examples" / "demo-stand.toml").read_text()
    wide = tmp_path / "wide.toml"
    wide.write_text(stored + "\n[calibration]\nC_pct = 10.0\nM_pct = 5.0\n")
    for config, holds in ((wide, True), (ROOT / "examples" / "demo-stand.toml", False)):
        out = run_json(["solve", str(run), "--config", str(config)], capsys)
        p1 = out["planes"][0]
        off = abs(p1["unbalance_g_mm"] - 5000)
        assert off > 10 * p1["uncertainty_g_mm"]  # the data alone say nothing of it
        assert (off <= p1["calibration_interval_g_mm"]) is holds, (config, p1)
        assert out["tolerance"]["criteria"][0]["limited_by"] == "calibration"


@pytest.mark.realtime
def test_after_the_alarm_every_answer_s_calibration_interval_covers_the_truth(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The issue's demo case: once its corrected rotors have raised the alarm, the next
    rotor balanced on the aged stand (C1 -10 %, M1 +5 %) with the old calibration reads
    plane 1 about 5 % off, and its calibration interval, widened by what stand health
    fitted, holds the truth; the answer says why."""
    from stand.config import config_toml
    from stand.sim import load_scene

    series_scene = tmp_path / "aged-series.toml"
    series_scene.write_text(
        (SCENES / "production-drift.toml").read_text()
        .replace("from_rotor = 100", "from_rotor = 1")
        .replace("step_pct = { C1 = -8.0 }", "step_pct = { C1 = -10.0, M1 = 5.0 }")
    )  # fmt: skip
    (tmp_path / "runs").mkdir()
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    args = ["simulate", str(series_scene), "--series", "12", "--out-dir", str(tmp_path / "runs")]
    assert main([*args, "--archive", url]) == 0
    believed = tmp_path / "believed.toml"  # the calibration the series was corrected with
    believed.write_text(config_toml(load_scene(str(series_scene))[0].config()))
    aged = tmp_path / "aged.toml"
    aged.write_text(
        (SCENES / "demo.toml").read_text().replace("C1 = 4.5e4", "C1 = 40500.0")
        .replace("M1 = 8.0", "M1 = 8.4")
    )  # fmt: skip
    out = run_json(["balance", "--scene", str(aged), "--config", str(believed), "--archive", url,
                    "--out", str(tmp_path / "next.h5"), "--quiet"], capsys)  # fmt: skip
    p1 = out["planes"][0]
    off = abs(p1["unbalance_g_mm"] - 5000)
    assert off > 10 * p1["uncertainty_g_mm"]
    assert off <= p1["calibration_interval_g_mm"], p1
    assert any("no longer matches its calibration" in w for w in out["warnings"])


def test_a_series_never_replaces_runs_without_force(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    (tmp_path / "runs").mkdir()
    args = ["simulate", "production-drift", "--series", "2", "--out-dir", str(tmp_path / "runs")]
    assert main([*args, "--archive", url]) == 0
    capsys.readouterr()
    assert main([*args, "--archive", url]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "exists already" in err and "--force" in err, err
    assert main([*args, "--archive", url, "--force"]) == 0


def test_reprocess_with_the_recalibration_names_every_changed_rotor(
    series: tuple[Path, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The quality engineer's chain: the calibration the runs carry, `calibrate
    --from-archive`, then `reprocess --config` the corrected file: every run's verdict is
    `stand solve` of its file alone with that config, and the rotors whose final verdict
    changes are exactly those named (recall: passed, fails or is undecided now; cleared:
    failed, passes now)."""
    d, url = series
    cfg = tmp_path / "stand.toml"
    assert main(["inspect", str(d / "runs" / "S-00001-a.h5"), "--config-out", str(cfg)]) == 0
    new = tmp_path / "new.toml"
    assert main(["calibrate", "--from-archive", "--config", str(cfg), "--out", str(new),
                 "--archive", url]) == 0  # fmt: skip
    out = run_json(["reprocess", "--archive", url, "--config", str(new), "--revision", "C1",
                    "--jobs", "2"], capsys)  # fmt: skip
    assert out["counts"]["runs"] == 280 and out["counts"]["ok"] == 280
    files = [r["run_file"] for r in out["runs"]]
    alone = run_json(["solve", *files, "--config", str(new), "--jobs", "2"], capsys)
    final: dict[str, tuple[str, str]] = {}
    for r in out["runs"]:
        verdict = alone[r["run_file"]]["verdict"]
        assert r["after"]["verdict"] == verdict, r
        final[r["serial"]] = (r["before"]["verdict"], verdict)
    recall = sorted(s for s, (b, a) in final.items() if b == "pass" and a in ("fail", "undecided"))
    assert out["recall"] == recall
    assert out["cleared"] == sorted(s for s, (b, a) in final.items() if b == "fail" and a == "pass")
    assert len(final) == 140


def test_a_series_makes_its_out_dir_and_refuses_a_file_there(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The docs' series command works on a fresh machine (the folder is made); a file where
    the folder should be is one line, exit 2; the runs carry the rotor's serial."""
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    out = tmp_path / "new" / "runs"
    args = ["simulate", "production-drift", "--series", "1", "--archive", url]
    assert main([*args, "--out-dir", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["S-00001-a.h5", "S-00001-b.h5"]
    runs = run_json(["history", "--archive", url], capsys)["runs"]
    assert [r["serial"] for r in runs] == ["S-00001", "S-00001"]
    assert runs[1]["checks_run"] == runs[0]["id"] and runs[0]["rotor_type"] == "auger-A"
    (tmp_path / "file").write_text("x")
    capsys.readouterr()
    assert main([*args, "--out-dir", str(tmp_path / "file")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not a folder" in err


def test_a_change_inside_its_interval_keeps_the_calibration(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Twelve rotors on a stand that did not change: C1 refitted moves less than its own
    95 % interval, so `calibrate --from-archive` says "no significant change: keep the
    calibration" and writes nothing (it wrote a new calibration); `--force` writes it, and
    the last rotors are named by their serials, not by digests."""
    from stand.config import config_toml
    from stand.sim import load_scene

    scene = tmp_path / "steady.toml"
    scene.write_text((SCENES / "production-drift.toml").read_text()
                     .replace("from_rotor = 100", "from_rotor = 100000"))  # fmt: skip
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    assert main(["simulate", str(scene), "--series", "12", "--out-dir", str(tmp_path / "runs"),
                 "--archive", url]) == 0  # fmt: skip
    cfg = tmp_path / "stand.toml"
    cfg.write_text(config_toml(load_scene(str(scene))[0].config()))
    capsys.readouterr()
    argv = ["calibrate", "--from-archive", "--config", str(cfg), "--archive", url, "--fit", "C1"]
    out = run_json([*argv, "--json"], capsys)
    (fit,) = out["fits"]
    assert out["significant"] is False and out["config"] is None
    assert abs(fit["change_pct"]) <= fit["interval95_pct"]
    assert not (tmp_path / "stand-recalibrated.toml").exists()
    assert main(argv) == 0
    named, said = capsys.readouterr().out.split("\n", 1)
    assert named.startswith("from the archive: 12 corrected rotors of stand ")
    assert named.endswith(", rotor type auger-A")  # the config's own: no other's rotors
    assert (
        said.startswith("no significant change: keep the calibration (C1 ")
        and said.count("\n") == 1
    )
    assert "from 12 corrected rotors" in said
    assert main([*argv, "--force"]) == 0
    forced = capsys.readouterr().out
    assert (tmp_path / "stand-recalibrated.toml").is_file() and "  S-00012: plane 1" in forced


def test_recalibration_takes_only_the_configs_own_stand_and_rotor_type(
    series: tuple[Path, str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The series is rotor type auger-A: a config of another type in the same archive
    finds none of its rotors (and says whose it looked for); ``--stand`` or
    ``--rotor-type`` naming others than the config's are refused before anything is
    read."""
    from stand.config import config_toml
    from stand.sim import load_scene

    _, url = series
    text = config_toml(load_scene("production-drift")[0].config())
    other = tmp_path / "other.toml"
    other.write_text(text.replace('type = "auger-A"', 'type = "auger-B"'))
    capsys.readouterr()
    assert main(["calibrate", "--from-archive", "--config", str(other), "--archive", url]) == 2
    said = capsys.readouterr()
    assert "0 corrected rotors of stand" in said.out and "rotor type auger-B" in said.out
    own = tmp_path / "own.toml"
    own.write_text(text)
    for flag, value in (("--stand", "stand-elsewhere"), ("--rotor-type", "auger-B")):
        assert main(["calibrate", "--from-archive", "--config", str(own), flag, value,
                     "--archive", url]) == 2  # fmt: skip
        err = capsys.readouterr().err
        assert f"{flag} {value}" in err and "its own stand's rotors" in err, err
