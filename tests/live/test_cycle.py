"""The stand's own cycle on the simulated inverter (Modbus TCP on 127.0.0.1): run-up,
measure, brake, the correction places stopped at the mark; the supervision's refusals and
aborts; the CLI's words and exit codes.

Tolerances: the index goal is ±2 deg between where the drive stopped and the target it was
given (the inverter's 3600 counts a revolution quantise it to ±0.05 deg); against the
truth (the scene's unbalance angle, where the simulated drive knows the shaft is), ±2 deg
plus the measurement's own angle interval (its 95 % radius over the unbalance, in rad).
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import pytest
from scenes import edited_scene

from stand.cli import EXIT_ABORTED, main
from stand.core.motor import wrap_deg
from stand.live import live_source, measure_live
from stand.live.cycle import run_cycle
from stand.solve import SolveOptions

ROOT = Path(__file__).resolve().parents[2]
CONFIG = str(ROOT / "examples" / "drive-modbus.toml")
CONFIGS = {"modbus": CONFIG, "cia402": str(ROOT / "examples" / "drive-cia402.toml")}
INDEX_GOAL_DEG = 2.0


def _with_drive_fault(folder: Path, fault: str) -> Path:
    """demo-drive with an ``[effects.drive]`` line."""
    edit = {"[effects.noise]": f"[effects.drive]\n{fault}\n\n[effects.noise]"}
    return edited_scene("demo-drive", folder, edit)


def _cycle(scene: str, run: Path, plane2: bool = True, config: str = CONFIG):  # type: ignore[no-untyped-def]
    source = live_source(scene, config, "balance")
    assert source.drive is not None and source.drive.sim is not None

    def measure(stop, on_play, watch):  # type: ignore[no-untyped-def]
        result, _ = measure_live(source, dict(source.scene_bus or {}), str(run), SolveOptions(),
                                 lambda cfg, params, U: (1e-4, 1e-4), max_seconds=30.0,
                                 silence_timeout_s=2.0, stop=stop, on_play=on_play,
                                 on_progress=watch)  # fmt: skip
        return result

    result = run_cycle(source.drive, source.cfg, measure, run_path=str(run), rpm=None,
                       plane2=lambda: plane2)  # fmt: skip
    return result, source.drive.sim


@pytest.mark.realtime
@pytest.mark.parametrize("family", sorted(CONFIGS))
def test_the_cycle_stops_each_place_at_the_mark(tmp_path: Path, family: str) -> None:
    result, sim = _cycle("demo-drive", tmp_path / "r.h5", plane2=False, config=CONFIGS[family])
    c = result.cycle
    assert c is not None and c.aborted is None and c.drive == family
    (stop,) = c.index
    assert abs(stop.error_deg) <= INDEX_GOAL_DEG
    # the truth: plane 1's heavy spot (30 deg in the scene, drilled in mode remove) faces
    # the operator's mark (0 deg) where the simulated shaft really is
    true_place = wrap_deg(math.degrees(sim.true_angle_rad()) - 30.0)
    U = abs(result.U_kg_m[0])
    spread = math.degrees(result.measurement.radius95_kg_m[0] / U)
    assert abs(true_place) <= INDEX_GOAL_DEG + spread, (true_place, spread)
    # the phases: a run-up no shorter than the torque allows, the measurement's window,
    # the cycle within 1.15x its physical floor (the benchmark's goal; here with room for
    # a busy machine's late polls: 1.5x)
    assert c.runup_s >= 0.35 * 900 * math.pi / 30 / 25.0
    assert c.measure_s > 0 and c.brake_s > 0 and c.total_s >= c.floor_s * 0.99
    assert c.total_s <= 1.5 * c.floor_s


@pytest.mark.realtime
@pytest.mark.parametrize("example", ["drive-modbus.toml", "drive-modbus-rtu.toml"])
def test_balance_runs_the_cycle_from_the_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                             example: str) -> None:  # fmt: skip
    """Modbus TCP, and Modbus RTU (the simulated inverter's RTU frames carried over TCP)."""
    run = tmp_path / "r.h5"
    code = main(["balance", "--scene", "demo-drive", "--config", str(ROOT / "examples" / example),
                 "--out", str(run), "--no-archive", "--json", "--index-both"])  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    cycle, index = out["cycle"], out["index"]
    assert cycle["aborted"] is None and cycle["drive"] == "modbus"
    for key in ("runup_s", "settle_s", "measure_s", "brake_s", "index_s", "total_s", "floor_s"):
        assert cycle[key] >= 0, key
    assert [i["plane"] for i in index] == [1, 2]
    assert all(abs(i["error_deg"]) <= INDEX_GOAL_DEG for i in index)
    # plane 2's place: the scene's 200 deg, at the mark
    assert abs(wrap_deg(index[1]["target_deg"] - 200.0)) < 2.0


@pytest.mark.parametrize(
    ("fault", "words"),
    [("guard_open = true", "the guard is open: close it"),
     ("fault_code = 17", "in fault (code 17)")],
)  # fmt: skip
def test_a_drive_that_may_not_start_is_refused_before_anything_turns(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], fault: str, words: str
) -> None:
    scene = _with_drive_fault(tmp_path, fault)
    run = tmp_path / "r.h5"
    code = main(["balance", "--scene", str(scene), "--config", CONFIG, "--out", str(run),
                 "--no-archive"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and words in err, err
    assert len(err.strip().splitlines()) == 1
    assert not run.exists()  # nothing measured, nothing left behind


def test_an_undamped_scene_is_refused_for_a_drive(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The ``demo`` scene's supports have no damping: run up by a drive they would ring for
    ever; refused in one line naming the scene that has damped supports."""
    run = tmp_path / "r.h5"
    code = main(["balance", "--scene", "demo", "--config", CONFIG, "--out", str(run),
                 "--no-archive"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and "scene demo: its supports are undamped" in err, err
    assert "--scene demo-drive" in err and len(err.strip().splitlines()) == 1
    assert not run.exists()


def test_a_silent_drive_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scene = _with_drive_fault(tmp_path, "silent = true")
    code = main(["balance", "--scene", str(scene), "--config", CONFIG, "--out",
                 str(tmp_path / "r.h5"), "--no-archive"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and "drive modbus 127.0.0.1:" in err and "no answer" in err, err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.realtime
@pytest.mark.parametrize(
    ("fault", "code", "words"),
    [("guard_opens_at_s = 2.0", EXIT_ABORTED, "cycle aborted: guard opened at"),
     ("overspeed_pct = 5.0", EXIT_ABORTED, "cycle aborted: over-speed"),
     ("speed_scale = 0.98", 2, "reports 882.0 rpm, the reference mark gives 900.0 rpm"),
     ("stall_rpm = 200.0", EXIT_ABORTED, "the set point 900 rpm was not reached (200 rpm")],
)  # fmt: skip
def test_supervision_stops_the_rotor_and_keeps_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], fault: str, code: int, words: str
) -> None:
    scene = _with_drive_fault(tmp_path, fault)
    run = tmp_path / "r.h5"
    got = main(["balance", "--scene", str(scene), "--config", CONFIG, "--out", str(run),
                "--no-archive"])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert got == code and words in err[-1], err
    assert run.exists() and str(run) in err[-1]  # the run is kept, and said where


@pytest.mark.realtime
def test_an_aborted_cycle_is_journaled_with_its_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scene = _with_drive_fault(tmp_path, "guard_opens_at_s = 2.0")
    run, url = tmp_path / "r.h5", f"sqlite:///{tmp_path / 'archive.db'}"
    assert main(["balance", "--scene", str(scene), "--config", CONFIG, "--out", str(run),
                 "--archive", url]) == EXIT_ABORTED  # fmt: skip
    capsys.readouterr()
    assert main(["audit", "list", "--action", "cycle", "--archive", url, "--json"]) == 0
    (entry,) = json.loads(capsys.readouterr().out)["entries"]
    assert entry["reason"].startswith("guard opened at")
    assert entry["new_sha256"] == hashlib.sha256(run.read_bytes()).hexdigest()
    assert main(["audit", "verify", "--archive", url]) == 0
