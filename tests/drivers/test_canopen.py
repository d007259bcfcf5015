"""CANopen analog input modules sampling on SYNC (``[bus] protocol = "canopen"``): the demo
through the simulated modules solved with the example config; TPDOs lost and late; the
spread against the Cramer-Rao bound; bad EDS and mappings."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
from protocols import holds_the_demo, short_scene, solve_json

from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "examples" / "canopen-stand.toml"


def _rewrite(run: Path, out: Path, change) -> int:  # type: ignore[no-untyped-def]
    """A copy of a run file with its frames changed by ``change(frames) -> frames``."""
    from stand.drivers import read_recording, write_recording

    rec = read_recording(str(run))
    frames = change(rec.frames)
    write_recording(type(rec)(rec.path, frames, rec.meta, rec.warnings), str(out))
    return len(rec.frames) - len(frames)


def test_the_demo_through_canopen_modules_solves_to_its_unbalance(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The demo-canopen scene (SYNC at 2 kHz, TPDO1 of nodes 1 and 2 on 0x181 and 0x182,
    protocol v1's MARK ids: the decoder is chosen per bus): solved with its stored config
    and with examples/canopen-stand.toml, the unbalance inside the 95 % circles."""
    run = tmp_path / "c.h5"
    assert main(["simulate", str(short_scene(tmp_path, "demo-canopen")), "--out", str(run)]) == 0
    capsys.readouterr()
    holds_the_demo(solve_json(run, capsys))
    holds_the_demo(solve_json(run, capsys, "--config", str(CONFIG)))


def test_lost_and_late_tpdos_keep_their_place(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """1 % of node 1's TPDOs and a burst of 40 dropped: lost samples in place, the answer
    inside its circles, the angles within 0.05 deg of the whole run's; a TPDO that came
    after the next SYNC is put back on its own SYNC, said, and changes nothing."""
    run = tmp_path / "c.h5"
    assert main(["simulate", str(short_scene(tmp_path, "demo-canopen")), "--out", str(run)]) == 0
    capsys.readouterr()
    whole = solve_json(run, capsys)

    def drop(frames):  # type: ignore[no-untyped-def]
        node1 = np.flatnonzero(frames.can_id == 0x181)
        gone = node1[np.random.default_rng(5).random(len(node1)) < 0.01]
        gone = np.concatenate((gone, node1[900:940]))
        keep = np.ones(len(frames), bool)
        keep[gone] = False
        return frames.take(keep)

    lost = tmp_path / "lost.h5"
    n = _rewrite(run, lost, drop)
    cut = solve_json(lost, capsys)
    holds_the_demo(cut)
    for a, b in zip(whole["planes"], cut["planes"], strict=True):
        assert abs((a["angle_deg"] - b["angle_deg"] + 180) % 360 - 180) < 0.05
    assert n > 40

    def late(frames):  # type: ignore[no-untyped-def]
        order = np.arange(len(frames))
        k = int(np.flatnonzero(frames.can_id == 0x182)[500])
        nxt = k + 1 + int(np.flatnonzero(frames.can_id[k + 1 :] == 0x80)[0])
        order = np.concatenate((order[:k], order[k + 1 : nxt + 1], [k], order[nxt + 1 :]))
        return frames.take(order)

    moved = tmp_path / "late.h5"
    _rewrite(run, moved, late)
    after = solve_json(moved, capsys)
    assert after["planes"] == whole["planes"]
    said = [w for w in after["warnings"] if "after the next SYNC" in w]
    assert len(said) == 1 and "1 TPDO(s)" in said[0], after["warnings"]


def test_backlogs_are_left_out_and_too_many_refuse_the_node(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Node 1's TPDOs come three at a time after the SYNC of the last, stamped as they
    arrive (a host that fell behind): which SYNC each answered is not known, so all three
    are left out, never placed by guess; a few such backlogs leave the answer in its
    circles, more than a fifth of the TPDOs refuse the node in one line, naming the share.
    The same backlogs with each TPDO's wire time (a bus stamping in hardware, a simulated
    module stamping when it answered): each is put back on the SYNC its stamp follows, and
    the answer is the whole run's."""
    run = tmp_path / "c.h5"
    assert main(["simulate", str(short_scene(tmp_path, "demo-canopen")), "--out", str(run)]) == 0

    def backlog(share: float, step: int, wire: bool = False):  # type: ignore[no-untyped-def]
        def change(frames):  # type: ignore[no-untyped-def]
            node1 = np.flatnonzero(frames.can_id == 0x181)
            pos, t = np.arange(len(frames), dtype=float), frames.t_s.copy()
            groups = node1[: 3 * int(share * len(node1) / 3)].reshape(-1, 3)
            for g in groups[::step]:
                pos[g[0]], pos[g[1]] = pos[g[2]] - 0.2, pos[g[2]] - 0.1  # after g[2]'s SYNC
                if not wire:
                    t[g[0]] = t[g[1]] = t[g[2]]  # stamped on arrival
            moved = dataclasses.replace(frames, t_s=t)
            return moved.take(np.argsort(pos, kind="stable"))

        return change

    few, many = tmp_path / "few.h5", tmp_path / "many.h5"
    _rewrite(run, few, backlog(0.9, 20))  # every 20th group of three: about 4.5 %
    _rewrite(run, many, backlog(0.3, 1))  # 30 % of them
    stamped = tmp_path / "stamped.h5"
    _rewrite(run, stamped, backlog(0.3, 1, wire=True))
    capsys.readouterr()
    whole = solve_json(run, capsys)
    placed = solve_json(stamped, capsys)
    assert placed["planes"] == whole["planes"]
    said = [w for w in placed["warnings"] if "by their stamps" in w]
    # two of each three put back (the third arrived after its own SYNC), none left out
    assert said and ", 0 in a backlog" in said[0], said
    assert int(said[0].split(": ")[1].split(" ")[0]) == 2 * len(range(0, 1200, 3)), said
    out = solve_json(few, capsys)
    holds_the_demo(out)
    said = [w for w in out["warnings"] if "in a backlog on one SYNC" in w]
    assert said and said[0].startswith("node 1: 0 TPDO(s) came after"), said
    assert main(["solve", str(many)]) == 2
    err = capsys.readouterr().err
    assert (
        err.startswith("stand: error: ")
        and "node 1: " in err
        and "came late, in backlogs (30 %" in err
    ), err


def test_the_spread_sits_at_the_cramer_rao_bound() -> None:
    """100 runs of 2 s at 2 kHz without SYNC jitter: the support 1 phasor's spread within
    1.2x of sqrt(2 sigma^2 / N) (noise and quantization), as the scan module's."""
    from stand.config.bus import bus_choice
    from stand.drivers.canopen.codec import pdo_streams
    from stand.drivers.canopen.layout import load_pdo_layout
    from stand.sim import load_scene, simulate
    from stand.sim.scan_emit import SENSITIVITY_M_S2_PER_V, VOLTS_PER_COUNT
    from stand.solve import SolveOptions, measure_streams

    sc, p, _ = load_scene("demo-canopen")
    cfg = sc.config()
    layout = load_pdo_layout(bus_choice(cfg.bus, "x").table, Path("."), "x")
    z = []
    for seed in range(100):
        run = sc.run.model_copy(update={"seconds": 2.0, "seed": seed})
        frames = simulate(sc.model_copy(update={"run": run}), p).frames
        z.append(measure_streams(pdo_streams(frames, layout), cfg, p, SolveOptions())
                 .supports[0].A_m_s2)  # fmt: skip
    zz = np.array(z)
    q = VOLTS_PER_COUNT * SENSITIVITY_M_S2_PER_V
    bound = math.sqrt(2 * ((0.001 * math.sqrt(1000)) ** 2 + q**2 / 12) / 4000)
    for part in (zz.real, zz.imag):
        assert 1 / 1.2 < np.std(part, ddof=1) / bound < 1.2


@pytest.mark.parametrize(
    ("edit", "says"),
    [
        (('accel = "0x7130:1"', 'accel = "0x7131:1"'), "has no object 0x7131:1"),
        (('accel = "0x7130:1"', 'accel = "0x6114:1"'), "0x6114:1 is not mapped in TPDO1"),
        (('accel = "0x7130:1"', 'accel = "0x1018:1"'), "0x1018:1 is not mapped in TPDO1"),
        (("node_id = 2", "node_id = 1"), "two modules cannot share a node id"),
        (('eds = "../drivers/canopen/canopen_ai.eds"', 'eds = "nope.eds"'), "cannot read"),
        (('accel = "0x7130:1"', 'accel = "7130:1"'), "bus.canopen.nodes.0.accel"),
        (("rate_hz = 2000.0", "rate_hz = 2000.0\nwindow_s = 0.0005"), "is not within a SYNC"),
    ],
)
def test_bad_eds_and_mappings_are_one_line(
    edit: tuple[str, str], says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "c.h5"
    assert main(["simulate", str(short_scene(tmp_path, "demo-canopen")), "--out", str(run)]) == 0
    capsys.readouterr()
    text = CONFIG.read_text()
    assert edit[0] in text
    (tmp_path / "canopen_ai.eds").write_text(
        (ROOT / "drivers" / "canopen" / "canopen_ai.eds").read_text()
    )
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace(edit[0], edit[1], 1).replace("../drivers/canopen/", ""))
    assert main(["solve", str(run), "--config", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err, err


@pytest.mark.realtime
def test_a_live_balance_reads_the_modules(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["balance", "--scene", "demo-canopen", "--out", str(tmp_path / "b.h5"), "--json",
            "--quiet"]  # fmt: skip
    assert main(argv) == 0
    live = json.loads(capsys.readouterr().out)
    holds_the_demo(live)
    assert live["stopped_by"] == "precision"
