"""Hostile inputs: stray frames, configs that try to open files, log writers that lose
frames, formats whose package is missing."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np
import pytest

from stand.cli import main
from stand.drivers import read_recording
from stand.drivers.frames import Frames
from stand.drivers.v1.protocol import SAMPLES_BASE

ROOT = Path(__file__).resolve().parents[2]
CFG = (ROOT / "examples" / "demo-stand.toml").read_text()


def test_a_stray_frame_from_an_unused_node_is_left_aside(
    demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One SAMPLES frame from node 3 (no STATUS) refused the whole run ("node 3: no STATUS")."""
    f = read_recording(demo_run).frames
    stray = Frames(
        f.t_s[:1] + 1.0, np.array([SAMPLES_BASE + 3], np.uint32), f.dlc[:1], f.data[:1], f.flags[:1]
    )
    log = tmp_path / "stray.log"
    from stand.drivers.runs.logs import write_log

    write_log(Frames.concat([f, stray]), log)
    cfg = tmp_path / "cfg.toml"
    cfg.write_text(CFG)
    assert main(["solve", str(log), "--config", str(cfg), "--json"]) == 0
    out = capsys.readouterr().out
    assert "node 3: no STATUS" in out and "not a support node" in out


@pytest.mark.parametrize(
    "channel", ["spy://loop://?file=victim.txt", "loop://", "socket://localhost:1", "rfc2217://x:1"]
)
def test_a_url_channel_is_refused_unless_the_command_line_allows_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], channel: str
) -> None:
    """`[bus] interface = "slcan", channel = "spy://loop://?file=victim.txt"` truncated
    victim.txt (pyserial's URL handlers open files)."""
    victim = tmp_path / "victim.txt"
    victim.write_text("kept")
    cfg = tmp_path / "cfg.toml"
    bus = f'[bus]\ninterface = "slcan"\nchannel = "{channel}"\n'
    i = CFG.index("[bus]")  # the last table of the example
    cfg.write_text(CFG[:i] + bus)
    out = tmp_path / "r.h5"
    assert main(["record", "--config", str(cfg), "--out", str(out), "--timeout", "0.2"]) == 2
    err = capsys.readouterr().err
    assert "is a URL" in err and "--allow-url-channel" in err
    assert victim.read_text() == "kept" and not out.exists()
    # a file cannot allow it for itself
    cfg.write_text(cfg.read_text().replace(bus, bus + "allow_url_channel = true\n"))
    assert main(["record", "--config", str(cfg), "--out", str(out), "--timeout", "0.2"]) == 2
    assert "a file cannot allow URL channels" in capsys.readouterr().err


def test_a_db_log_holds_every_frame(
    demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """python-can's SQLite writer kept 2004 of 21588 frames, and "wrote" was said."""
    out = tmp_path / "run.db"
    assert main(["convert", str(demo_run), str(out)]) == 0
    with sqlite3.connect(out) as conn:
        assert conn.execute("SELECT COUNT(*) FROM messages").fetchone()[0] == 21588
    assert len(read_recording(out).frames) == 21588


def test_a_format_whose_package_is_missing_names_the_extra(
    demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("can")
    try:
        import asammdf  # noqa: F401

        pytest.skip("asammdf is installed here")
    except ImportError:
        pass
    assert main(["convert", str(demo_run), str(tmp_path / "run.mf4")]) == 2
    err = capsys.readouterr().err
    assert "pip install 'python-can[mf4]'" in err and "internal error" not in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("cut", [4, 12, 30])
def test_a_candump_log_cut_mid_line_is_read_with_a_warning(
    demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], cut: int
) -> None:
    """A killed candump leaves its last line cut short: it was refused whole."""
    log = tmp_path / "run.log"
    assert main(["convert", str(demo_run), str(log)]) == 0
    text = log.read_bytes()
    log.write_bytes(text[: len(text) - cut])
    capsys.readouterr()
    assert main(["inspect", str(log)]) == 0
    err = capsys.readouterr().err
    assert "cut short: left out" in err or "malformed protocol frame" in err, err


def test_an_interface_without_its_driver_leaves_no_run_behind(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """kvaser without its library raised NameError and left an empty run file that
    blocked the retry."""
    out = tmp_path / "r.h5"
    for _ in range(2):  # the retry meets the same clean error, not "exists already"
        assert main(["record", "-i", "kvaser", "-c", "0", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert "cannot open the bus" in err and "internal error" not in err
        assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("ext", "after"), [(".trc", 20), (".asc", 7)])
def test_a_text_log_counts_the_lines_it_skips_and_names_the_first(
    demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], ext: str, after: int
) -> None:
    """Garbage lines in .asc and .trc logs were skipped without a word."""
    log = tmp_path / f"run{ext}"
    assert main(["convert", str(demo_run), str(log)]) == 0
    lines = log.read_text().splitlines(keepends=True)
    lines[after:after] = ["this is not a frame\n", "nor is this\n"]
    log.write_text("".join(lines))
    capsys.readouterr()
    assert main(["inspect", str(log)]) == 0
    err = capsys.readouterr().err
    assert f"{log}:{after + 1}: 2 line(s) that are not frames were left out" in err, err


def test_frames_of_the_wrong_length_are_named_not_called_no_samples(
    demo_run: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Node 1's SAMPLES frames all of DLC 7 were reported as "no samples"."""
    f = read_recording(demo_run).frames
    dlc = f.dlc.copy()
    dlc[f.can_id == SAMPLES_BASE + 1] = 7
    log = tmp_path / "dlc7.log"
    from stand.drivers.runs.logs import write_log

    write_log(Frames(f.t_s, f.can_id, dlc, f.data, f.flags), log)
    cfg = tmp_path / "cfg.toml"
    cfg.write_text(CFG)
    assert main(["solve", str(log), "--config", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert "node 1: no samples" in err and "wrong length: DLC 7, expected 8" in err, err
