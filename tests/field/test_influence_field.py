"""`stand influence` in N planes, several speeds, least squares, weighted or min-max."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]
PUBLISHED = ROOT / "examples" / "published"


def run_json(args: list[str], capsys: pytest.CaptureFixture[str]) -> dict:
    capsys.readouterr()
    assert main([*args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_the_published_cases_from_the_command_line(capsys: pytest.CaptureFixture[str]) -> None:
    """Goodman's 0.81 and 1.48 at 0 deg; Darlow's case 3 leaves plane 2 out; Foiles'
    min-max with every plane capped at 3.402 g (the core's tests hold the tolerances)."""
    out = run_json(["influence", str(PUBLISHED / "goodman-1964.toml")], capsys)
    got = [(p["weights"][0]["mass_g"], p["weights"][0]["angle_deg"]) for p in out["planes"]]
    assert got[0] == pytest.approx((0.81, 0.0), abs=0.005)
    assert got[1] == pytest.approx((1.48, 0.0), abs=0.005)
    out = run_json(["influence", str(PUBLISHED / "darlow-1982.toml")], capsys)
    assert [p["dependent"] for p in out["planes"]] == [False, True, False]
    assert out["planes"][1]["weights"] == [] and "plane 2" in out["warnings"][0]
    assert out["planes"][2]["weights"][0]["angle_deg"] == pytest.approx(205, abs=2)
    foiles = str(PUBLISHED / "foiles-2000.toml")
    ls = run_json(["influence", foiles], capsys)
    mm = run_json(["influence", foiles, "--method", "minmax", "--max-mass-g", "3.402"], capsys)
    assert mm["worst_after"] < 0.7 * ls["worst_after"]
    assert all(p["weights"][0]["mass_g"] <= 3.402 for p in mm["planes"])
    assert mm["planes"][0]["at_limit"] and mm["max_mass_g"] == 3.402


def _speeds_runs(folder: Path, extra: str = "", speeds: str = "[900, 900, 1500, 1500]") -> Path:
    """Two sensors at two speeds, three planes tried one at a time (made from a known
    matrix: each trial adds its column times 10 g at 0 deg)."""
    path = folder / "speeds.toml"
    path.write_text(
        extra
        + f"""
[[runs]]
sensors = [[10, 0], [8, 90], [30, 45], [20, 180]]
speeds_rpm = {speeds}
[[runs]]
trial = {{ plane = 1, mass_g = 10, angle_deg = 0 }}
sensors = [[14, 0], [8, 90], [40, 45], [20, 180]]
speeds_rpm = {speeds}
[[runs]]
trial = {{ plane = 2, mass_g = 10, angle_deg = 0 }}
sensors = [[10, 0], [12, 90], [30, 45], [25, 180]]
speeds_rpm = {speeds}
[[runs]]
trial = {{ plane = 3, mass_g = 10, angle_deg = 0 }}
sensors = [[12, 0], [10, 90], [30, 45], [35, 180]]
speeds_rpm = {speeds}
"""
    )
    return path


def test_readings_at_two_speeds_in_three_planes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Four readings (two sensors at 900 and 1500 rpm), three planes: each reading labelled
    with its sensor and speed; min-max's worst is at most least squares'; weighted least
    squares with the 1500 rpm readings weighted 10x leaves them smaller than plain least
    squares does."""
    runs = str(_speeds_runs(tmp_path))
    ls = run_json(["influence", runs], capsys)
    assert [(r["sensor"], r["speed_rpm"]) for r in ls["readings"]] == [
        (1, 900.0),
        (2, 900.0),
        (1, 1500.0),
        (2, 1500.0),
    ]
    mm = run_json(["influence", runs, "--method", "minmax"], capsys)
    assert mm["worst_after"] <= ls["worst_after"] + 1e-12
    weighted = _speeds_runs(tmp_path, "weights = [1, 1, 10, 10]\n")
    wls = run_json(["influence", str(weighted), "--method", "wls"], capsys)
    late = lambda out: sum(r["after"][0] ** 2 for r in out["readings"][2:])  # noqa: E731
    assert late(wls) < late(ls)
    capsys.readouterr()
    assert main(["influence", runs]) == 0
    text = capsys.readouterr().out
    assert "sensor 2 at 1500 rpm" in text and "plane 3: add" in text


@pytest.mark.parametrize(
    ("runs", "args", "says"),
    [
        ("matrix = [[[1, 0], [1, 0]]]\n[[runs]]\nsensors = [[1, 0], [2, 0]]\n", [],
         "[matrix]: 1 rows for 2 readings"),
        ("matrix = [[[1, 0], [1, 0]], [[1, 0]]]\n[[runs]]\nsensors = [[1, 0], [2, 0]]\n", [],
         "[matrix]: rows of different lengths"),
        ('[[runs]]\nsensors = [[1, 0], [2, 0], [3, 0]]\n[[runs]]\n'
         'sensors = [[2, 0], [2, 0], [3, 0]]\n'
         'trial = { plane = 1, mass_g = 1, angle_deg = 0 }\n[[runs]]\n'
         'sensors = [[1, 0], [2, 0], [5, 0]]\ntrial = { plane = 3, mass_g = 1, angle_deg = 0 }\n',
         [], "no trial run in plane(s) [2]"),
        ("SPEEDS", [], "[speeds_rpm]: speed 900 rpm is listed twice"),
        ('[[runs]]\nsensors = [[1, 0], [2, 0]]\nspeeds_rpm = [900]\n'
         'trial = { plane = 3, mass_g = 1, angle_deg = 0 }\n', [],
         "[runs[0].speeds_rpm]: 1 speeds for 2 readings"),
        ("matrix = [[[1, 0], [1, 90]], [[1, 0], [2, 0]]]\n[[runs]]\nsensors = [[1, 0], [2, 0]]\n",
         ["--method", "wls"], "[weights]: --method wls: give weights"),
        ("weights = [1]\nmatrix = [[[1, 0], [1, 90]], [[1, 0], [2, 0]]]\n[[runs]]\n"
         "sensors = [[1, 0], [2, 0]]\n", ["--method", "wls"],
         "[weights]: 1 weights for 2 readings"),
        ("matrix = [[[1, 0]], [[1, 0]]]\n[[runs]]\nsensors = [[1, 0], [2, 0]]\n[[runs]]\n"
         "sensors = [[1, 0], [2, 0]]\ntrial = { plane = 1, mass_g = 1, angle_deg = 0 }\n", [],
         "[runs]: with the matrix typed in, give only the initial run"),
        ("matrix = [[[1, 0]], [[1, 0]]]\n[[runs]]\nsensors = [[1, 0], [2, 0]]\n",
         ["--max-mass-g", "-1"], "--max-mass-g"),
    ],
)  # fmt: skip
def test_bad_runs_files_are_one_line_naming_the_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], runs: str, args: list[str], says: str
) -> None:
    if runs == "SPEEDS":
        path = _speeds_runs(tmp_path, speeds="[900, 1500, 900, 1500]")
    else:
        path = tmp_path / "bad.toml"
        path.write_text(runs)
    capsys.readouterr()
    assert main(["influence", str(path), *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err, err
    assert "Traceback" not in err


def test_recorded_runs_at_two_speeds_give_the_scene_s_unbalance_back(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Trial runs recorded at 600 and 800 rpm (one run file per speed): four readings, two
    planes; the correction cancels the demo scene's 5000 g mm at 30 deg and 3000 at 200 deg
    (within 2 %, 2 deg: the runs' noise through the trial runs' matrix)."""
    runs = []
    for name, add in (("r0", []), ("t1", ["--add", "1:20@0"]), ("t2", ["--add", "2:20@0"])):
        files = []
        for rpm in ("600", "800"):
            path = tmp_path / f"{name}-{rpm}.h5"
            assert main(["simulate", "demo", "--rpm", rpm, *add, "--out", str(path)]) == 0
            files.append(path.name)
        runs.append(files)
    (tmp_path / "runs.toml").write_text(
        f"[[runs]]\nfile = {runs[0]}\n"
        f"[[runs]]\nfile = {runs[1]}\ntrial = {{ plane = 1, mass_g = 20, angle_deg = 0 }}\n"
        f"[[runs]]\nfile = {runs[2]}\ntrial = {{ plane = 2, mass_g = 20, angle_deg = 0 }}\n"
    )
    out = run_json(["influence", str(tmp_path / "runs.toml"), "--method", "wls"], capsys)
    assert [(r["sensor"], round(r["speed_rpm"])) for r in out["readings"]] == [
        (1, 600),
        (2, 600),
        (1, 800),
        (2, 800),
    ]
    want = [(5000, 30), (3000, 200)]
    for p, (g_mm, deg) in zip(out["planes"], want, strict=True):
        assert p["unbalance_mass_g"] * p["radius_mm"] == pytest.approx(g_mm, rel=0.02)
        assert abs((p["unbalance_angle_deg"] - deg + 180) % 360 - 180) < 2
    (tmp_path / "twice.toml").write_text(f"[[runs]]\nfile = {[runs[0][0], runs[0][0]]}\n")
    capsys.readouterr()
    assert main(["influence", str(tmp_path / "twice.toml")]) == 2
    assert "one run file per speed" in capsys.readouterr().err


def test_a_matrix_of_several_speeds_is_stored_and_not_taken_for_one_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--save stores the readings' speeds with the matrix; `stand solve --matrix` refuses it
    in one line (it serves the runs file, not one run's two-plane answer)."""
    saved = tmp_path / "m.json"
    assert main(["influence", str(_speeds_runs(tmp_path)), "--save", str(saved)]) == 0
    doc = json.loads(saved.read_text())
    assert doc["speeds_rpm"] == [900.0, 900.0, 1500.0, 1500.0]
    run = tmp_path / "r.h5"
    assert main(["simulate", "demo", "--out", str(run)]) == 0
    capsys.readouterr()
    assert main(["solve", str(run), "--matrix", str(saved)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "[speeds_rpm]" in err, err
