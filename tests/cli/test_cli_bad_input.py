"""`stand solve`'s bad-input matrix: one line on stderr saying what and where, exit 2."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from stand.cli import main
from stand.config import config_toml
from stand.drivers import Recording, write_recording
from stand.drivers.frames import Frames
from stand.drivers.runs.logs import write_log
from stand.drivers.v1.protocol import MARK_BASE, SAMPLES_BASE, STATUS_BASE
from stand.sim import load_scene, simulate

ROOT = Path(__file__).resolve().parents[2]
DEMO_CFG = (ROOT / "examples" / "demo-stand.toml").read_text()


@pytest.fixture(scope="module")
def frames() -> Frames:
    sc, p, _ = load_scene("demo")
    return simulate(sc, p).frames


def _log(tmp_path: Path, f: Frames, name: str = "run.log") -> Path:
    path = tmp_path / name
    write_log(f, path)
    return path


def _cfg(tmp_path: Path, text: str = DEMO_CFG) -> Path:
    path = tmp_path / "cfg.toml"
    path.write_text(text)
    return path


def _case(tmp_path: Path, frames: Frames, case: str) -> tuple[list[str], str]:
    cfg = str(_cfg(tmp_path))
    kind = frames.can_id & 0x7C0
    if case == "missing file":
        return [str(tmp_path / "nope.h5")], "nope.h5: no such file"
    if case == "unknown extension":
        (tmp_path / "run.xyz").write_text("x")
        return [str(tmp_path / "run.xyz"), "--config", cfg], "unknown log format '.xyz'"
    if case == "empty log":
        (tmp_path / "run.log").write_text("")
        return [str(tmp_path / "run.log"), "--config", cfg], "node 1 sent nothing"
    if case == "truncated run file":
        path = tmp_path / "run.h5"
        write_recording(Recording("x", frames), path)
        path.write_bytes(path.read_bytes()[:5000])
        return [str(path)], "run.h5: not a readable run file"
    if case == "truncated log":
        path = _log(tmp_path, frames, "run.blf")
        path.write_bytes(path.read_bytes()[:3000])
        # its first frames are readable (read, with a warning): too few to measure
        return [str(path), "--config", cfg], "run.blf: node 1: only 2 reference edges"
    if case == "one node only":
        keep = (frames.can_id & 0xF) == 1
        return [str(_log(tmp_path, frames.take(keep))), "--config", cfg], "node 2 sent nothing"
    if case == "no STATUS":
        return (
            [str(_log(tmp_path, frames.take(kind != STATUS_BASE))), "--config", cfg],
            "node 1: no STATUS within 1.5 s",
        )
    if case == "no reference edges":
        return (
            [str(_log(tmp_path, frames.take(kind != MARK_BASE))), "--config", cfg],
            "node 1: no reference edges",
        )
    if case == "all samples invalid":
        f = frames.take(np.arange(len(frames)))  # a copy: the fixture is shared
        rows = f.can_id == SAMPLES_BASE + 1
        f.data[rows, 2:] = np.array([0x00, 0x80] * 3, np.uint8)
        return [str(_log(tmp_path, f)), "--config", cfg], "node 1: all 31998 samples are invalid"
    bad_cfg = {
        "config missing a key": (DEMO_CFG.replace("M3 = 60.0", ""), "[rotor.M3]: missing (give it"),
        "wrong type": (DEMO_CFG.replace("M3 = 60.0", 'M3 = "60"'), "[rotor.M3]: Input should be"),
        "negative mass": (DEMO_CFG.replace("M1 = 8.0", "M1 = -8.0"), "[stand.M1]"),
        "b + c = 0": (
            DEMO_CFG.replace("c = 0.70", "c = -0.85").replace("d = 0.20", "d = 1.0"),
            "correction planes 0 mm apart",
        ),
    }
    text, msg = bad_cfg[case]
    run = _log(tmp_path, frames)
    return [str(run), "--config", str(_cfg(tmp_path, text))], msg


CASES = [
    "missing file",
    "unknown extension",
    "empty log",
    "truncated run file",
    "truncated log",
    "one node only",
    "no STATUS",
    "no reference edges",
    "all samples invalid",
    "config missing a key",
    "wrong type",
    "negative mass",
    "b + c = 0",
]


@pytest.mark.parametrize("case", CASES)
def test_bad_input_is_one_line_and_exit_2(
    tmp_path: Path, frames: Frames, case: str, capsys: pytest.CaptureFixture[str]
) -> None:
    argv, message = _case(tmp_path, frames, case)
    before = sorted(p.name for p in tmp_path.iterdir())
    assert main(["solve", *argv, "--json"]) == 2, case
    captured = capsys.readouterr()
    assert captured.out == ""  # nothing half-written
    err = captured.err
    assert err.count("\n") == 1 and err.startswith("stand: error: "), err
    assert message in err, err
    assert "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_the_good_log_solves(
    tmp_path: Path, frames: Frames, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = [str(_log(tmp_path, frames)), "--config", str(_cfg(tmp_path)), "--json"]
    assert main(["solve", *argv]) == 0
    out: dict[str, Any] = json.loads(capsys.readouterr().out)
    assert out["planes"][0]["unbalance_g_mm"] == pytest.approx(5000, abs=10)


def test_config_toml_of_the_demo_round_trips() -> None:
    sc, _, _ = load_scene("demo")
    assert "[tolerance]" in config_toml(sc.config())


def test_a_batch_solves_in_parallel_and_writes_its_summary(
    tmp_path: Path, frames: Frames, capsys: pytest.CaptureFixture[str]
) -> None:
    import csv

    runs = []
    for i in range(3):
        path = tmp_path / f"r{i}.h5"
        assert main(["simulate", "demo", "--seed", str(i), "--out", str(path)]) == 0
        runs.append(str(path))
    (tmp_path / "bad.log").write_text("garbage\n")
    summary = tmp_path / "summary.csv"
    code = main(
        ["solve", *runs, str(tmp_path / "bad.log"), "--jobs", "2", "--summary", str(summary)]
    )
    assert code == 2  # one bad run: said, and the others still solved
    rows = list(csv.DictReader(summary.open()))
    assert [r["run"] for r in rows] == [*runs, str(tmp_path / "bad.log")]
    for r in rows[:3]:
        assert float(r["plane1_g_mm"]) == pytest.approx(5000, abs=15) and r["error"] == ""
        assert r["plane1_verdict"] == "fail" and r["verdict"] == "fail"
    assert "not a candump frame line" in rows[3]["error"]
    err = capsys.readouterr().err
    assert "1 of 4 runs could not be solved" in err
    js = tmp_path / "summary.json"
    assert main(["solve", *runs, "--summary", str(js)]) == 0
    assert set(json.loads(js.read_text())) == set(runs)
