"""`stand balance`: the operator's command, on the simulated stand."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stand.cli import main
from stand.sim import shipped_scenes


def _balance(argv: list[str], capsys: pytest.CaptureFixture[str]) -> dict:
    capsys.readouterr()
    assert main(["balance", *argv, "--json", "--quiet"]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.realtime
def test_balance_demo_gives_the_correction_and_the_verdict(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = _balance(["--scene", "demo", "--out", str(tmp_path / "r.h5")], capsys)
    c1, c2 = out["corrections"]
    (w1,) = c1["weights"]
    (w2,) = c2["weights"]
    # remove 5000 g mm / 90 mm = 55.56 g at 30 deg, 3000 / 80 = 37.5 g at 200 deg
    assert w1["mass_g"] == pytest.approx(55.56, rel=0.005) and w1["angle_deg"] == pytest.approx(
        30.0, abs=0.3
    )
    assert w2["mass_g"] == pytest.approx(37.5, rel=0.005) and w2["angle_deg"] == pytest.approx(
        200.0, abs=0.3
    )
    t = out["tolerance"]
    assert t["permissible_g_mm"] == pytest.approx(
        1000 * 6.3 * 60 / (1500 * 3.14159265 / 30), rel=1e-6
    )
    assert [c["verdict"] == "pass" for c in t["criteria"]] == [False, False]
    # precision target: 10 % of each plane's tolerance
    want = [0.1 * p for p in t["plane_limits_g_mm"]]
    assert out["targets_g_mm"] == pytest.approx(want, abs=1e-3)  # both rounded to 1e-3
    assert out["stopped_by"] == "precision"


@pytest.mark.realtime
def test_check_after_a_correction_gives_the_reduction_ratio(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = tmp_path / "before.h5"
    assert main(["simulate", "demo", "--out", str(before)]) == 0
    text = Path(str(shipped_scenes()["demo"])).read_text()
    after_scene = tmp_path / "after.toml"
    after_scene.write_text(
        text.replace("g_mm = 5000.0, angle_deg = 30.0", "g_mm = 200.0, angle_deg = 40.0").replace(
            "g_mm = 3000.0, angle_deg = 200.0", "g_mm = 150.0, angle_deg = 190.0"
        )
    )
    out = _balance(
        [
            "--scene",
            str(after_scene),
            "--out",
            str(tmp_path / "after.h5"),
            "--check",
            str(before),
            "--max-seconds",
            "4",
        ],
        capsys,
    )
    p1, p2 = out["check"]["planes"]
    assert p1["before_g_mm"] == pytest.approx(5000, abs=15)
    assert p1["after_g_mm"] == pytest.approx(200, abs=15)
    assert p1["urr"] == pytest.approx(1 - 200 / 5000, abs=0.004)
    assert p2["urr"] == pytest.approx(1 - 150 / 3000, abs=0.005)
    assert [c["verdict"] == "pass" for c in out["tolerance"]["criteria"]] == [True, True]


@pytest.mark.realtime
@pytest.mark.parametrize("how", ["SIGINT", "SIGTERM", "SIGINT ignored at start (nohup)"])
def test_a_signal_stops_cleanly_keeps_the_recording_and_still_answers(
    tmp_path: Path, how: str
) -> None:
    import signal
    import subprocess
    import sys
    import time

    sig = signal.SIGTERM if how == "SIGTERM" else signal.SIGINT

    def ignore_sigint() -> None:  # what nohup, a shell script's background job, a service do
        signal.signal(signal.SIGINT, signal.SIG_IGN)

    from stand.drivers.runs.recording import read_run

    run = tmp_path / "r.h5"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "stand.cli",
            "balance",
            "--scene",
            "demo",
            "--out",
            str(run),
            "--target-g-mm",
            "0.001",
            "--json",
            "--quiet",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=ignore_sigint if "ignored" in how else None,
    )
    deadline = time.monotonic() + 20
    while not run.exists() and time.monotonic() < deadline:  # recording has begun
        time.sleep(0.05)
    time.sleep(2.5)
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    res = json.loads(out)
    assert res["stopped_by"] == "interrupted"
    rec = read_run(run)
    assert rec.meta["complete"] and len(rec.frames) > 5000  # about 2.5 s of frames kept
    assert res["planes"][0]["unbalance_g_mm"] == pytest.approx(5000, abs=50)


@pytest.mark.realtime
def test_an_answer_kept_from_the_last_estimate_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """When the whole run cannot be measured again once it has ended (here: made to fail),
    the last estimate made while it ran is the answer, and a warning says so: never in
    silence."""
    import stand.live.loop
    from stand.errors import MeasurementError
    from stand.live import LiveSession

    closed = []
    real_close, real_measure = LiveSession.close, stand.live.loop.measure_streams

    def close(self: LiveSession) -> object:
        closed.append(True)
        return real_close(self)

    def measure(*args: object, **kwargs: object) -> object:
        if closed:
            raise MeasurementError("the drive stopped")
        return real_measure(*args, **kwargs)

    monkeypatch.setattr(LiveSession, "close", close)
    monkeypatch.setattr(stand.live.loop, "measure_streams", measure)
    out = _balance(["--scene", "demo", "--out", str(tmp_path / "r.h5"), "--no-archive"], capsys)
    (w,) = [w for w in out["warnings"] if "last estimate" in w]
    assert "could not be measured again (the drive stopped)" in w
    assert len(out["corrections"]) == 2
