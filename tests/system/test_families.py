"""Every command that takes a run file, on a run of every family of the registry recorded
from the same scene: the same answer as protocol v1's within the two answers' intervals.
``solve``, ``report``, ``inspect``, ``convert`` (to a candump log and back), ``tooling
measure`` (the index runs), ``influence`` (trial runs), ``autobalance test``,
``calibrate``, ``reprocess``; the live commands and the station read each family through
the same builders (``tests/live/test_source.py``, the realtime tests of each family).

A family's runs are the shipped scenes (the demo, the tooling's index runs, trial runs)
played through that family's simulated hardware (``[nodes] protocol``); each command
reads its run once and decodes it with the family its stored config names
(``stand.solve.acquisition``).  Tolerances: two estimates of one truth with 95 % radii
``u1`` and ``u2`` differ by at most ``sqrt(u1^2 + u2^2)`` in 95 % of draws; each check
here is of one estimate per plane, so 1.5 times that is held (a chance failure below
1e-4 per plane); the rpm within 0.5 % (the scenes' speed is exact; the receive clock of a
2 s run is read to 1e-5)."""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path
from typing import Any

import pytest
import tomlkit
from protocols import holds_the_demo, solve_json

from stand.cli import main
from stand.drivers.family import FAMILIES
from stand.sim import shipped_scenes

HARDWARE: dict[str, dict[str, Any]] = {
    "v1": {},
    "scan": {"protocol": "scan", "rate_hz": 2000},
    "canopen": {"protocol": "canopen", "rate_hz": 2000},
}
"""The ``[nodes]`` keys that put each family's simulated hardware on the stand."""


def test_every_registered_family_is_tested_here() -> None:
    assert set(HARDWARE) == set(FAMILIES)


def scene_of(folder: Path, name: str, fam: str, seconds: float = 2.0) -> Path:
    """The shipped scene ``name`` through family ``fam``'s hardware, ``seconds`` long."""
    data = tomllib.loads(Path(str(shipped_scenes()[name])).read_text())
    data["run"]["seconds"] = seconds
    data.setdefault("nodes", {}).update(HARDWARE[fam])
    path = folder / f"{name}-{fam}.toml"
    path.write_text(tomlkit.dumps(data))
    return path


def _vector(p: dict[str, Any], amount: str = "unbalance_g_mm") -> complex:
    return complex(p[amount] * math.cos(math.radians(p["angle_deg"])),
                   -p[amount] * math.sin(math.radians(p["angle_deg"])))  # fmt: skip


def same_within(a: list[dict[str, Any]], b: list[dict[str, Any]], amount: str = "unbalance_g_mm",
                radius: str = "uncertainty_g_mm") -> None:  # fmt: skip
    """Plane by plane, the two answers within 1.5 x their combined 95 % radius."""
    for pa, pb in zip(a, b, strict=True):
        bound = 1.5 * math.hypot(pa[radius], pb[radius])
        assert abs(_vector(pa, amount) - _vector(pb, amount)) <= bound, (pa, pb)


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Per family: the demo run, the tooling's index runs, a trial run per plane."""
    out: dict[str, Path] = {}
    for fam in FAMILIES:
        d = tmp_path_factory.mktemp(fam)
        demo, tooling = scene_of(d, "demo", fam), scene_of(d, "tooling", fam)
        jobs = {
            "demo": [str(demo)],
            "t0": [str(tooling)],
            "t180": [str(tooling), "--index", "180"],
            "trial1": [str(demo), "--add", "1:20@210"],  # against the unbalance: in range
            "trial2": [str(demo), "--add", "2:20@20"],
        }
        for key, argv in jobs.items():
            run = d / f"{key}.h5"
            assert main(["simulate", *argv, "--out", str(run)]) == 0
            out[f"{fam}/{key}"] = run
    return out


@pytest.fixture(autouse=True)
def _quiet(capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()


@pytest.mark.parametrize("fam", list(FAMILIES))
def test_solve_and_report(fam: str, runs: dict[str, Path],
                          capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:  # fmt: skip
    capsys.readouterr()
    got, v1 = (solve_json(runs[f"{f}/demo"], capsys) for f in (fam, "v1"))
    holds_the_demo(got)
    same_within(got["planes"], v1["planes"])
    html = tmp_path / "r.html"
    assert main(["report", str(runs[f"{fam}/demo"]), "-o", str(html)]) == 0
    assert html.stat().st_size > 10_000


@pytest.mark.parametrize("fam", list(FAMILIES))
def test_inspect_and_convert_to_a_log_and_back(
    fam: str, runs: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run, cfg = runs[f"{fam}/demo"], tmp_path / "own.toml"
    capsys.readouterr()
    assert main(["inspect", str(run), "--json"]) == 0
    seen = json.loads(capsys.readouterr().out)
    assert main(["inspect", str(run), "--config-out", str(cfg)]) == 0
    assert [n["node"] for n in seen["nodes"]] == [1, 2]
    assert all(n["rpm"] == pytest.approx(900.0, rel=5e-3) for n in seen["nodes"])
    log = tmp_path / "run.log"
    assert main(["convert", str(run), str(log)]) == 0
    capsys.readouterr()
    # a log carries no config: the family is the given config's (its description files
    # beside it: the stored config names them by absolute path, the shipped ones)
    from_log = solve_json(log, capsys, "--config", str(cfg))
    from_run = solve_json(run, capsys)
    for a, b in zip(from_log["planes"], from_run["planes"], strict=True):
        # candump logs keep times to the microsecond: the same samples, the same answer
        assert a["unbalance_g_mm"] == pytest.approx(b["unbalance_g_mm"], rel=1e-6)


@pytest.mark.parametrize("fam", list(FAMILIES))
def test_tooling_measure(fam: str, runs: dict[str, Path], tmp_path: Path,
                         capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    def measured(f: str, tag: str) -> dict[str, Any]:
        folder = tmp_path / tag
        argv = ["tooling", "measure", str(runs[f"{f}/t0"]), str(runs[f"{f}/t180"]),
                "--folder", str(folder), "--name", "mandrel", "--json",
                "--archive", f"sqlite:///{tmp_path / tag}.db"]  # fmt: skip
        capsys.readouterr()
        assert main(argv) == 0
        out: dict[str, Any] = json.loads(capsys.readouterr().out)
        return out

    got, v1 = measured(fam, "got"), measured("v1", "v1")
    for a in got["tooling"]:  # the scene's mandrel: 800 g mm in each plane
        assert a["unbalance_g_mm"] == pytest.approx(800.0, abs=1.5 * a["uncertainty_g_mm"])
    same_within(got["tooling"], v1["tooling"])


@pytest.mark.parametrize("fam", list(FAMILIES))
def test_influence_from_trial_runs(fam: str, runs: dict[str, Path], tmp_path: Path,
                                   capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    def corrections(f: str) -> dict[str, Any]:
        text = f'[[runs]]\nfile = "{runs[f"{f}/demo"]}"\n'
        for plane, deg in ((1, 210.0), (2, 20.0)):
            text += f'[[runs]]\nfile = "{runs[f"{f}/trial{plane}"]}"\n'
            text += f"trial = {{ plane = {plane}, mass_g = 20.0, angle_deg = {deg} }}\n"
        path = tmp_path / f"{f}.toml"
        path.write_text(text)
        capsys.readouterr()
        assert main(["influence", str(path), "--json"]) == 0
        out: dict[str, Any] = json.loads(capsys.readouterr().out)
        return out

    got, v1 = corrections(fam), corrections("v1")
    assert len(got["planes"]) == len(v1["planes"]) == 2
    for a, b in zip(got["planes"], v1["planes"], strict=True):  # the demo's 55.5 g / 37.5 g
        assert a["mass_g"] == pytest.approx(b["mass_g"], rel=0.05)
        assert abs((a["angle_deg"] - b["angle_deg"] + 180) % 360 - 180) < 3.0


def _balls(folder: Path, fam: str) -> tuple[list[Path], Path]:
    """Two starts of the demo-balls scene, 20 s each, through family ``fam``; their config."""
    scene = scene_of(folder, "demo-balls", fam, seconds=20.0)
    assert main(["simulate", str(scene), "--starts", "2", "--out-dir", str(folder / fam)]) == 0
    starts = [folder / fam / f"start-0{k}.h5" for k in (1, 2)]
    cfg = folder / f"balls-{fam}.toml"
    assert main(["inspect", str(starts[0]), "--config-out", str(cfg)]) == 0
    return starts, cfg


@pytest.mark.parametrize("fam", [f for f in FAMILIES if f != "v1"])
def test_autobalance_test(fam: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The balls' acceptance test (its starts 20 s: unsettled, both ways, so exit 1) gives
    each start's residual of v1's run of the same starts, and the same verdict."""
    out = {}
    for f in ("v1", fam):
        starts, cfg = _balls(tmp_path, f)
        capsys.readouterr()
        argv = ["autobalance", "test", *map(str, starts), "--config", str(cfg), "--json",
                "--no-archive"]  # fmt: skip
        assert main(argv) == 1
        out[f] = json.loads(capsys.readouterr().out)
    assert out[fam]["verdict"] == out["v1"]["verdict"]
    for a, b in zip(out[fam]["starts"], out["v1"]["starts"], strict=True):
        same_within(a["residual"], b["residual"])


def _proving(folder: Path, fam: str) -> Path:
    """The new-stand scene's proving rotor bare and with 20 g in each plane, at 700 and 1100
    rpm, through ``fam``; the runs file for stand calibrate."""
    lines = []
    for rpm in (700, 1100):
        for name, add in (
            ("bare", []),
            ("t1", ["--add", "1:20@90"]),
            ("t2", ["--add", "2:20@300"]),
        ):
            scene = tomllib.loads(scene_of(folder, "new-stand", fam, seconds=4.0).read_text())
            scene["run"]["rpm"] = float(rpm)
            path = folder / f"{name}{rpm}.toml"
            path.write_text(tomlkit.dumps(scene))
            run = folder / f"{name}{rpm}.h5"
            assert main(["simulate", str(path), *add, "--out", str(run)]) == 0
            masses = "[]" if not add else (
                f"[{{ plane = {add[1][0]}, mass_g = 20.0, angle_deg = {add[1].split('@')[1]}.0 }}]"
            )  # fmt: skip
            lines.append(f'[[runs]]\nfile = "{run.name}"\nmasses = {masses}\n')
    (folder / "calib.toml").write_text("\n".join(lines))
    return folder / "calib.toml"


@pytest.mark.parametrize("fam", [f for f in FAMILIES if f != "v1"])
def test_calibrate(fam: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The stand identified from each family's proving runs: every parameter within the two
    identifications' combined 4 standard errors of v1's."""
    got = {}
    for f in ("v1", fam):
        d = tmp_path / f
        d.mkdir()
        runs = _proving(d, f)
        own = d / "own.toml"
        assert main(["inspect", str(d / "bare700.h5"), "--config-out", str(own)]) == 0
        start = tomllib.loads(own.read_text())
        start["stand"].update({"M1": 5.0, "C2": 7e4, "reference_angle_deg": 0.0})
        own.write_text(tomlkit.dumps(start))
        capsys.readouterr()
        argv = ["calibrate", str(runs), "--config", str(own), "--out", str(d / "cal.toml"),
                "--json"]  # fmt: skip
        assert main(argv) == 0
        got[f] = json.loads(capsys.readouterr().out)
    a, b = got[fam], got["v1"]
    for name, value in b["values"].items():
        bound = 4 * math.hypot(a["std_errors"][name], b["std_errors"][name])
        assert abs(a["values"][name] - value) <= bound, (name, a["values"][name], value, bound)


@pytest.mark.parametrize("fam", list(FAMILIES))
def test_reprocess(fam: str, runs: dict[str, Path], tmp_path: Path,
                   capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    """A run archived, then re-judged into a revision: the revision's answer is v1's."""

    def revised(f: str, tag: str) -> list[dict[str, Any]]:
        url = f"sqlite:///{tmp_path / tag}.db"
        assert main(["archive", "import", str(runs[f"{f}/demo"]), "--archive", url]) == 0
        capsys.readouterr()
        assert main(["reprocess", "--archive", url, "--revision", "r1", "--json"]) == 0
        done = json.loads(capsys.readouterr().out)["runs"]
        assert [r["status"] for r in done] == ["ok"]
        planes: list[dict[str, Any]] = done[0]["after"]["planes"]
        return planes

    same_within(revised(fam, "got"), revised("v1", "v1"))
