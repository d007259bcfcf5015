"""`stand inspect`, `stand record`, `stand convert` from the command line (main(argv))."""

from __future__ import annotations

import itertools
import json
import threading
import time
import uuid
from pathlib import Path

import can
import numpy as np
import pytest
from synth import sine_run

from stand.cli import main
from stand.drivers import Frames
from stand.drivers.bus import play
from stand.drivers.runs.logs import write_log
from stand.drivers.runs.recording import read_run

ROOT = Path(__file__).resolve().parents[2]
DEMO = ROOT / "examples" / "demo-stand.toml"


def _inspect(path: Path, capsys: pytest.CaptureFixture[str]) -> dict:
    assert main(["inspect", str(path), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_inspect_json_of_an_8_s_log(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "run.log"
    write_log(sine_run(seconds=8.0, rpm=900.0), path)
    out = _inspect(path, capsys)
    assert [n["node"] for n in out["nodes"]] == [1, 2]
    n1 = out["nodes"][0]
    assert {
        k: n1[k]
        for k in (
            "frames",
            "samples",
            "lost_frames",
            "invalid_samples",
            "marks",
            "rate_hz",
            "scale_um_s2",
            "flags",
        )
    } == {
        "frames": 10666,
        "samples": 31998,
        "lost_frames": 0,
        "invalid_samples": 0,
        "marks": 120,
        "rate_hz": 4000,
        "scale_um_s2": 100,
        "flags": [],
    }
    assert n1["rpm"] == pytest.approx(900.0, abs=1e-3)
    assert (out["unknown_frames"], out["bad_frames"]) == (0, 0)
    assert out["duration_s"] == pytest.approx(8.0, abs=1e-3)


def test_inspect_text_shows_the_table(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "run.blf"
    write_log(sine_run(seconds=2.0), path)
    assert main(["inspect", str(path)]) == 0
    out = capsys.readouterr().out
    assert "node   frames" in out and "900.00" in out


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        (
            "garbage.log",
            "(1.0) can0 101#0001020304050607\nthis is not a frame\n",
            "garbage.log:2: not a candump frame line",
        ),
        ("empty.log", "", "empty.log: no frames in the file"),
        (
            "other.log",
            "(1.0) can0 7E0#0001020304050607\n(1.1) can0 7E8#00\n",
            "other.log: no sensor-node frames: 2 frames, none with a protocol id",
        ),
        ("broken.h5", "\x89HDF\r\n\x1a\n and then nothing", "broken.h5: not a readable run file"),
        ("missing.log", None, "missing.log: no such file"),
    ],
)
def test_inspect_bad_input_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str, content: str | None, message: str
) -> None:
    path = tmp_path / name
    if content is not None:
        path.write_text(content)
    assert main(["inspect", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err


def test_convert_round_trips_through_every_format(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = tmp_path / "a.log"
    write_log(sine_run(seconds=2.0), src)
    chain = [src, tmp_path / "b.h5", tmp_path / "c.blf", tmp_path / "d.asc", tmp_path / "e.h5"]
    for a, b in itertools.pairwise(chain):
        assert main(["convert", str(a), str(b)]) == 0
    capsys.readouterr()
    first, last = _inspect(src, capsys), _inspect(chain[-1], capsys)
    assert first["nodes"] == last["nodes"]
    assert main(["convert", str(src), str(chain[1])]) == 2  # no silent overwrite
    assert "exists already" in capsys.readouterr().err


def _record_while_playing(argv: list[str], channel: str, frames: Frames) -> int:
    tx = can.Bus(interface="virtual", channel=channel)

    def player() -> None:
        time.sleep(0.4)  # the recorder opens its end of the bus first
        play(tx, frames)

    t = threading.Thread(target=player, daemon=True)
    t.start()
    try:
        return main(argv)
    finally:
        t.join()
        tx.shutdown()


@pytest.mark.realtime
def test_record_from_the_config_bus_with_an_override(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    channel = f"rec-{uuid.uuid4().hex}"
    out = tmp_path / "run.h5"
    frames = sine_run(seconds=1.0)
    code = _record_while_playing(
        [
            "record",
            "--config",
            str(DEMO),
            "-c",
            channel,
            "--out",
            str(out),
            "--seconds",
            "2",
            "--quiet",
            "--json",
        ],
        channel,
        frames,
    )
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    assert [n["frames"] for n in summary["nodes"]] == [1333, 1333]
    rec = read_run(out)
    assert np.array_equal(rec.frames.data, frames.data)
    assert rec.meta["config_toml"] == DEMO.read_text()
    assert json.loads(rec.meta["source"])["channel"] == channel
    assert rec.meta["complete"]


@pytest.mark.realtime
def test_record_keeps_what_came_when_the_frames_stop(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    channel = f"rec-{uuid.uuid4().hex}"
    out = tmp_path / "run.h5"
    code = _record_while_playing(
        [
            "record",
            "-i",
            "virtual",
            "-c",
            channel,
            "--out",
            str(out),
            "--timeout",
            "0.5",
            "--quiet",
        ],
        channel,
        sine_run(seconds=0.5),
    )
    assert code == 0  # the sender stopped: a normal end, every frame kept (noted as a warning)
    assert "no more frames for 0.5 s" in capsys.readouterr().err
    assert len(read_run(out).frames) == len(sine_run(seconds=0.5))


def test_record_with_no_bus_or_no_frames_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "run.h5"
    assert main(["record", "-i", "nosuch", "--out", str(out)]) == 2  # python-can's choices
    assert "invalid choice: 'nosuch'" in capsys.readouterr().err and not out.exists()
    assert main(["record", "-i", "kvaser", "-c", "0", "--out", str(out)]) == 2
    assert "cannot open the bus" in capsys.readouterr().err and not out.exists()
    assert (
        main(
            [
                "record",
                "-i",
                "virtual",
                "-c",
                uuid.uuid4().hex,
                "--out",
                str(out),
                "--timeout",
                "0.2",
                "--quiet",
            ]
        )
        == 2
    )
    assert "no frames at all" in capsys.readouterr().err and not out.exists()
    assert main(["record", "--out", str(out)]) == 2
    assert "no CAN interface given" in capsys.readouterr().err


def test_python_can_s_environment_is_the_last_fallback_for_the_bus(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """No [bus], no -i: python-can's CAN_INTERFACE names the interface (it was ignored)."""
    out = tmp_path / "run.h5"
    assert main(["record", "--out", str(out), "--timeout", "0.3"]) == 2
    assert "no CAN interface given" in capsys.readouterr().err
    monkeypatch.setenv("CAN_INTERFACE", "virtual")
    monkeypatch.setenv("CAN_CHANNEL", f"env-{uuid.uuid4().hex}")
    assert main(["record", "--out", str(out), "--timeout", "0.3"]) == 2
    err = capsys.readouterr().err
    assert "virtual interface joins buses inside one process only" in err, err
    assert not out.exists()
