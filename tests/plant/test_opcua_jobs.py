"""The MES sends the stand its jobs (OPC 40001-3 with ISA-95 Job Control), driven by an
asyncua client that knows only the namespace URIs and the Foundation's NodeIds: it finds
JobManagement by its type, stores job orders, is refused as the specification says, and
reads back the job order list and the job's response, whose ResultId gives the result
archived under the job (its JobId the job's).  The node-opcua client does the round trip
in ``test_opcua_foreign``."""

from __future__ import annotations

import asyncio
import socket
from pathlib import Path
from typing import Any

import pytest
from accounts import with_accounts
from mes import job_management

from stand.cli import main
from stand.config import default_stand_id

RESULT = "http://opcfoundation.org/UA/Machinery/Result/"
NO_ERROR, UNKNOWN_ID, INVALID_STATUS, UNABLE, INVALID_REQUEST = 1, 2, 8, 16, 1 << 32
"""ReturnStatus bits (OPC 10031-4 Annex B)."""


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _order(ua: Any, job_id: str, rotor: str = "demo", serial: str | None = "SN-1",
           **more: Any) -> Any:  # fmt: skip
    params = (
        []
        if serial is None
        else [ua.ISA95ParameterDataType(ID="SerialNumber", Value=ua.Variant(serial))]
    )
    return ua.ISA95JobOrderDataType(
        JobOrderID=job_id, WorkMasterID=[ua.ISA95WorkMasterDataType(ID=rotor)],
        JobOrderParameters=params + more.pop("params", []), **more)  # fmt: skip


async def _mes(endpoint: str, url: str, tmp: Path) -> dict[str, Any]:
    from asyncua import Client, ua

    async with Client(endpoint) as client:
        await client.load_data_type_definitions()
        control, results, ns = await job_management(client)

        async def call(node: Any, name: str, *args: Any) -> Any:
            return await node.call_method(ua.QualifiedName(name, ns["i"]), *args)

        none = ua.Variant([], ua.VariantType.LocalizedText)
        out: dict[str, Any] = {"refused": {}}
        out["masters"] = [w.ID for w in await (await control.get_child(
            [f"{ns['i']}:WorkMaster"])).read_value()]  # fmt: skip
        person = [ua.ISA95PersonnelDataType(ID="Olena")]
        out["store"] = await call(control, "Store", _order(ua, "J-1", PersonnelRequirements=person),
                                  none)  # fmt: skip
        bad = {
            "duplicate": _order(ua, "J-1"),
            "unknown rotor type": _order(ua, "J-2", rotor="no-such-rotor"),
            "no serial": _order(ua, "J-3", serial=None),
            "serial too long": _order(ua, "J-4", serial="S" * 65),
            "unknown parameter": _order(ua, "J-5", params=[
                ua.ISA95ParameterDataType(ID="Colour", Value=ua.Variant("red"))]),
            "another machine": _order(ua, "J-6", EquipmentRequirements=[
                ua.ISA95EquipmentDataType(ID="lathe-3")]),
            "empty id": _order(ua, ""),
        }  # fmt: skip
        for why, order in bad.items():
            out["refused"][why] = await call(control, "Store", order, none)
        out["start_unknown"] = await call(control, "Start", "J-404", none)
        out["clear_running"] = await call(control, "Clear", "J-1", none)
        await call(control, "StoreAndStart", _order(ua, "J-7", serial="SN-7"), none)
        await call(control, "Store", _order(ua, "J-8", serial="SN-8"), none)
        out["cancel"] = await call(control, "Cancel", "J-8", none)
        out["abort"] = await call(control, "Abort", "J-7", none)
        await asyncio.sleep(0.6)  # the server polls the archive every 0.25 s
        listed = await (await control.get_child([f"{ns['i']}:JobOrderList"])).read_value()
        out["list"] = {j.JobOrder.JobOrderID: j.State[0].StateText.Text for j in listed}
        out["current"] = (await (await control.get_child(["0:CurrentState"])).read_value()).Text
        run = tmp / "r.h5"
        out["balance"] = await asyncio.to_thread(main, [
            "balance", "--scene", "demo", "--job", "J-1", "--archive", url, "--out", str(run),
            "--quiet", "--json"])  # fmt: skip
        response, status = await call(results, "RequestJobResponseByJobOrderID", "J-1")
        out["response"] = (status, response.JobState[0].StateText.Text,
                           {p.ID: p.Value.Value for p in response.JobResponseData})  # fmt: skip
        rm = await (await control.get_parent()).get_parent()
        r = (await client.get_namespace_array()).index(RESULT)
        management = await rm.get_child([f"{r}:ResultManagement"])
        _, result, error = await management.call_method(
            ua.QualifiedName("GetResultById", r),
            out["response"][2]["ResultId"],
            ua.Variant(0, ua.VariantType.Int32),
        )
        out["result"] = (error, result.ResultMetaData.JobId, result.ResultMetaData.PartId)
        state = ua.ISA95StateDataType(BrowsePath=ua.RelativePath(), StateNumber=6,
                                      StateText=ua.LocalizedText("Aborted"))  # fmt: skip
        aborted, status = await call(results, "RequestJobResponseByJobOrderState", [state])
        out["aborted"] = (status, [r.JobOrderID for r in aborted])
        out["clear_aborted"] = await call(control, "Clear", "J-7", none)
        return out


def test_the_mes_stores_jobs_is_refused_as_isa95_says_and_reads_the_result(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    from stand.archive import Archive
    from stand.plant import ResultServer

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    Archive(url).close()
    port = _port()
    server = ResultServer(url, default_stand_id(), "127.0.0.1", port,
                          rotor_types=lambda: ["demo"])  # fmt: skip
    server.run_in_thread()
    try:
        out = asyncio.run(_mes(f"opc.tcp://127.0.0.1:{port}/stand/", url, tmp_path))
    finally:
        server.stop()
    assert out["masters"] == ["demo"]
    assert out["store"] == NO_ERROR
    assert out["refused"] == {
        "duplicate": UNABLE | INVALID_REQUEST, "unknown rotor type": UNABLE,
        "no serial": INVALID_REQUEST, "serial too long": INVALID_REQUEST,
        "unknown parameter": INVALID_REQUEST, "another machine": UNABLE,
        "empty id": INVALID_REQUEST,
    }  # fmt: skip
    assert (out["start_unknown"], out["clear_running"]) == (UNKNOWN_ID, INVALID_STATUS)
    assert (out["cancel"], out["abort"]) == (NO_ERROR, NO_ERROR)
    assert out["list"] == {"J-1": "AllowedToStart", "J-7": "Aborted"}
    assert out["current"] == "AllowedToStart"
    assert out["balance"] == 0
    status, state, data = out["response"]
    assert status == NO_ERROR and data["SerialNumber"] == "SN-1"
    assert state == ("Ended" if data["Verdict"] == "pass" else "Running")
    assert out["result"] == (0, "J-1", "SN-1")  # the result archived under the job
    assert out["aborted"] == (NO_ERROR, ["J-7"])
    assert out["clear_aborted"] == NO_ERROR
    err = capfd.readouterr().err
    assert "Traceback" not in err and "refused: WorkMasterID 'no-such-rotor'" in err, err


def test_balance_refuses_a_job_it_cannot_run(tmp_path: Path, capsys: Any) -> None:
    """``--job`` naming no waiting job order, or beside the job's own fields: exit 2."""
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    base = ["balance", "--scene", "demo", "--archive", url, "--out", str(tmp_path / "r.h5")]
    assert main([*base, "--job", "J-404"]) == 2
    assert "no such job order waiting or running" in capsys.readouterr().err
    assert main([*base, "--job", "J-1", "--serial", "X"]) == 2
    assert "leave out --serial" in capsys.readouterr().err


def test_the_stands_accounts_decide_who_may_send_jobs(tmp_path: Path) -> None:
    """With accounts in the archive: anonymous is not let in at all (it read before); an
    operator reads but may not send a job (BadUserAccessDenied); a setter may; a wrong
    password does not log in."""
    from asyncua import Client, ua
    from asyncua.ua.uaerrors import BadUserAccessDenied

    from stand.archive import Archive
    from stand.plant import ResultServer

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    Archive(url).close()
    (tmp_path / "pw").write_text("a-long-password\n")
    with_accounts(url, ("kim", "operator", "a-long-password"), ("ana", "setter", "a-long-password"))
    port = _port()
    server = ResultServer(url, "stand-7", "127.0.0.1", port, rotor_types=lambda: ["demo"])
    server.run_in_thread()
    endpoint = f"opc.tcp://127.0.0.1:{port}/stand/"

    async def store(user: str | None, password: str = "a-long-password") -> str:
        client = Client(endpoint)
        if user:
            client.set_user(user)
            client.set_password(password)
        stage = "log-in"
        try:
            async with client:
                stage = "call"
                await client.load_data_type_definitions()
                control, _, ns = await job_management(client)
                await control.get_child(["0:CurrentState"])  # reading: anyone
                bits = await control.call_method(
                    ua.QualifiedName("Store", ns["i"]),
                    _order(ua, f"J-{user}"),
                    ua.Variant([], ua.VariantType.LocalizedText),
                )
                return f"stored {bits}"
        except BadUserAccessDenied:
            return f"denied at {stage}"

    try:
        got = {who: asyncio.run(store(who)) for who in (None, "kim", "ana")}
        wrong = asyncio.run(store("ana", "not-her-password"))
    finally:
        server.stop()
    assert got == {None: "denied at log-in", "kim": "denied at call", "ana": "stored 1"}, got
    assert wrong == "denied at log-in"
    # journaled: who sent the job order (the OPC UA user), and each log-in, failed or not
    from stand.archive.audit import entries

    (job,) = entries(url, action="job")
    assert (job["who"], job["source"]) == ("ana", "opcua") and "J-ana" in job["subject"]
    assert {(e["who"], e["source"]) for e in entries(url, action="login")} >= {
        ("kim", "opcua"), ("ana", "opcua")}  # fmt: skip
    failed = [(e["who"], e["source"]) for e in entries(url, action="login_failed")]
    assert ("ana", "opcua") in failed and "not-her-password" not in str(entries(url))
