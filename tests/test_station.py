"""The operator station without a browser: the shared measurement, the loop through the
screens as a simulated user (NiceGUI's user simulation), the bind rule and the token."""

from __future__ import annotations

import asyncio
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from stand.errors import StationBusyError, UsageError
from stand.pipeline import precision_targets
from stand.result import Job
from stand.station.safety import TokenGate, check_bind, is_local, read_token
from stand.station.service import Station

ROTORS = Path(__file__).resolve().parents[1] / "stand" / "data" / "rotors"
TOKEN = "a-long-enough-token"


def _targets(cfg: Any, params: Any, U: Any) -> tuple[float, float]:
    return precision_targets(cfg, params, U, tolerance_share=0.10)


@pytest.fixture
def station(tmp_path: Path) -> Station:
    return Station(ROTORS, tmp_path / "runs", f"sqlite:///{tmp_path / 'a.sqlite'}", _targets)


def _wait(station: Station, timeout_s: float = 30.0) -> Any:
    s = station.wait(timeout_s)
    assert s.phase == "done", s.error
    return s


@pytest.mark.realtime
def test_one_measurement_at_a_time_and_a_hand_stop(station: Station) -> None:
    station.start("demo-auger", "demo", Job(serial="B-7"))
    with pytest.raises(StationBusyError, match="B-7"):
        station.start("demo-auger", "demo", Job(serial="B-8"))
    with pytest.raises(StationBusyError):
        station.next_rotor()
    while station.snapshot().progress is None:  # the first estimate, at 1 s
        time.sleep(0.01)
    station.stop()
    s = _wait(station)
    assert s.result.live.stopped_by == "stopped by hand"
    assert s.result.live.elapsed_s < 1.25  # before the next estimate was due
    station.start("demo-auger", "demo", Job(serial="B-8"))
    station.stop()  # at once: too little data for an answer, and the screen says why
    s = station.wait(30)
    assert s.phase == "failed" and "reference edges" in s.error


@pytest.mark.realtime
def test_the_loop_live_estimates_twice_a_second(station: Station) -> None:
    """Initial run, correction applied to the simulated rotor, check: within tolerance, the
    two runs archived and linked; the live estimate renewed at least every 0.5 s."""
    station.start("demo-auger", "demo", Job(serial="A-1", operator="kim"))
    times = set()
    while station.snapshot().phase == "measuring":
        p = station.snapshot().progress
        if p is not None:
            times.add(round(p.elapsed_s, 3))
        time.sleep(0.02)
    s = _wait(station)
    gaps = [b - a for a, b in zip(sorted(times), sorted(times)[1:], strict=False)]
    # the cap 0.4 s, plus one 0.1 s read, plus 0.1 s for a solve delayed by a busy machine
    assert gaps and max(gaps) <= 0.6
    assert s.run_id is not None and s.notes == ()
    masses = station.apply_correction()
    assert {m.plane for m in masses} == {1, 2} and all(m.grams > 0 for m in masses)
    station.check()
    s = _wait(station)
    assert s.kind == "check" and s.result.check is not None
    assert s.result.tolerance is not None
    after = abs(s.result.U_kg_m) + s.result.measurement.radius95_kg_m
    assert np.all(after < np.asarray(s.result.tolerance.per_plane_kg_m))  # with its interval
    rows = station.history(serial="A-1")
    assert [r["checks_run"] for r in rows] == [rows[1]["id"], None]  # newest first
    assert station.report_file(s.run_id).read_text().count("A-1") >= 1


def test_rotor_types_and_files_stay_inside_their_folders(station: Station, tmp_path: Path) -> None:
    assert station.rotor_types() == ["demo-auger"]
    for bad in ("../demo-auger", "/etc/passwd", "demo-auger.toml", ""):
        with pytest.raises(UsageError):
            station.config_path(bad)
    with pytest.raises(UsageError, match="no source"):
        station.start("demo-auger", "../../scene", Job())
    with pytest.raises(UsageError, match="no run 99"):
        station.report_file(99)


def test_a_report_outside_the_runs_folder_is_refused(station: Station, demo_run: Path) -> None:
    from stand.archive import archive_result
    from stand.pipeline import solve_recording

    run_id = archive_result(solve_recording(str(demo_run)), station.archive_url)
    with pytest.raises(UsageError, match="outside"):
        station.report_file(run_id)


@pytest.mark.parametrize(
    ("host", "local"),
    [("127.0.0.1", True), ("localhost", True), ("::1", True), ("127.1.2.3", True),
     ("0.0.0.0", False), ("192.168.1.5", False), ("::", False), ("stand.example", False)],
)  # fmt: skip
def test_a_bind_beyond_this_machine_needs_a_token(host: str, local: bool) -> None:
    assert is_local(host) is local
    if local:
        check_bind(host, None)
    else:
        with pytest.raises(UsageError, match="--token"):
            check_bind(host, None)
        check_bind(host, TOKEN)


def test_the_cli_refuses_a_network_bind_without_a_token_in_one_line() -> None:
    out = subprocess.run(
        [sys.executable, "-m", "stand.cli", "station", "--host", "0.0.0.0", "--no-browser"],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert out.returncode == 2
    assert out.stderr.count("\n") == 1 and "--token" in out.stderr, out.stderr


@pytest.mark.parametrize("token", ["short", "has space in it", "semi;colon;tok", "ünïcode-tokens"])
def test_weak_or_unsafe_tokens_are_refused(token: str, tmp_path: Path) -> None:
    with pytest.raises(UsageError):
        read_token(token, None)
    f = tmp_path / "token"
    f.write_text(TOKEN + "\n")
    assert read_token(None, str(f)) == TOKEN
    with pytest.raises(UsageError, match="not both"):
        read_token(TOKEN, str(f))


def _call(gate: TokenGate, scope: dict[str, Any]) -> list[dict[str, Any]]:
    sent: list[dict[str, Any]] = []

    async def app(scope: Any, receive: Any, send: Any) -> None:
        await send({"type": "http.response.start", "status": 200, "headers": []})

    async def send(message: dict[str, Any]) -> None:
        sent.append(message)

    async def receive() -> dict[str, Any]:
        return {}

    gate.app = app
    asyncio.run(gate(scope, receive, send))
    return sent


@pytest.mark.parametrize(
    ("kind", "query", "headers", "status"),
    [
        ("http", b"", [], 401),
        ("http", b"token=wrong-token-12345", [], 401),
        ("http", b"token=" + TOKEN.encode(), [], 200),
        ("http", b"", [(b"cookie", b"a=b; stand_token=" + TOKEN.encode())], 200),
        ("http", b"", [(b"cookie", b"stand_token=" + TOKEN.encode() + b"x")], 401),
        ("http", b"", [(b"authorization", b"Bearer " + TOKEN.encode())], 200),
        ("websocket", b"", [], "closed"),
        ("websocket", b"", [(b"cookie", b"stand_token=" + TOKEN.encode())], "passed"),
    ],
)  # fmt: skip
def test_every_request_must_carry_the_token(
    kind: str, query: bytes, headers: list[Any], status: Any
) -> None:
    sent = _call(TokenGate(None, TOKEN), {"type": kind, "query_string": query, "headers": headers})  # type: ignore[arg-type]
    if kind == "websocket":
        closed = sent and sent[0]["type"] == "websocket.close"
        assert ("closed" if closed else "passed") == status
        return
    assert sent[0]["status"] == status
    cookie = [v for k, v in sent[0]["headers"] if k == b"set-cookie"]
    assert bool(cookie) == (status == 200 and bool(query))


@pytest.mark.realtime
def test_the_loop_through_the_screens_as_a_simulated_user(station: Station) -> None:
    """Start a job on the demo scene, measure until precise, apply the correction, check,
    see the run in the history: every step through the screens."""
    asyncio.run(_flow(station))


async def _flow(station: Station) -> None:
    from nicegui import ui
    from nicegui.testing.user_simulation import user_simulation

    from stand.station.pages import add_routes, frame

    async def until(cond: Any, timeout_s: float = 30.0) -> None:
        end = time.monotonic() + timeout_s
        while not cond():
            assert time.monotonic() < end, station.snapshot().error
            await asyncio.sleep(0.1)

    async with user_simulation(root=lambda: frame(station)) as user:
        add_routes(station)
        await user.open("/")
        user.find(marker="serial").type("S-42")
        user.find(marker="operator").type("kim")
        user.find(marker="start").click()
        await until(lambda: station.snapshot().phase == "measuring")
        await user.should_see("Stop")
        await until(lambda: station.snapshot().phase == "done")
        await user.should_see("Go to the correction", retries=20)
        await user.should_see(marker="plane1-live")
        user.find("Go to the correction").click()
        await user.should_see("ADD", retries=20)
        await user.should_see("in hole")
        user.find(marker="apply").click()
        await user.should_see("masses put on the simulated rotor")
        user.find(marker="check-run").click()
        await until(lambda: station.snapshot().kind == "check")
        await until(lambda: station.snapshot().phase == "done")
        await user.should_see("See the check", retries=20)
        user.find("See the check").click()
        await user.should_see("S-42: WITHIN TOLERANCE", retries=20)
        await user.should_see("Open the certificate")
        user.find(marker="nav-history").click()
        await user.should_see(marker="history-table", retries=20)
        user.find(marker="history-serial").type("S-42")
        user.find(marker="history-search").click()
        table = user.find(ui.table).elements.pop()
        assert [r["serial"] for r in table.rows] == ["S-42", "S-42"]
        assert "pass (check)" in [r["verdict"] for r in table.rows]
        response = await user.http_client.get(table.rows[0]["report"])
        assert response.status_code == 200 and "S-42" in response.text
