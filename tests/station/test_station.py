"""The operator station without a browser: the shared measurement, the loop through the
screens as a simulated user (NiceGUI's user simulation), the bind rule and the token."""

from __future__ import annotations

import asyncio
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from stand.errors import StationBusyError, UsageError
from stand.plant import TokenGate, check_bind, is_local, read_token
from stand.solve import Job
from stand.solve.pipeline import precision_targets
from stand.station import Station

ROTORS = Path(__file__).resolve().parents[2] / "stand" / "data" / "rotors"
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
    # the stop may come before a node's first samples or after its first few: either way
    # the run is refused and the screen names what was missing
    assert s.phase == "failed"
    assert "reference edges" in s.error or "no samples" in s.error, s.error


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
    assert station.rotor_types() == ["demo-auger", "demo-auger-drilled"]
    for bad in ("../demo-auger", "/etc/passwd", "demo-auger.toml", ""):
        with pytest.raises(UsageError):
            station.config_path(bad)
    with pytest.raises(UsageError, match="no source"):
        station.start("demo-auger", "../../scene", Job())
    with pytest.raises(UsageError, match="no run 99"):
        station.report_file(99)


def test_the_history_shows_each_rotor_type_in_its_own_units(tmp_path: Path) -> None:
    """A rotor type whose configuration asks for ounces and inches has its archived
    unbalances shown so; a type no longer in the folder (or broken) in g mm."""
    from stand.i18n import Display
    from stand.station.history import _history_row

    folder = tmp_path / "rotors"
    folder.mkdir()
    text = (ROTORS / "demo-auger.toml").read_text()
    (folder / "us.toml").write_text(text + '\n[display]\nmass = "oz"\nlength = "in"\n')
    (folder / "broken.toml").write_text("[rotor\n")
    st = Station(folder, tmp_path / "runs", f"sqlite:///{tmp_path / 'a.sqlite'}", _targets)
    plane = {"plane": 1, "unbalance_g_mm": 2834.952, "angle_deg": 30.0, "urr": None}
    row = {"id": 3, "start_time": "2026-11-22T10:00:00+00:00", "serial": "U-1",
           "rotor_type": "us", "verdict": "pass", "checks_run": None,
           "planes": [plane]}  # fmt: skip
    note = "balancer test: balls ok; rotor within tolerance (start 1 of 2)"  # as archived
    assert _history_row({**row, "note": note}, Display(*st.display_units("us")))["note"] == note
    shown = _history_row(row, Display(*st.display_units("us")))["plane 1"]
    assert shown == "3.937 oz in at 30°"  # 2834.952 g mm / 28.3495 g/oz / 25.4 mm/in
    for gone in ("broken", "demo-auger", None):
        assert (
            _history_row(row, Display(*st.display_units(gone)))["plane 1"] == "2835.0 g mm at 30°"
        )


def test_a_report_outside_the_runs_folder_is_refused(station: Station, demo_run: Path) -> None:
    from stand.actions import archive_run, os_actor
    from stand.solve import solve_recording

    run_id = archive_run(solve_recording(str(demo_run)), station.archive_url, os_actor())
    with pytest.raises(UsageError, match="outside"):
        station.report_file(run_id)


@pytest.mark.skipif(
    shutil.which("chromium") is None and shutil.which("chromium-browser") is None,
    reason="the PDF is printed by Chromium (Debian: apt-get install chromium)",
)
def test_the_certificate_is_printed_once_as_a_pdf_beside_its_report(
    station: Station, demo_run: Path
) -> None:
    from stand.actions import archive_run, os_actor
    from stand.report import render
    from stand.solve import SolveOptions, solve_recording

    station.runs_dir.mkdir(parents=True)
    run = station.runs_dir / "demo.h5"
    shutil.copy(demo_run, run)
    result = solve_recording(str(run), options=SolveOptions(traces=True))  # as the station
    run.with_suffix(".html").write_text(render(result), encoding="utf-8")
    run_id = archive_run(result, station.archive_url, os_actor())
    pdf = station.certificate_pdf(run_id)
    assert pdf == run.with_suffix(".pdf") and pdf.read_bytes()[:5] == b"%PDF-"
    printed = pdf.stat().st_mtime_ns
    assert station.certificate_pdf(run_id).stat().st_mtime_ns == printed  # not again
    os.utime(run.with_suffix(".html"), ns=(printed + 10**9, printed + 10**9))  # report changed
    assert station.certificate_pdf(run_id).stat().st_mtime_ns > printed  # printed again
    assert sorted(p.name for p in station.runs_dir.iterdir()) == [
        "demo.h5", "demo.html", "demo.pdf"]  # fmt: skip
    with pytest.raises(UsageError, match="no run 99"):
        station.certificate_pdf(99)


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


def _call(gate: TokenGate, scope: dict[str, Any], body: bytes = b"") -> list[dict[str, Any]]:
    sent: list[dict[str, Any]] = []

    async def app(scope: Any, receive: Any, send: Any) -> None:
        await send({"type": "http.response.start", "status": 200, "headers": []})

    async def send(message: dict[str, Any]) -> None:
        sent.append(message)

    async def receive() -> dict[str, Any]:
        return {"type": "http.request", "body": body, "more_body": False}

    gate.app = app
    asyncio.run(gate(scope, receive, send))
    return sent


@pytest.mark.parametrize(
    ("kind", "query", "headers", "status"),
    [
        ("http", b"", [], 401),
        ("http", b"token=wrong-token-12345", [], 401),
        ("http", b"token=" + TOKEN.encode(), [], 401),  # never from a URL
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
    scope = {"type": kind, "query_string": query, "headers": headers, "path": "/"}
    sent = _call(TokenGate(None, TOKEN), scope)  # type: ignore[arg-type]
    if kind == "websocket":
        closed = sent and sent[0]["type"] == "websocket.close"
        assert ("closed" if closed else "passed") == status
        return
    assert sent[0]["status"] == status
    assert not [v for k, v in sent[0]["headers"] if k == b"set-cookie"]


@pytest.mark.parametrize(("typed", "status"), [(TOKEN, 303), ("wrong-token-12345", 401)])
@pytest.mark.parametrize("tls", [False, True])
def test_the_token_is_typed_into_a_form_that_sets_the_cookie(
    typed: str, status: int, tls: bool
) -> None:
    """``POST /token`` with the form's token: the cookie (``Secure`` under TLS) and on to
    the screens; a wrong one gets the form again."""
    scope = {"type": "http", "method": "POST", "path": "/token", "headers": []}
    sent = _call(TokenGate(None, TOKEN, tls=tls), scope, f"token={typed}".encode())  # type: ignore[arg-type]
    assert sent[0]["status"] == status
    cookie = [v.decode() for k, v in sent[0]["headers"] if k == b"set-cookie"]
    if status == 303:
        assert cookie[0].startswith(f"stand_token={TOKEN};") and ("Secure" in cookie[0]) == tls
    else:
        assert not cookie


@pytest.mark.realtime
def test_the_loop_through_the_screens_as_a_simulated_user(station: Station) -> None:
    """Start a job on the demo scene, measure until precise, apply the correction, check,
    see the run in the history: every step through the screens."""
    asyncio.run(_flow(station))


async def _flow(station: Station) -> None:
    from nicegui import ui
    from nicegui.testing.user_simulation import user_simulation

    from stand.station.pages import frame
    from stand.station.routes import add_routes

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
        await until(lambda: station.snapshot().run_id is not None)  # filed after the answer
        await user.should_see("Open the certificate", retries=20)
        assert "stored as a calibration datum (stand health)" in station.snapshot().notes
        user.find(marker="nav-history").click()
        await user.should_see(marker="history-table", retries=20)
        await user.should_see("Stand health (demo-auger at 900 rpm, 1 rotor): as calibrated")
        user.find(marker="history-serial").type("S-42")
        user.find(marker="history-search").click()
        table = user.find(ui.table).elements.pop()
        assert [r["serial"] for r in table.rows] == ["S-42", "S-42"]
        assert "pass (check)" in [r["verdict"] for r in table.rows]
        response = await user.http_client.get(table.rows[0]["report"])
        assert response.status_code == 200 and "S-42" in response.text
        user.find(marker="history-export")  # the button; its route gives the file
        dfq = await user.http_client.get("/export/qdas/demo-auger")
        assert dfq.status_code == 200 and dfq.content.startswith(b"K0100 8\r\n")
        assert b"K0014/0 S-42" in dfq.content
        missing = await user.http_client.get("/export/qdas/no-such-type")
        assert missing.status_code == 404 and "nothing exported" in missing.text
        ids = ",".join(str(r["run"]) for r in table.rows)  # one speed twice: no correction
        same = await user.http_client.get(f"/speeds/{ids}")
        assert same.status_code == 422 and "give each speed once" in same.text
        bad = await user.http_client.get("/speeds/1,x")
        assert bad.status_code == 400


@pytest.mark.realtime
def test_a_failed_check_is_corrected_again_and_a_correction_goes_on_once(
    station: Station,
) -> None:
    """Checked without the correction: not within tolerance; Correct then shows what the
    check run prescribes, it goes on the rotor once, and the next check passes against it."""
    station.start("demo-auger", "demo", Job(serial="T-1"))
    first = _wait(station).result
    station.check()  # nothing applied: the check fails
    s = _wait(station)
    assert s.kind == "check" and s.result.check.previous_run == first.provenance.run_file
    assert np.all(abs(s.result.U_kg_m) > np.asarray(s.result.tolerance.per_plane_kg_m))
    assert station.latest() is s.result  # Correct and Apply start from the check run
    station.apply_correction()
    with pytest.raises(UsageError, match="on the rotor already"):
        station.apply_correction()
    station.check()
    s = _wait(station)
    after = abs(s.result.U_kg_m) + s.result.measurement.radius95_kg_m
    assert np.all(after < np.asarray(s.result.tolerance.per_plane_kg_m))
    assert len(station.history(serial="T-1")) == 3


def test_what_the_screens_say() -> None:
    from stand.station.views import check_verdict, instructions

    def corr(plane: int, **kw: Any) -> dict[str, Any]:
        return {"plane": plane, "weights": [], "within_noise": False, "within_tolerance": False,
                **kw}  # fmt: skip

    w = {"mass_g": 39.0, "angle_deg": 225.0, "position": 6, "pieces_g": [20, 10, 5, 2, 2],
         "radius_mm": 90.0}  # fmt: skip
    out = {"correction_mode": "add", "display": {"mass": "g", "length": "mm"},
           "corrections": [corr(1, weights=[w]), corr(2, within_tolerance=True)]}  # fmt: skip
    one, two = instructions(out)
    assert one.lines == (("ADD 39.00 g", "in hole 6 (225°)", "stock: 20.00 g + 10.00 g + "
                          "5.00 g + 2.00 g + 2.00 g"),)  # fmt: skip
    assert one.headline == "plane 1: at radius 90 mm" and one.marks == ((225.0, "39.00 g"),)
    assert not two.needed and two.headline == "plane 2: within tolerance"
    out["correction_mode"] = "remove"
    w.update(position=None, pieces_g=[])
    assert instructions(out)[0].lines == (("REMOVE 39.00 g", "at 225°", ""),)
    hole = {"number": 1, "angle_deg": 20.0, "depth_mm": 16.5, "diameter_mm": 20.0,
            "point_angle_deg": 118.0, "entry_radius_mm": 90.0, "direction": "radial",
            "mass_g": 30.47}  # fmt: skip
    drilled = {
        "correction_mode": "drill",
        "corrections": [corr(1), corr(2)],
        "planes": [{"plane": 1, "holes": [hole], "slot": None}, {"plane": 2, "holes": []}],
    }
    one, two = instructions(drilled)
    assert one.headline == "plane 1: drill 1 radial hole into radius 90 mm"
    assert one.lines == (("1. DRILL Ø20 mm, 16.5 mm DEEP", "at 20° (radial; depth to the tip)",
                          "removes 30.47 g"),)  # fmt: skip
    assert one.marks == ((20.0, "1"),) and not two.needed
    assert check_verdict({}) is None
    for state in ("pass", "fail", "undecided"):
        assert check_verdict({"verdict": state}) == state
    assert check_verdict({"verdict": "none"}) is None


def test_the_rotor_face_numbers_the_holes_and_marks_the_masses() -> None:
    import xml.etree.ElementTree as ET

    from stand.station.face import face_svg

    svg = face_svg([(180.0, "20.00 g"), (225.0, "39.00 g")], positions=8, title="plane 1")
    root = ET.fromstring(svg)
    texts = [t.text for t in root.iter("{http://www.w3.org/2000/svg}text")]
    assert [str(k) for k in range(1, 9)] == [t for t in texts if t and t.isdigit()]
    assert {"reference mark", "rotation"} <= set(texts)
    # each mass a dot, its mass its tooltip (the instruction beside says it in large type)
    dots = [c for c in root.iter("{http://www.w3.org/2000/svg}circle")
            if c.find("{http://www.w3.org/2000/svg}title") is not None]  # fmt: skip
    assert [d.find("{http://www.w3.org/2000/svg}title").text for d in dots] == [  # type: ignore[union-attr]
        "20.00 g", "39.00 g"]  # fmt: skip
    bare = face_svg([], positions=0)
    assert not any(t and t.isdigit() for t in ET.fromstring(bare).itertext())


def test_the_live_chart_draws_the_circles_where_they_are() -> None:
    from stand.i18n import Display
    from stand.station.views import PlaneLive, polar_chart

    p = PlaneLive(U_kg_m=5e-3, angle_deg=30.0, radius95_kg_m=1e-3, goal_kg_m=2e-3,
                  permissible_kg_m=1.1e-3)  # fmt: skip
    opts = polar_chart(1, p, Display())
    series = {s["name"]: s["data"] for s in opts["series"]}
    assert series["unbalance"] == [[5000.0, 30.0]]
    assert {round(r, 6) for r, _ in series["tolerance"]} == {1100.0}
    # every point of the 95 % circle lies 1000 g mm from the unbalance (clockwise angles)
    z0 = 5000 * np.exp(1j * np.radians(30.0))
    for key, radius in (("95 % circle", 1000.0), ("precision goal", 2000.0)):
        z = np.array([r * np.exp(1j * np.radians(a)) for r, a in series[key]])
        # angles are sent rounded to 1e-3 deg: at most 5e-4 deg x 7000 g mm = 0.06 g mm off
        assert np.allclose(abs(z - z0), radius, rtol=0, atol=0.07)
    assert opts["radiusAxis"]["max"] >= 7000.0  # the goal circle fits


def test_one_station_is_one_stand(tmp_path: Path) -> None:
    """The stand id OPC UA serves is the rotor types' [stand] id (its runs are archived
    under it), the host name without one; rotor types naming two stands are refused."""
    import socket

    folder = tmp_path / "rotors"
    folder.mkdir()
    text = (ROTORS / "demo-auger.toml").read_text()
    st = Station(folder, tmp_path / "runs", f"sqlite:///{tmp_path / 'a.sqlite'}", _targets)
    (folder / "a.toml").write_text(text)
    assert st.stand_id() == socket.gethostname()[:64]
    for name in ("a", "b"):
        (folder / f"{name}.toml").write_text(text.replace("[stand]\n", '[stand]\nid = "line-3"\n'))
    assert st.stand_id() == "line-3"
    (folder / "b.toml").write_text(text.replace("[stand]\n", '[stand]\nid = "line-4"\n'))
    with pytest.raises(UsageError, match="name different stands"):
        st.stand_id()


def test_a_rotor_without_a_serial_is_not_started(station: Station) -> None:
    """Start without a serial (blank or spaces) is refused, saying what to do: the rotor
    would be anonymous in the archive, Q-DAS and OPC UA."""
    for blank in (Job(), Job(serial="   ")):
        with pytest.raises(UsageError, match="serial number first"):
            station.start("demo-auger", "demo", blank)
    assert station.snapshot().phase == "idle"


def test_the_station_archives_where_its_rotor_types_say(tmp_path: Path) -> None:
    """The rotor types' one `[archive] url` is the station's; a type that does not load is
    left to the screen that chooses it (the others still start); two urls are refused."""
    text = (Path(__file__).parents[2] / "stand" / "data" / "rotors" / "demo-auger.toml").read_text()
    url = f"sqlite:///{tmp_path / 'line.sqlite'}"
    (tmp_path / "a.toml").write_text(text + f'\n[archive]\nurl = "{url}"\n')
    (tmp_path / "b.toml").write_text(text)  # names none
    (tmp_path / "broken.toml").write_text("x = [\n")
    assert Station.rotor_types_archive(tmp_path) == url
    (tmp_path / "c.toml").write_text(text + '\n[archive]\nurl = "sqlite:////elsewhere.sqlite"\n')
    with pytest.raises(UsageError, match="different archives"):
        Station.rotor_types_archive(tmp_path)


def test_a_rotor_type_with_a_serial_rule_makes_the_serial(tmp_path: Path) -> None:
    """A rotor without a serial under ``[rotor] serial_rule``: the next of the day, after
    those archived (two rotors: -0001, -0002)."""
    import datetime as dt

    text = (Path(__file__).parents[2] / "stand" / "data" / "rotors" / "demo-auger.toml").read_text()
    folder = tmp_path / "rotors"
    folder.mkdir()
    (folder / "demo-auger.toml").write_text(
        text.replace(
            'type = "demo-auger"', 'type = "demo-auger"\nserial_rule = "AUG-{date}-{n:04}"'
        )
    )
    st = Station(folder, tmp_path / "runs", f"sqlite:///{tmp_path / 'a.sqlite'}", _targets)
    today = dt.datetime.now().astimezone().strftime("%Y%m%d")
    made = []
    for _ in range(2):
        st.start("demo-auger", "demo", Job())
        s = st.wait(60)
        made.append(s.job.serial)
        end = time.monotonic() + 60  # filed after the answer: a hang guard
        while st.snapshot().run_id is None and time.monotonic() < end:
            time.sleep(0.05)
        st.next_rotor()
    assert made == [f"AUG-{today}-0001", f"AUG-{today}-0002"]
