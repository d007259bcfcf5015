"""A scan-stream module described by a DBC (``[bus] protocol = "scan"``): the demo scene
through the simulated module, solved with the example config; lost frames with and
without a counter; the spread against the Cramer-Rao bound; bad mappings."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from protocols import holds_the_demo, short_scene, solve_json

from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "examples" / "scan-stand.toml"


def test_the_demo_through_a_scan_module_solves_to_its_unbalance(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """8 s of the demo-scan scene: solved with its stored config and with
    examples/scan-stand.toml, the scene's unbalance inside the 95 % circles."""
    run = tmp_path / "s.h5"
    assert main(["simulate", "demo-scan", "--out", str(run)]) == 0
    capsys.readouterr()
    stored = solve_json(run, capsys)
    holds_the_demo(stored)
    given = solve_json(run, capsys, "--config", str(CONFIG))
    assert given["planes"] == stored["planes"]


def _drop(run: Path, out: Path, keep: np.ndarray) -> None:
    """A copy of a run file without the frames where ``keep`` is false (as a bus loses them)."""
    from stand.drivers import read_recording, write_recording

    rec = read_recording(str(run))
    rec = type(rec)(rec.path, rec.frames.take(keep), rec.meta, rec.warnings)
    write_recording(rec, str(out))


def test_a_lost_frame_with_a_counter_is_a_lost_sample_in_place(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """1 % of the frames dropped at random and a burst of 300 (0.15 s: two marks lost with
    them): the counter keeps every later sample in its place and the turns are counted
    across the gap, so the answer stays inside its circle and the angles move less than
    0.05 deg from the complete recording's."""
    run, cut = tmp_path / "s.h5", tmp_path / "cut.h5"
    assert main(["simulate", str(short_scene(tmp_path, "demo-scan")), "--out", str(run)]) == 0
    capsys.readouterr()
    whole = solve_json(run, capsys)
    from stand.drivers import read_recording

    n = len(read_recording(str(run)).frames)
    keep = np.random.default_rng(3).random(n) >= 0.01
    keep[1000:1300] = False
    _drop(run, cut, keep)
    lost = solve_json(cut, capsys)
    holds_the_demo(lost)
    for a, b in zip(whole["planes"], lost["planes"], strict=True):
        assert abs((a["angle_deg"] - b["angle_deg"] + 180) % 360 - 180) < 0.05
    from stand.config import load_config
    from stand.config.bus import bus_choice
    from stand.drivers.scan.codec import scan_streams
    from stand.drivers.scan.layout import load_layout

    cfg = load_config(CONFIG)[0]
    layout = load_layout(bus_choice(cfg.bus, str(CONFIG)).table, CONFIG.parent, str(CONFIG))
    streams = scan_streams(read_recording(str(cut)).frames, layout)
    assert streams.nodes[1].lost_frames == int(np.count_nonzero(~keep))


def test_without_a_counter_a_gap_flags_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A module that sends no counter: complete, no flag; with frames lost, the receive
    times show the gap and the run is flagged."""
    run, cut = tmp_path / "s.h5", tmp_path / "cut.h5"
    assert (
        main(
            ["simulate", str(short_scene(tmp_path, "demo-scan", counter=False)), "--out", str(run)]
        )
        == 0
    )
    capsys.readouterr()
    whole = solve_json(run, capsys)
    assert not [w for w in whole["warnings"] if "without a counter" in w]
    holds_the_demo(whole)
    from stand.drivers import read_recording

    keep = np.ones(len(read_recording(str(run)).frames), bool)
    keep[1500:1503] = False
    _drop(run, cut, keep)
    flagged = solve_json(cut, capsys)
    said = [w for w in flagged["warnings"] if "without a counter" in w]
    assert len(said) == 1 and "1 gap(s)" in said[0], flagged["warnings"]


def test_the_spread_sits_at_the_cramer_rao_bound(tmp_path: Path) -> None:
    """100 runs of 2 s at 2 kHz: the support 1 phasor's spread (both components) within 1.2x
    of sqrt(2 sigma^2 / N), sigma the sensor noise with the module's quantization (q^2/12);
    100 runs estimate a standard deviation to about 7 % (1.2 is 2.8 of those above 1)."""
    from stand.config.bus import bus_choice
    from stand.drivers.scan.codec import scan_streams
    from stand.drivers.scan.layout import load_layout
    from stand.sim import load_scene, simulate
    from stand.sim.scan_emit import SENSITIVITY_M_S2_PER_V, VOLTS_PER_COUNT
    from stand.solve import SolveOptions, measure_streams

    sc, p, _ = load_scene("demo-scan")
    cfg = sc.config()
    layout = load_layout(bus_choice(cfg.bus, "demo-scan").table, Path("."), "demo-scan")
    phasors = []
    for seed in range(100):
        run = sc.run.model_copy(update={"seconds": 2.0, "seed": seed})
        frames = simulate(sc.model_copy(update={"run": run}), p).frames
        m = measure_streams(scan_streams(frames, layout), cfg, p, SolveOptions())
        phasors.append(m.supports[0].A_m_s2)
    z = np.array(phasors)
    q = VOLTS_PER_COUNT * SENSITIVITY_M_S2_PER_V
    sigma2 = (0.001 * math.sqrt(2000 / 2)) ** 2 + q**2 / 12
    bound = math.sqrt(2 * sigma2 / (2.0 * 2000))
    for part in (z.real, z.imag):
        assert 1 / 1.2 < np.std(part, ddof=1) / bound < 1.2


@pytest.mark.parametrize(
    ("edit", "says"),
    [
        (('signal = "ai3"', 'signal = "ai9"'), "has no signal 'ai9'"),
        (('role = "mark"\n', 'role = "accel"\nsupport = 1\n'), "exactly one channel for the mark"),
        (('dbc = "../drivers/scan/scan_module.dbc"', 'dbc = "nope.dbc"'), "cannot read"),
        (('protocol = "scan"', 'protocol = "canbus"'), "[bus] protocol"),
        (('counter = "counter"', 'counter = "ctr"'), "has no signal 'ctr'"),
    ],
)
def test_bad_mappings_are_one_line(
    edit: tuple[str, str], says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "s.h5"
    assert main(["simulate", str(short_scene(tmp_path, "demo-scan")), "--out", str(run)]) == 0
    capsys.readouterr()
    text = CONFIG.read_text()
    assert edit[0] in text
    bad = tmp_path / "bad.toml"
    (tmp_path / "scan_module.dbc").write_text(
        (ROOT / "drivers" / "scan" / "scan_module.dbc").read_text()
    )
    bad.write_text(text.replace(edit[0], edit[1]).replace("../drivers/scan/scan_module.dbc",
                                                          "scan_module.dbc"))  # fmt: skip
    assert main(["solve", str(run), "--config", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err, err


@pytest.mark.realtime
def test_a_live_balance_reads_the_module(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`stand balance --scene demo-scan` plays the module's frames on a virtual bus in real
    time and measures them live to the precision it needs; its run file solves again; a
    config of the other protocol is refused in one line."""
    run = tmp_path / "b.h5"
    argv = ["balance", "--scene", "demo-scan", "--out", str(run), "--json", "--quiet"]
    assert main(argv) == 0
    live = json.loads(capsys.readouterr().out)
    holds_the_demo(live)
    assert live["stopped_by"] == "precision"
    again = solve_json(run, capsys)
    holds_the_demo(again)
    v1 = str(ROOT / "examples" / "demo-stand.toml")
    assert main([*argv[:3], "--config", v1, "--out", str(tmp_path / "c.h5")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "sends protocol scan frames" in err, err


def test_a_run_the_mapping_does_not_fit_is_one_line(
    tmp_path: Path, demo_run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A protocol v1 run solved as a scan module's (no frame of its message), and a mark
    threshold the mark never crosses: one line each, exit 2, never a traceback."""
    assert main(["solve", str(demo_run), "--config", str(CONFIG)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "sent nothing" in err, err
    run = tmp_path / "s.h5"
    assert main(["simulate", str(short_scene(tmp_path, "demo-scan")), "--out", str(run)]) == 0
    capsys.readouterr()
    high = tmp_path / "high.toml"
    high.write_text(CONFIG.read_text().replace("mark_threshold = 2.5", "mark_threshold = 9.5")
                    .replace("../drivers/", str(ROOT / "drivers") + "/"))  # fmt: skip
    assert main(["solve", str(run), "--config", str(high)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no reference edges" in err, err


def test_can_fd_frames_of_eight_scans(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The module sending CAN FD frames of 8 scans (64 bytes, 250 a second at 2 kHz):
    solved with its stored config, the demo in its circles and the same answer as a
    classic frame a scan to 1e-9 (the same samples); 3 frames (24 scans) lost with the
    counter: lost in place, counted; without the counter: flagged; read with a config of
    one scan a frame: one line naming the key."""
    classic, fd = tmp_path / "c.h5", tmp_path / "fd.h5"
    assert main(["simulate", str(short_scene(tmp_path, "demo-scan")), "--out", str(classic)]) == 0
    assert main(["simulate", str(short_scene(tmp_path, "demo-scan", scans_per_frame=8)),
                 "--out", str(fd)]) == 0  # fmt: skip
    capsys.readouterr()
    a, b = solve_json(classic, capsys), solve_json(fd, capsys)
    holds_the_demo(b)
    for p, q in zip(a["planes"], b["planes"], strict=True):
        assert p["unbalance_g_mm"] == pytest.approx(q["unbalance_g_mm"], rel=1e-9)
    from stand.drivers import read_recording

    frames = read_recording(str(fd)).frames
    assert len(frames) == 500 and set(frames.dlc.tolist()) == {64}
    keep = np.ones(len(frames), bool)
    keep[200:203] = False
    cut = tmp_path / "cut.h5"
    _drop(fd, cut, keep)
    assert main(["inspect", str(cut), "--json"]) == 0
    nodes = json.loads(capsys.readouterr().out)["nodes"]
    assert [n["lost_frames"] for n in nodes] == [24, 24]
    holds_the_demo(solve_json(cut, capsys))
    bare = tmp_path / "bare.h5"
    assert main(["simulate", str(short_scene(tmp_path, "demo-scan", scans_per_frame=8,
                                             counter=False)), "--out", str(bare)]) == 0  # fmt: skip
    gone = tmp_path / "gone.h5"
    _drop(bare, gone, keep)
    capsys.readouterr()
    flagged = solve_json(gone, capsys)
    assert any("1 gap(s)" in w for w in flagged["warnings"]), flagged["warnings"]
    assert main(["solve", str(fd), "--config", str(CONFIG)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "set scans_per_frame" in err, err


@pytest.mark.parametrize(
    ("edit", "says"),
    [
        ("scans_per_frame = 9", "not a CAN FD payload length"),
        ("scans_per_frame = 8\nscan_bytes = 6", "beyond a scan's 6 bytes"),
        ("scan_bytes = 0", "bus.scan.scan_bytes"),
    ],
)
def test_bad_fd_layouts_are_one_line(
    edit: str, says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "s.h5"
    assert main(["simulate", str(short_scene(tmp_path, "demo-scan")), "--out", str(run)]) == 0
    capsys.readouterr()
    bad = tmp_path / "bad.toml"
    bad.write_text(CONFIG.read_text().replace("[bus.scan]\n", f"[bus.scan]\n{edit}\n")
                   .replace("../drivers/", str(ROOT / "drivers") + "/"))  # fmt: skip
    assert main(["solve", str(run), "--config", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err, err
