"""`stand simulate` and `stand scenes` from the command line."""

from __future__ import annotations

import json
import threading
import time
import tomllib
import uuid
from pathlib import Path

import numpy as np
import pytest

from stand.cli import main
from stand.config import config_from_dict
from stand.drivers.runs.recording import read_recording, read_run
from stand.sim import load_scene, shipped_scenes, simulate


def test_scenes_lists_the_shipped_scenes(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["scenes", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == set(shipped_scenes()) >= {"demo", "small-fast", "heavy", "near-resonance"}
    assert out["run-up"]["physics"] == "integrate" and out["demo"]["effects"] == ["noise"]
    assert main(["scenes"]) == 0
    assert "demo" in capsys.readouterr().out


@pytest.mark.parametrize("suffix", [".h5", ".log", ".blf", ".asc"])
def test_simulate_writes_the_run_in_the_format_of_the_extension(
    tmp_path: Path, suffix: str, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / f"demo{suffix}"
    assert main(["simulate", "demo", "--out", str(out)]) == 0
    rec = read_recording(out)
    sc, p, _ = load_scene("demo")
    want = simulate(sc, p).frames
    assert np.array_equal(rec.frames.data, want.data)
    assert np.array_equal(rec.frames.can_id, want.can_id)
    if suffix == ".h5":  # the run carries the config that solves it
        cfg, params = config_from_dict(tomllib.loads(read_run(out).meta["config_toml"]))
        assert cfg == sc.config() and params == p


def test_simulate_seed_and_refusals(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    assert main(["simulate", "demo", "--out", str(a)]) == 0
    assert main(["simulate", "demo", "--out", str(b), "--seed", "5"]) == 0
    assert not np.array_equal(read_run(a).frames.data, read_run(b).frames.data)
    capsys.readouterr()
    assert main(["simulate", "demo", "--out", str(a)]) == 2
    assert "exists already" in capsys.readouterr().err
    assert main(["simulate", "demo"]) == 2
    assert "give --out FILE, --bus, or both" in capsys.readouterr().err
    assert main(["simulate", "no-such-scene", "--out", str(tmp_path / "c.h5")]) == 2
    assert "no such scene" in capsys.readouterr().err


@pytest.mark.realtime
def test_simulate_on_the_bus_is_what_record_receives(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scene = tmp_path / "short.toml"
    text = Path(str(shipped_scenes()["demo"])).read_text().replace("seconds = 8.0", "seconds = 1.5")
    scene.write_text(text)
    channel = uuid.uuid4().hex
    out = tmp_path / "rec.h5"

    def player() -> None:
        time.sleep(0.5)
        main(["simulate", str(scene), "--bus", "-c", channel])

    t = threading.Thread(target=player)
    t.start()
    code = main(
        ["record", "-i", "virtual", "-c", channel, "--out", str(out), "--timeout", "1", "--quiet"]
    )
    t.join()
    assert code == 0  # it ended normally when the frames stopped, keeping them
    sc, p, _ = load_scene(scene)
    assert np.array_equal(read_run(out).frames.data, simulate(sc, p).frames.data)
