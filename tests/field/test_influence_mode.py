"""Influence mode at par with the model: trial runs on the simulated stand, a stored matrix
that says what it is good for, the config's correction and tolerance, live balancing."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from configs import with_type

from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]


def _config(folder: Path, rotor_type: str, *, add8: bool = False) -> Path:
    text = (ROOT / "examples" / "demo-stand.toml").read_text()
    text = with_type(text, rotor_type)
    if add8:
        text = text.replace('mode = "remove"', 'mode = "add"')
        text = text.replace("positions = 0", "positions = 8\nweights_g = [1, 2, 5, 10, 20]")
    path = folder / f"{rotor_type}{'-add8' if add8 else ''}.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def trial_runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The initial run, the suggested trial masses, a trial run per plane, the matrix."""
    d = tmp_path_factory.mktemp("trials")
    cfg = str(_config(d, "auger-A"))
    assert main(["simulate", "demo", "--config", cfg, "--out", str(d / "r0.h5")]) == 0
    (d / "one.toml").write_text('[[runs]]\nfile = "r0.h5"\n')
    return d


def _suggested(d: Path, capsys: pytest.CaptureFixture[str]) -> list[dict]:
    capsys.readouterr()
    assert main(["influence", str(d / "one.toml"), "--json"]) == 0
    return json.loads(capsys.readouterr().out)["next_trials"]


def _matrix(d: Path, capsys: pytest.CaptureFixture[str]) -> Path:
    if (d / "M.json").exists():
        return d / "M.json"
    cfg = str(d / "auger-A.toml")
    runs = '[[runs]]\nfile = "r0.h5"\n'
    for t in _suggested(d, capsys):
        grams = round(t["mass_g"])
        run = d / f"r{t['plane']}.h5"
        argv = ["simulate", "demo", "--config", cfg, "--add", f"{t['plane']}:{grams}@0"]
        assert main([*argv, "--out", str(run)]) == 0
        runs += f'[[runs]]\nfile = "{run.name}"\n'
        runs += f"trial = {{ plane = {t['plane']}, mass_g = {grams}.0, angle_deg = 0.0 }}\n"
    (d / "runs.toml").write_text(runs)
    assert main(["influence", str(d / "runs.toml"), "--save", str(d / "M.json"), "--json"]) == 0
    capsys.readouterr()
    return d / "M.json"


def test_a_trial_mass_is_suggested_before_the_trial_runs(
    trial_runs: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """From the initial run and the stand model: a change of the larger 1x by about 30 %."""
    t1, t2 = _suggested(trial_runs, capsys)
    assert (t1["plane"], t2["plane"]) == (1, 2)
    assert 5 < t1["mass_g"] < 60 and 5 < t2["mass_g"] < 60 and t1["radius_mm"] == 90
    assert main(["influence", str(trial_runs / "one.toml")]) == 0
    text = capsys.readouterr().out
    assert "plane 1: put about" in text and "against the direction of rotation" in text


def test_the_stored_matrix_says_what_it_is_good_for(
    trial_runs: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    stored = json.loads(_matrix(trial_runs, capsys).read_text())
    assert (
        stored["kind"] == "stand influence matrix" and stored["readings"] == "support acceleration"
    )
    assert stored["rpm"] == pytest.approx(900, rel=1e-3) and stored["rotor_type"] == "auger-A"
    assert stored["created"].endswith("+00:00") and len(stored["config_sha256"]) == 64
    assert len(stored["cov_alpha"]) == 8  # the matrix's own error, from the trial runs' noise
    # the runs file's initial run, solved through its own matrix, and the stored matrix
    # used on the same run: the same unbalance, the config's correction and tolerance
    assert (
        main(["solve", str(trial_runs / "r0.h5"), "--matrix", str(trial_runs / "M.json"), "--json"])
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    assert out["correction_mode"] == "remove" and "tolerance" in out
    truth = [(5000.0, 30.0), (3000.0, 200.0)]
    for p, (g_mm, deg) in zip(out["planes"], truth, strict=True):
        assert abs(p["unbalance_g_mm"] - g_mm) <= p["uncertainty_g_mm"]
        assert abs(p["angle_deg"] - deg) <= 0.5
    assert out["provenance"]["influence_matrix"] == str(trial_runs / "M.json")


def test_a_matrix_used_at_another_speed_warns_and_another_rotor_type_is_refused(
    trial_runs: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    matrix = str(_matrix(trial_runs, capsys))
    fast = str(trial_runs / "fast.h5")
    assert (
        main(
            [
                "simulate",
                "demo",
                "--config",
                str(trial_runs / "auger-A.toml"),
                "--rpm",
                "1000",
                "--out",
                fast,
            ]
        )
        == 0
    )
    capsys.readouterr()
    assert main(["solve", fast, "--matrix", matrix]) == 0
    err = capsys.readouterr().err
    assert "measured at 900 rpm, this run is at 1000 rpm (+11 %)" in err, err
    other = _config(trial_runs, "auger-B")
    assert main(["solve", fast, "--matrix", matrix, "--config", str(other)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "rotor type 'auger-A', the config's is 'auger-B'" in err, err


@pytest.mark.parametrize(
    ("content", "says"),
    [
        ("not json", "not a stored influence matrix"),
        ('{"influence": [[[1, 0]]], "units": "reading per kg"}', "earlier version"),
        ("[1, 2]", "not a JSON object"),
        ('{"kind": "stand influence matrix"}', "version"),
        ("NaN-ALPHA", "alpha_per_kg_m"),
        ("TYPED", "typed-in readings"),
        ("RAGGED", "rows of different lengths"),
        ("WIDE", "supports >= planes"),
    ],
)
def test_a_bad_matrix_file_is_one_line_naming_it(
    trial_runs: Path, capsys: pytest.CaptureFixture[str], content: str, says: str
) -> None:
    good = json.loads(_matrix(trial_runs, capsys).read_text())
    if content == "NaN-ALPHA":
        good["alpha_per_kg_m"][0][0] = [float("nan"), 0.0]
        content = json.dumps(good)
    elif content == "TYPED":
        content = json.dumps({**good, "readings": "typed in"})
    elif content == "RAGGED":
        good["alpha_per_kg_m"][1] = good["alpha_per_kg_m"][1][:1]
        content = json.dumps(good)
    elif content == "WIDE":
        good["alpha_per_kg_m"] = [row * 2 for row in good["alpha_per_kg_m"]]
        good["cov_alpha"] = None
        content = json.dumps(good)
    bad = trial_runs / "bad.json"
    bad.write_text(content)
    assert main(["solve", str(trial_runs / "r0.h5"), "--matrix", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(bad) in err and says in err, err
    assert "Traceback" not in err


def test_typed_readings_honour_the_config_s_correction(tmp_path: Path, capsys) -> None:
    """Brüel & Kjær's example with a config: its radii, removal mode and 8 holes."""
    cfg = _config(tmp_path, "fan", add8=False)
    text = cfg.read_text().replace("positions = 0", "positions = 8")
    cfg.write_text(text)
    runs = str(ROOT / "examples" / "bk-example6-runs.toml")
    assert main(["influence", runs, "--config", str(cfg), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["radius"] == "each plane's correction radius"
    for p in out["planes"]:
        assert p["action"] == "remove"
        assert len(p["weights"]) == 2 and all(1 <= w["position"] <= 8 for w in p["weights"])
    # without a config, the note's masses to add (tested in test_influence)
    p1 = out["planes"][0]
    assert p1["unbalance_mass_g"] == pytest.approx(1.9795, abs=1e-3)  # at the trial radius 90 mm
    assert p1["unbalance_angle_deg"] == pytest.approx(56.17, abs=0.05)


@pytest.mark.realtime
def test_influence_mode_balances_the_demo_live(
    trial_runs: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Trial runs -> matrix -> balance live with it (add, 8 holes, stock weights) -> apply ->
    check: the run keeps its matrix, so --apply and reprocessing use it too."""
    matrix = str(_matrix(trial_runs, capsys))
    cfg = str(_config(trial_runs, "auger-A", add8=True))
    first, second = str(trial_runs / "b1.h5"), str(trial_runs / "b2.h5")
    base = ["balance", "--scene", "demo", "--config", cfg, "--matrix", matrix, "--quiet"]
    assert main([*base, "--out", first, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["correction_mode"] == "add" and out["provenance"]["influence_matrix"] == matrix
    assert main([*base, "--apply", first, "--check", first, "--out", second, "--json"]) == 0
    after = json.loads(capsys.readouterr().out)
    urr = [p["urr"] for p in after["check"]["planes"]]
    assert min(urr) >= 0.95, urr
    assert after["verdict"] == "pass"
    assert main(["solve", first, "--json"]) == 0  # reprocessed with the matrix it stores
    again = json.loads(capsys.readouterr().out)
    assert again["provenance"]["influence_matrix"] == f"{first} (stored matrix)"


def test_a_runs_file_mixing_typed_and_recorded_runs_is_refused(
    trial_runs: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    runs = trial_runs / "mixed.toml"
    runs.write_text(
        '[[runs]]\nfile = "r0.h5"\n[[runs]]\nsensors = [[1.0, 0.0], [1.0, 0.0]]\n'
        "trial = { plane = 1, mass_g = 20.0, angle_deg = 0.0 }\n"
    )
    assert main(["influence", str(runs)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "mixed: one kind per runs file" in err and str(runs) in err
