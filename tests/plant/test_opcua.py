"""The OPC UA result server, driven by asyncua's own client: browse, read, call, subscribe;
the result-ready event within 1 s of a run's archiving; read-only; who may connect."""

from __future__ import annotations

import asyncio
import json
import socket
import time
from pathlib import Path
from typing import Any

import pytest

from stand.cli import main

NS = "urn:rotor-stand:balancing-stand"


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def demo_result(tmp_path_factory: pytest.TempPathFactory) -> Any:
    folder = tmp_path_factory.mktemp("opcua")
    run = folder / "r.h5"
    assert main(["simulate", "demo", "--out", str(run), "--serial", "UA-7"]) == 0
    from stand.solve import solve_recording

    return solve_recording(str(run))


async def _browse(client: Any, stand: str) -> tuple[int, Any]:
    idx = await client.get_namespace_index(NS)
    node = await client.nodes.objects.get_child([f"{idx}:Machines", f"{idx}:{stand}"])
    return idx, node


def test_browse_read_call_subscribe_and_the_event_within_a_second(
    tmp_path: Path, demo_result: Any, capfd: pytest.CaptureFixture[str]
) -> None:
    from stand.archive import Archive, archive_result
    from stand.plant import ResultServer

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    Archive(url).close()
    port = _port()
    server = ResultServer(url, "stand-7", "127.0.0.1", port)
    server.run_in_thread()
    try:
        asyncio.run(_client(f"opc.tcp://127.0.0.1:{port}/stand/", url, demo_result))
    finally:
        server.stop()
    err = capfd.readouterr().err
    assert "Traceback" not in err, err
    assert "GetLatestResult: 1 arguments, it takes 0 (BadTooManyArguments)" in err, err

    del archive_result


async def _client(endpoint: str, url: str, result: Any) -> None:
    from asyncua import Client, ua

    from stand.archive import archive_result
    from stand.solve import to_json

    result = type(result)(**{**result.__dict__, "provenance": type(result.provenance)(
        **{**result.provenance.__dict__, "stand_id": "stand-7"})})  # fmt: skip
    async with Client(endpoint) as client:
        idx, stand = await _browse(client, "stand-7")
        names = {(await n.read_browse_name()).Name for n in await stand.get_children()}
        assert {"Identification", "MachineryItemState", "Results"} <= names
        ident = await stand.get_child([f"{idx}:Identification"])
        props = {(await n.read_browse_name()).Name: await n.read_value()
                 for n in await ident.get_children()}  # fmt: skip
        assert props["SerialNumber"] == "stand-7" and props["SoftwareRevision"]
        state = await stand.get_child([f"{idx}:MachineryItemState", f"{idx}:CurrentState"])
        assert await state.read_value() == "NotExecuting"
        latest = await stand.get_child([f"{idx}:Results", f"{idx}:LatestResult"])
        heard: list[tuple[float, Any]] = []

        class Handler:
            def event_notification(self, event: Any) -> None:
                heard.append((time.perf_counter(), event))

        etype = await client.nodes.base_event_type.get_child([f"{idx}:ResultReadyEventType"])
        sub = await client.create_subscription(50, Handler())
        await sub.subscribe_events(stand, etype)
        await asyncio.sleep(0.5)
        done = time.perf_counter()
        run_id = archive_result(result, url)  # the balance run's last step
        while not heard and time.perf_counter() - done < 5:
            await asyncio.sleep(0.02)
        assert heard, "no result-ready event"
        delay = heard[0][0] - done
        assert delay < 1.0, delay
        assert heard[0][1].ResultId == run_id and heard[0][1].RotorSerial == "UA-7"
        values = {}
        for key in ("ResultId", "RotorSerial", "Verdict", "RunFileSha256"):
            values[key] = await (await latest.get_child([f"{idx}:{key}"])).read_value()
        assert values["ResultId"] == run_id and values["RotorSerial"] == "UA-7"
        out = to_json(result)
        for i in (1, 2):
            plane = await latest.get_child([f"{idx}:Plane{i}"])
            got = await (await plane.get_child([f"{idx}:ResidualUnbalance_g_mm"])).read_value()
            assert got == pytest.approx(out["planes"][i - 1]["unbalance_g_mm"], abs=1e-3)
        results = await stand.get_child([f"{idx}:Results"])
        method = await results.get_child([f"{idx}:GetLatestResult"])
        called = json.loads(await results.call_method(method))
        assert called["job"]["serial"] == "UA-7" and called["planes"] == out["planes"]
        # a call the method does not take: the specification's status code, one line
        with pytest.raises(ua.UaStatusCodeError) as bad:
            await results.call_method(method, ua.Variant(7, ua.VariantType.Int64))
        assert bad.value.code == ua.StatusCodes.BadTooManyArguments
        rid = await latest.get_child([f"{idx}:ResultId"])
        with pytest.raises(ua.UaError):  # read-only for every client
            await rid.write_value(ua.Variant(5, ua.VariantType.Int64))
        await sub.delete()
    print(f"result-ready event {1000 * delay:.0f} ms after archiving")


def test_a_user_and_password_keep_anonymous_clients_out(tmp_path: Path) -> None:
    from stand.archive import Archive
    from stand.plant import Access, ResultServer

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    Archive(url).close()
    port = _port()
    server = ResultServer(url, None, "127.0.0.1", port, Access("mes", "a-long-password"))
    server.run_in_thread()

    async def clients() -> None:
        from asyncua import Client

        endpoint = f"opc.tcp://127.0.0.1:{port}/stand/"
        with pytest.raises(Exception, match=r"(?i)identity|token|denied|rejected"):
            async with Client(endpoint) as anonymous:
                await anonymous.get_namespace_index(NS)
        client = Client(endpoint)
        client.set_user("mes")
        client.set_password("a-long-password")
        async with client:
            _, stand = await _browse(client, "stand")
            assert await stand.get_children()

    try:
        asyncio.run(clients())
    finally:
        server.stop()


def test_a_port_in_use_or_a_bind_without_a_password_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert main(["opcua", "--port", str(port), "--archive", url]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"127.0.0.1:{port}" in err[0] and "in use" in err[0], err
    assert main(["opcua", "--host", "0.0.0.0", "--archive", url]) == 2
    assert "--password-file" in capsys.readouterr().err


def test_the_station_serves_opcua_beside_its_screens(tmp_path: Path) -> None:
    import os
    import subprocess
    import sys

    port, ua_port = _port(), _port()
    host = socket.gethostname()[:64]
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_CURRENT_TEST"}
    env["XDG_DATA_HOME"] = str(tmp_path / "data")
    proc = subprocess.Popen(
        [sys.executable, "-m", "stand.cli", "station", "--no-browser", "--port", str(port),
         "--opcua", "--opcua-port", str(ua_port), "--runs-dir", str(tmp_path / "runs"),
         "--archive", f"sqlite:///{tmp_path / 'a.sqlite'}"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env, text=True,
    )  # fmt: skip

    async def state() -> str:
        from asyncua import Client

        end = time.monotonic() + 60
        while True:
            try:
                async with Client(f"opc.tcp://127.0.0.1:{ua_port}/stand/") as client:
                    # one identity: the machine is the stand id its runs are archived
                    # under (no [stand] id: the host name), and so is its SerialNumber
                    idx, stand = await _browse(client, host)
                    serial = await stand.get_child([f"{idx}:Identification", f"{idx}:SerialNumber"])
                    assert await serial.read_value() == host
                    node = await stand.get_child(
                        [f"{idx}:MachineryItemState", f"{idx}:CurrentState"]
                    )
                    return str(await node.read_value())
            except (OSError, TimeoutError):
                assert proc.poll() is None and time.monotonic() < end, "no OPC UA server"
                await asyncio.sleep(0.3)

    try:
        assert asyncio.run(state()) == "NotExecuting"
    finally:
        proc.terminate()
        proc.wait(15)


def test_a_guarded_method_answers_each_bad_call_with_its_status_code(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """OPC 10000-4's Call results, one stderr line each, never a traceback."""
    from asyncua import ua

    from stand.errors import UsageError
    from stand.plant.ua_call import guarded

    async def by_id(rid: int) -> list:
        if rid < 0:
            raise UsageError(f"no result {rid}")
        if rid == 0:
            raise KeyError("the method's own fault")
        return [ua.Variant(str(rid), ua.VariantType.String)]

    call = guarded("GetResultById", [ua.VariantType.Int64], by_id)
    i64 = lambda v: ua.Variant(v, ua.VariantType.Int64)  # noqa: E731
    cases = [
        ((), "BadArgumentsMissing"),
        ((i64(1), i64(2)), "BadTooManyArguments"),
        ((ua.Variant("1", ua.VariantType.String),), "BadInvalidArgument"),
        ((i64(-1),), "BadInvalidArgument"),
        ((i64(0),), "BadInternalError"),
    ]
    for args, code in cases:
        res = asyncio.run(call(None, *args))
        assert res.StatusCode.value == getattr(ua.StatusCodes, code), (args, res)
    mismatch = asyncio.run(call(None, ua.Variant("1", ua.VariantType.String)))
    assert [s.value for s in mismatch.InputArgumentResults] == [ua.StatusCodes.BadTypeMismatch]
    assert asyncio.run(call(None, i64(5)))[0].Value == "5"
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == len(cases) + 1 and all(ln.startswith("stand opcua: ") for ln in lines)
    assert "Traceback" not in "\n".join(lines)
