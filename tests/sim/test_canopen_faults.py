"""The simulated CANopen modules' faults on demand (``[effects.canopen]``): a wrong
identity and a refused mapping stop a live run at its set-up in one line; an EMCY, a
restart and late TPDOs reach the answer as flags and warnings, never silently."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import h5py
import pytest
from protocols import holds_the_demo, short_scene, solve_json

from stand.cli import main


def _scene(tmp_path: Path, faults: str) -> Path:
    path = short_scene(tmp_path, "demo-canopen")
    path.write_text(path.read_text() + f"\n[effects.canopen]\n{faults}\n")
    return path


@pytest.mark.parametrize(
    ("faults", "says"),
    [
        (
            "node = 2\nvendor_id = 0x1234",
            "CANopen node 2 is another module: identity (0x1018) vendor 0x00001234",
        ),
        ("refuse_mapping = true", "CANopen node 1 refused write 0x1A00:1 (SDO abort 0x06040041"),
    ],
)
def test_a_wrong_module_stops_the_run_at_its_set_up(
    faults: str, says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "b.h5"
    argv = ["balance", "--scene", str(_scene(tmp_path, faults)), "--out", str(out), "--quiet"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err, err
    assert not out.exists() and not list(tmp_path.glob("*.tmp*"))  # no empty run left


def _said(out: dict[str, Any], *words: str) -> bool:
    """A warning of the answer holds all of ``words``."""
    return any(all(w in line for w in words) for line in out["warnings"])


def _node(run: Path, node: int, capsys: pytest.CaptureFixture[str]) -> dict[str, Any]:
    """``stand inspect RUN --json``'s summary of one node."""
    assert main(["inspect", str(run), "--json"]) == 0
    nodes = json.loads(capsys.readouterr().out)["nodes"]
    out: dict[str, Any] = next(n for n in nodes if n["node"] == node)
    return out


def _solved(tmp_path: Path, faults: str, capsys: pytest.CaptureFixture[str]
            ) -> tuple[Path, dict[str, Any]]:  # fmt: skip
    """The short demo-canopen scene with these faults, simulated and solved."""
    run = tmp_path / "c.h5"
    assert main(["simulate", str(_scene(tmp_path, faults)), "--out", str(run)]) == 0
    capsys.readouterr()
    return run, solve_json(run, capsys)


def test_an_emcy_leaves_its_invalid_samples_out_and_is_said(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run, out = _solved(tmp_path, "emcy_at_s = 0.8\ninvalid_s = 0.05", capsys)
    holds_the_demo(out)
    assert _said(out, "node 1: EMCY 0x5000 at 0.800 s"), out["warnings"]
    assert _said(out, "node 1: 101 sample(s) the module marked not valid"), out["warnings"]
    node1 = _node(run, 1, capsys)  # 0.05 s at 2 kHz, both ends in: 101 samples
    assert node1["invalid_samples"] == 101 and node1["flags"] == ["sensor_fault", "emcy"]


def test_a_restart_is_flagged_and_the_run_before_it_measured(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run, out = _solved(tmp_path, "node = 2\nrestart_at_s = 1.5", capsys)
    assert _said(out, "node 2: the module restarted (boot-up at 1.500 s)"), out["warnings"]
    assert _node(run, 2, capsys)["flags"] == ["restart"]
    holds_the_demo(out)


def test_late_tpdos_are_put_back_and_said(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _, out = _solved(tmp_path, "late_probability = 0.02", capsys)
    holds_the_demo(out)
    assert _said(out, "node 1:", "came after the next SYNC (put back on their own,")


@pytest.mark.realtime
def test_a_live_run_stores_its_set_up(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "b.h5"
    argv = ["balance", "--scene", str(short_scene(tmp_path, "demo-canopen")), "--out",
            str(out), "--quiet", "--json"]  # fmt: skip
    assert main(argv) == 0
    capsys.readouterr()
    with h5py.File(out) as f:
        assert '"object": "0x1018:1"' in f.attrs["canopen_setup"]


def test_faults_of_another_protocol_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = short_scene(tmp_path, "demo")
    path.write_text(path.read_text() + "\n[effects.canopen]\nrefuse_mapping = true\n")
    assert main(["simulate", str(path), "--out", str(tmp_path / "x.h5")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "[effects.canopen]" in err, err


@pytest.mark.parametrize(
    ("faults", "key"),
    [("node = 3", "effects.canopen.node"), ("vendor_id = -1", "effects.canopen.vendor_id"),
     ("late_probability = 1.5", "effects.canopen.late_probability"),
     ("restart_at_s = nan", "effects.canopen.restart_at_s"), ("smoke = 1", "effects.canopen")],
)  # fmt: skip
def test_a_bad_fault_is_one_line(
    faults: str, key: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["simulate", str(_scene(tmp_path, faults)), "--out", str(tmp_path / "x.h5")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and key in err, err
