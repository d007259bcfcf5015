"""The OPC UA result server, driven by a client written from the companion specifications
alone: it knows the namespace URIs and NodeIds of DI, Machinery (OPC 40001-1) and Machinery
Result (OPC 40001-101), never the server's own names; it browses, reads, calls, decodes
and subscribes on the Server object.  Then who may connect, and bad input."""

from __future__ import annotations

import asyncio
import os
import socket
import stat
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from stand.cli import main

MACHINERY = "http://opcfoundation.org/UA/Machinery/"
STAND = "urn:rotor-stand:balancing-stand"
"""The stand's own namespace (docs/plant.md)."""
DI = "http://opcfoundation.org/UA/DI/"
RESULT = "http://opcfoundation.org/UA/Machinery/Result/"
NAMESPACE = "urn:rotor-stand:balancing-stand"
"""The stand's own namespace, as docs/plant.md gives it."""
MACHINES, MACHINE_IDENTIFICATION_TYPE, ITEM_STATE_TYPE = 1001, 1012, 1002
NOT_EXECUTING, OPERATION_MODE_TYPE = 5007, 1008
RESULT_MANAGEMENT_TYPE, RESULT_READY_EVENT_TYPE = 1004, 1002
"""From the Foundation's NodeIds lists (Machinery, Machinery/Result)."""
SERVER_OBJECT, ORGANIZES, HAS_ADD_IN = 2253, 35, 17604
"""Namespace 0: the Server object, Organizes, HasAddIn."""
ARCHIVE_IN_ANOTHER_PROCESS = """
import dataclasses, sys, time
from stand.actions import archive_run, os_actor
from stand.solve import solve_recording
r = solve_recording(sys.argv[1])
r = dataclasses.replace(r, provenance=dataclasses.replace(r.provenance, stand_id="stand-7"))
run_id = archive_run(r, sys.argv[2], os_actor())
print(run_id, time.time(), flush=True)
"""


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def demo_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    run = tmp_path_factory.mktemp("opcua") / "r.h5"
    assert main(["simulate", "demo", "--out", str(run), "--serial", "UA-7", "--order", "J-12"]) == 0
    return run


async def _machine(client: Any, serial: str) -> tuple[dict[str, int], Any]:
    """The namespace indices by URI, and the machine in Machines whose
    MachineIdentificationType identification has this SerialNumber."""
    from asyncua import ua

    uris = await client.get_namespace_array()
    ns = {"di": uris.index(DI), "m": uris.index(MACHINERY), "r": uris.index(RESULT),
          "own": uris.index(STAND)}  # fmt: skip
    machines = client.get_node(ua.NodeId(MACHINES, ns["m"]))
    for machine in await machines.get_children(refs=ORGANIZES):
        ident = await machine.get_child([f"{ns['di']}:Identification"])
        if await ident.read_type_definition() != ua.NodeId(MACHINE_IDENTIFICATION_TYPE, ns["m"]):
            continue
        if await (await ident.get_child([f"{ns['di']}:SerialNumber"])).read_value() == serial:
            return ns, machine
    raise AssertionError(f"no machine {serial} in Machines")


async def _typed(node: Any, type_id: Any, refs: int) -> Any:
    """The child of ``node`` (by ``refs``) whose type definition is ``type_id``."""
    for child in await node.get_children(refs=refs):
        if await child.read_type_definition() == type_id:
            return child
    raise AssertionError(f"no child of type {type_id}")


def _with_server(url: str, client: Any) -> Any:
    """``client(endpoint)`` run against a server of stand-7 on a new archive ``url``."""
    from stand.archive import Archive
    from stand.plant import ResultServer

    Archive(url).close()
    port = _port()
    server = ResultServer(url, "stand-7", "127.0.0.1", port)
    server.run_in_thread()
    try:
        return asyncio.run(client(f"opc.tcp://127.0.0.1:{port}/stand/"))
    finally:
        server.stop()


def test_a_client_from_the_specifications_finds_calls_and_hears_a_result(
    tmp_path: Path, demo_run: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """Machine in Machines by its identification; the state machine; ResultManagement by
    its type; GetLatestResult, GetResultById and GetResultIdListFiltered decoded as
    ResultDataType; a ResultReadyEventType on the Server object within 1 s of another
    process archiving a run; every node read-only."""
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    delay = _with_server(url, lambda endpoint: _client(endpoint, url, demo_run))
    err = capfd.readouterr().err
    assert "Traceback" not in err, err
    print(f"ResultReadyEvent on the Server object {1000 * delay:.0f} ms after archiving")


async def _client(endpoint: str, url: str, run: Path) -> float:
    from asyncua import Client, ua

    async with Client(endpoint) as client:
        ns, machine = await _machine(client, "stand-7")
        blocks = await machine.get_child([f"{ns['m']}:MachineryBuildingBlocks"])
        sm = await blocks.get_child([f"{ns['m']}:MachineryItemState"])
        assert await sm.read_type_definition() == ua.NodeId(ITEM_STATE_TYPE, ns["m"])
        current = await sm.get_child(["0:CurrentState"])
        assert (await current.read_value()).Text == "NotExecuting"
        state_id = await (await current.get_child(["0:Id"])).read_value()
        assert state_id == ua.NodeId(NOT_EXECUTING, ns["m"])
        mode = await blocks.get_child([f"{ns['m']}:MachineryOperationMode"])
        assert await mode.read_type_definition() == ua.NodeId(OPERATION_MODE_TYPE, ns["m"])
        mode_now = await mode.get_child(["0:CurrentState"])  # beside no station: none known
        assert (await mode_now.read_value()).Text == "None"
        assert await (await mode_now.get_child(["0:Id"])).read_value() == ua.NodeId(5024, ns["m"])
        rm = await _typed(machine, ua.NodeId(RESULT_MANAGEMENT_TYPE, ns["r"]), HAS_ADD_IN)
        await client.load_data_type_definitions()
        heard: list[tuple[float, Any]] = []

        class Handler:
            def event_notification(self, event: Any) -> None:
                heard.append((time.time(), event))

        sub = await client.create_subscription(50, Handler())
        etype = client.get_node(ua.NodeId(RESULT_READY_EVENT_TYPE, ns["r"]))
        await sub.subscribe_events(client.get_node(ua.NodeId(SERVER_OBJECT)), etype)
        await asyncio.sleep(0.5)
        proc = await asyncio.create_subprocess_exec(
            sys.executable, "-c", ARCHIVE_IN_ANOTHER_PROCESS, str(run), url,
            stdout=asyncio.subprocess.PIPE,
        )  # fmt: skip
        out, _ = await proc.communicate()
        run_id, archived_at = out.split()
        while not heard and time.time() - float(archived_at) < 5:
            await asyncio.sleep(0.02)
        assert len(heard) == 1, "one result-ready event on the Server object"
        delay = heard[0][0] - float(archived_at)
        assert delay < 1.0, delay
        event = heard[0][1].Result
        assert event.ResultMetaData.ResultId == run_id.decode()
        await _calls(ns, rm, run_id.decode(), event, url)
        with pytest.raises(ua.UaError):  # read-only for every client
            await current.write_value(ua.LocalizedText("Executing"))
        await sub.delete()
    return delay


async def _calls(ns: dict[str, int], rm: Any, run_id: str, event: Any, url: str) -> None:
    """The three methods, their ResultDataType decoded, against the event and the run."""
    from asyncua import ua

    from stand.archive.query import Filters, history

    def method(name: str) -> Any:
        return rm.get_child([f"{ns['r']}:{name}"])

    timeout = ua.Variant(0, ua.VariantType.Int32)
    handle, result, error = await rm.call_method(await method("GetLatestResult"), timeout)
    assert (handle, error) == (0, 0)
    meta = result.ResultMetaData
    assert meta.ResultId == run_id and meta.PartId == "UA-7" and meta.JobId == "J-12"
    assert meta.IsSimulated is True and meta.ResultState == 1
    assert meta.CreationTime is not None and meta.ProcessingTimes.EndTime > meta.CreationTime
    assert meta == event.ResultMetaData
    # the browse path docs/plant.md gives: the folder Result:Results, the variable in the
    # stand's own namespace (Result:Results/Result:LatestResult was BadNoMatch)
    latest = await rm.get_child([f"{ns['r']}:Results", f"{ns['own']}:LatestResult"])
    assert (await latest.read_value()).ResultMetaData.ResultId == run_id
    (variant,) = result.ResultContent
    content = variant.Value  # BaseDataType: a Variant holding the stand's structure
    (row,) = [r for r in history(url, Filters()) if str(r["id"]) == run_id]
    assert content.Verdict == row["verdict"] and content.RunFileSha256 == row["file_sha256"]
    codes = {"pass": 1, "fail": 2, "undecided": 3, "none": 0}  # ResultEvaluationEnum
    assert int(meta.ResultEvaluation) == codes[row["verdict"]]
    for got, want in zip(content.Planes, row["planes"], strict=True):
        assert got.ResidualUnbalance_g_mm == pytest.approx(want["unbalance_g_mm"], abs=1e-9)
        assert got.ResidualAngle_deg == pytest.approx(want["angle_deg"], abs=1e-9)
        assert got.Permissible_g_mm == pytest.approx(want["permissible_g_mm"], abs=1e-9)
        assert got.Pass is want["pass"]
    by_id = await method("GetResultById")
    _, again, error = await rm.call_method(by_id, ua.Variant(run_id), timeout)
    assert error == 0 and again == result
    _, none, error = await rm.call_method(by_id, ua.Variant("999"), timeout)
    assert error == -1 and getattr(none, "Body", none) is None  # a null ExtensionObject
    for spelled in ("²", "\u0661", "0" + run_id, None):  # another spelling, or none at all
        got = await rm.call_method(by_id, ua.Variant(spelled, ua.VariantType.String), timeout)
        assert got[2] == -1, spelled
    wrong = await rm.call_method(  # a ReadValueId where the ContentFilter goes: not "all"
        await method("GetResultIdListFiltered"), ua.Variant(ua.ReadValueId()),
        ua.Variant([], ua.VariantType.ExtensionObject), ua.Variant(0, ua.VariantType.UInt32),
        timeout,
    )  # fmt: skip
    assert wrong == [0, [], -2]
    listed = await rm.call_method(
        await method("GetResultIdListFiltered"), ua.Variant(ua.ContentFilter()),
        ua.Variant([], ua.VariantType.ExtensionObject), ua.Variant(0, ua.VariantType.UInt32),
        timeout,
    )  # fmt: skip
    assert listed == [0, [run_id], 0]
    unfiltered = await rm.call_method(  # a null Filter and OrderedBy: none given, every one
        await method("GetResultIdListFiltered"), ua.Variant(None, ua.VariantType.Null),
        ua.Variant(None, ua.VariantType.Null), ua.Variant(1, ua.VariantType.UInt32), timeout,
    )  # fmt: skip
    assert unfiltered == [0, [run_id], 0]


def _client_certificate(folder: Path) -> tuple[Path, Path]:
    """A client application's own certificate and key (asyncua's generator)."""
    from asyncua.crypto import cert_gen
    from cryptography import x509
    from cryptography.hazmat.primitives.serialization import Encoding
    from cryptography.x509.oid import ExtendedKeyUsageOID

    key = cert_gen.generate_private_key()
    uri = "urn:test:mes-client"
    cert = cert_gen.generate_self_signed_app_certificate(
        key, "mes-client", {}, [x509.UniformResourceIdentifier(uri)],
        extended=[ExtendedKeyUsageOID.CLIENT_AUTH],
    )  # fmt: skip
    (folder / "client.der").write_bytes(cert.public_bytes(Encoding.DER))
    (folder / "client.pem").write_bytes(cert_gen.dump_private_key_as_pem(key))
    return folder / "client.der", folder / "client.pem"


def test_off_loopback_only_an_encrypted_client_with_user_and_password_gets_in(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Served on every interface: an anonymous client over the plain endpoint is refused;
    over Basic256Sha256 SignAndEncrypt with the password, a client application the stand
    does not trust is refused too (``BadCertificateUntrusted``: a fresh self-signed
    certificate got in before) and its certificate kept in ``rejected/``; once ``stand
    opcua trust`` trusts it (journaled) it gets in.  The server's certificate is made on
    first start (its key readable by the owner only) and kept."""
    from stand.archive import Archive
    from stand.archive.audit import entries
    from stand.plant import Access, ResultServer

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    Archive(url).close()
    certs = tmp_path / "certs"
    certs.mkdir()
    port = _port()
    server = ResultServer(url, "stand-9", "0.0.0.0", port, Access("mes", "a-long-password"),
                          cert_dir=certs)  # fmt: skip
    server.run_in_thread()
    cert, key = _client_certificate(tmp_path)

    async def connect() -> None:
        from asyncua import Client

        client = Client(f"opc.tcp://127.0.0.1:{port}/stand/", timeout=10)
        client.application_uri = "urn:test:mes-client"  # as its certificate names it
        client.set_user("mes")
        client.set_password("a-long-password")
        await client.set_security_string(f"Basic256Sha256,SignAndEncrypt,{cert},{key}")
        async with client:
            _, machine = await _machine(client, "stand-9")
            assert await machine.get_children()

    async def anonymous() -> None:
        from asyncua import Client

        with pytest.raises(Exception):  # noqa: B017 - asyncua raises its own kinds
            async with Client(f"opc.tcp://127.0.0.1:{port}/stand/", timeout=5) as c:
                await c.get_namespace_array()

    try:
        asyncio.run(anonymous())
        with pytest.raises(Exception, match=r"Untrusted"):
            asyncio.run(connect())
        assert [p.suffix for p in (certs / "rejected").iterdir()] == [".der"]
        assert main(["opcua", "trust", str(cert), "--cert-dir", str(certs), "--archive", url,
                     "--reason", "the line's MES"]) == 0  # fmt: skip
        assert "trusted" in capsys.readouterr().out
        asyncio.run(connect())
    finally:
        server.stop()
    (trust,) = entries(url, action="trust")
    assert trust["subject"].startswith("OPC UA client") and trust["reason"] == "the line's MES"
    made = certs / "server-cert.der"
    assert made.is_file() and stat.S_IMODE(os.stat(certs / "server-key.pem").st_mode) == 0o600
    first = made.read_bytes()
    again = ResultServer(url, "stand-9", "0.0.0.0", _port(), Access("mes", "pw"), cert_dir=certs)
    again.run_in_thread()
    again.stop()
    assert made.read_bytes() == first  # kept, not made anew


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--host", "0.0.0.0", "--user", "u", "--password-file", "{tmp}/pw", "--cert-dir",
          "{tmp}/no-such-folder"], "--cert-dir {tmp}/no-such-folder: no such folder"),
        (["--host", "0.0.0.0", "--user", "u", "--password-file", "{tmp}/missing"],
         "{tmp}/missing: cannot read a password"),
        (["--host", "0.0.0.0", "--user", "u", "--password-file", "{tmp}"],
         "{tmp}: is a directory, not a file holding a password"),
        (["--host", "0.0.0.0"], "--password-file"),
    ],
)  # fmt: skip
def test_bad_security_input_is_one_line(
    argv: list[str], says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "pw").write_text("a-long-password\n")
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    args = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main(["opcua", "--archive", url, "--port", str(_port()), *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says.replace("{tmp}", str(tmp_path)) in err, err


def test_a_port_in_use_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert main(["opcua", "--port", str(port), "--archive", url]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"127.0.0.1:{port}" in err[0] and "in use" in err[0], err


def test_the_station_serves_opcua_beside_its_screens(tmp_path: Path) -> None:
    """One identity: the station's machine is the stand id its runs are archived under
    (no [stand] id: the host name), and so is its SerialNumber; its state NotExecuting.
    The stand has accounts and ``--anonymous-read``: an anonymous client on this machine
    reads (without the flag it is refused: the test above)."""
    from accounts import with_accounts

    url = with_accounts(f"sqlite:///{tmp_path / 'a.sqlite'}", ("kim", "operator", "a-long-pw1"))
    port, ua_port = _port(), _port()
    host = socket.gethostname()[:64]
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_CURRENT_TEST"}
    env["XDG_DATA_HOME"] = str(tmp_path / "data")
    proc = subprocess.Popen(
        [sys.executable, "-m", "stand.cli", "station", "--no-browser", "--port", str(port),
         "--opcua", "--opcua-port", str(ua_port), "--anonymous-read",
         "--runs-dir", str(tmp_path / "runs"), "--archive", url],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env, text=True,
    )  # fmt: skip

    async def state() -> str:
        from asyncua import Client

        end = time.monotonic() + 60
        while True:
            try:
                async with Client(f"opc.tcp://127.0.0.1:{ua_port}/stand/") as client:
                    ns, machine = await _machine(client, host)
                    node = await machine.get_child([
                        f"{ns['m']}:MachineryBuildingBlocks", f"{ns['m']}:MachineryItemState",
                        "0:CurrentState"])  # fmt: skip
                    return str((await node.read_value()).Text)
            except (OSError, TimeoutError):
                assert proc.poll() is None and time.monotonic() < end, "no OPC UA server"
                await asyncio.sleep(0.3)

    try:
        assert asyncio.run(state()) == "NotExecuting"
    finally:
        proc.terminate()
        proc.communicate(timeout=15)  # and its stderr pipe closed: never left to the GC


def test_a_guarded_method_answers_each_bad_call_with_its_status_code(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """OPC 10000-4's Call results, one stderr line each, never a traceback."""
    from asyncua import ua

    from stand.errors import UsageError
    from stand.plant.opcua.call import guarded

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


def test_a_toolings_index_runs_are_no_results(tmp_path: Path, demo_run: Path) -> None:
    """What the server serves (latest, by id, the id list) leaves out runs marked as a
    tooling's index runs: they are no production results."""
    import dataclasses
    import hashlib

    from stand.archive import Archive, rows
    from stand.archive.query import latest, latest_id, newest_ids
    from stand.solve import solve_recording

    r = solve_recording(str(demo_run))
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    with Archive(url) as archive:
        ids = []
        for k in range(2):
            prov = dataclasses.replace(r.provenance, run_file=f"t/{k}.h5")
            digest = hashlib.sha256(prov.run_file.encode()).hexdigest()
            ids.append(archive.add(*rows(dataclasses.replace(r, provenance=prov), digest, None)))
        assert archive.mark_tooling([hashlib.sha256(b"t/1.h5").hexdigest()]) == [ids[1]]
        assert latest_id(archive) == ids[0] and newest_ids(archive) == [ids[0]]
        got = latest(archive)
        assert got is not None and got["id"] == ids[0]
        assert latest(archive, run_id=ids[1]) is None


EVALUATED = {
    "verdict": "pass",
    "u_mar_test": {"e_mar_g_mm_per_kg": 0.666667, "limit_pct": 12.0, "planes": [
        {"plane": 1, "mean_g_mm": 199.5, "spread_pct": 1.8},
        {"plane": 2, "mean_g_mm": 199.64, "spread_pct": 2.28}]},
    "urr_test": {"claim_pct": 95.0, "runs": [{"urr_pct": [99.37, None]},
                                             {"urr_pct": [99.26, 98.77]}]},
    "cross_effect_pct": [0.37, 0.28],
}  # fmt: skip
"""A machine evaluation's figures as ``stand evaluate --json`` gives them (the demo's)."""


def test_machine_evaluations_are_results_too(tmp_path: Path, demo_run: Path) -> None:
    """An evaluation archived while the server runs is a ResultReadyEvent on the Server
    object with ResultId ``E<id>`` and the stand's MachineEvaluationDataType; GetResultById
    gives it again, GetResultIdListFiltered lists it after the runs; another stand's is
    none of this server's."""
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    _with_server(url, lambda endpoint: _evaluation_client(endpoint, url))


async def _evaluation_client(endpoint: str, url: str) -> None:
    import datetime as dt

    from asyncua import Client, ua

    from stand.actions import archive_evaluation, os_actor

    async with Client(endpoint) as client:
        ns, machine = await _machine(client, "stand-7")
        rm = await _typed(machine, ua.NodeId(RESULT_MANAGEMENT_TYPE, ns["r"]), HAS_ADD_IN)
        await client.load_data_type_definitions()
        heard: list[Any] = []

        class Handler:
            def event_notification(self, event: Any) -> None:
                heard.append(event)

        sub = await client.create_subscription(50, Handler())
        etype = client.get_node(ua.NodeId(RESULT_READY_EVENT_TYPE, ns["r"]))
        await sub.subscribe_events(client.get_node(ua.NodeId(SERVER_OBJECT)), etype)
        await asyncio.sleep(0.5)
        archive_evaluation(url, os_actor(), "machine", "stand-8", {**EVALUATED, "verdict": "fail"},
                           simulated=True, software="test")  # another stand's  # fmt: skip
        eid, _, _ = archive_evaluation(url, os_actor(), "machine", "stand-7",
                                       {**EVALUATED, "verdict": "pass"}, simulated=True,
                                       software="test", due=dt.date(2026, 12, 27))  # fmt: skip
        end = time.monotonic() + 5
        while not heard and time.monotonic() < end:
            await asyncio.sleep(0.02)
        await asyncio.sleep(0.6)  # two polls more: nothing else is heard
        assert len(heard) == 1, "one event, for this stand's evaluation"
        result = heard[0].Result
        meta = result.ResultMetaData
        assert meta.ResultId == f"E{eid}" and meta.ProductId == "ISO 21940-21"
        assert int(meta.ResultEvaluation) == 1 and meta.IsSimulated is True
        (variant,) = result.ResultContent
        content = variant.Value
        assert content.Verdict == "pass" and content.Due == "2026-12-27"
        assert content.LowestUrr1_pct == 99.26 and content.LowestUrr2_pct == 98.77
        assert content.UmarSpread2_pct == 2.28 and content.Emar_g_mm_per_kg == 0.666667
        timeout = ua.Variant(0, ua.VariantType.Int32)
        by_id = await rm.get_child([f"{ns['r']}:GetResultById"])
        _, again, error = await rm.call_method(by_id, ua.Variant(f"E{eid}"), timeout)
        assert error == 0 and again == result
        for other in (f"E{eid - 1}", "E", "E0", "e1", f"E{eid}x"):  # stand-8's, or no id
            got = await rm.call_method(by_id, ua.Variant(other), timeout)
            assert got[2] == -1, other
        listed = await rm.call_method(
            await rm.get_child([f"{ns['r']}:GetResultIdListFiltered"]),
            ua.Variant(ua.ContentFilter()), ua.Variant([], ua.VariantType.ExtensionObject),
            ua.Variant(0, ua.VariantType.UInt32), timeout,
        )  # fmt: skip
        assert listed == [0, [f"E{eid}"], 0]
        await sub.delete()


BASE_EVENT_TYPE, AUDIT_EVENT_TYPE = 2041, 2052
"""Namespace 0: BaseEventType and AuditEventType (which the stand never emits)."""


def _filter(ns: dict[str, int], elements: list[Any]) -> Any:
    """An EventFilter written from OPC 10000-4: select EventType, Severity and the Result
    field; where ``elements`` (element 0 the root)."""
    from asyncua import ua

    def field(name: str, type_id: Any) -> Any:
        op = ua.SimpleAttributeOperand()
        op.TypeDefinitionId = type_id
        op.BrowsePath = [ua.QualifiedName(name, type_id.NamespaceIndex)]
        op.AttributeId = ua.AttributeIds.Value
        return op

    base = ua.NodeId(BASE_EVENT_TYPE)
    f = ua.EventFilter()
    f.SelectClauses = [field("EventType", base), field("Severity", base),
                       field("Result", ua.NodeId(RESULT_READY_EVENT_TYPE, ns["r"]))]  # fmt: skip
    f.WhereClause = ua.ContentFilter()
    f.WhereClause.Elements = elements
    return f


def _element(op: Any, *operands: Any) -> Any:
    from asyncua import ua

    el = ua.ContentFilterElement()
    el.FilterOperator = op
    el.FilterOperands = list(operands)
    return el


def _where_cases(ns: dict[str, int]) -> dict[str, tuple[list[Any], bool]]:
    """Where clauses a client written from Part 4 sends, and whether the stand's result
    event (a BalancingResultReadyEventType, severity 500 for the demo's failed run)
    passes each."""
    from asyncua import ua

    op = ua.FilterOperator
    ready = ua.LiteralOperand(Value=ua.Variant(ua.NodeId(RESULT_READY_EVENT_TYPE, ns["r"])))
    base = ua.LiteralOperand(Value=ua.Variant(ua.NodeId(BASE_EVENT_TYPE)))
    audit = ua.LiteralOperand(Value=ua.Variant(ua.NodeId(AUDIT_EVENT_TYPE)))
    severity = ua.SimpleAttributeOperand(TypeDefinitionId=ua.NodeId(BASE_EVENT_TYPE),
                                         BrowsePath=[ua.QualifiedName("Severity", 0)],
                                         AttributeId=ua.AttributeIds.Value)  # fmt: skip
    missing = ua.SimpleAttributeOperand(TypeDefinitionId=ua.NodeId(BASE_EVENT_TYPE),
                                        BrowsePath=[ua.QualifiedName("NoSuchField", 0)],
                                        AttributeId=ua.AttributeIds.Value)  # fmt: skip

    def lit(x: int) -> Any:
        return ua.LiteralOperand(Value=ua.Variant(x, ua.VariantType.UInt16))

    def el(i: int) -> Any:
        return ua.ElementOperand(Index=i)

    return {
        "OfType ResultReadyEventType": ([_element(op.OfType, ready)], True),
        "OfType BaseEventType": ([_element(op.OfType, base)], True),
        "OfType AuditEventType": ([_element(op.OfType, audit)], False),
        "And(OfType ready, Severity = 500)": ([_element(op.And, el(1), el(2)),
                                               _element(op.OfType, ready),
                                               _element(op.Equals, severity, lit(500))], True),
        "And(OfType ready, Severity = 100)": ([_element(op.And, el(1), el(2)),
                                               _element(op.OfType, ready),
                                               _element(op.Equals, severity, lit(100))], False),
        "Or(OfType audit, Severity InList 100, 500)": (
            [_element(op.Or, el(1), el(2)), _element(op.OfType, audit),
             _element(op.InList, severity, lit(100), lit(500))], True),
        "Not(OfType ready)": ([_element(op.Not, el(1)), _element(op.OfType, ready)], False),
        "Equals(NoSuchField, 1)": ([_element(op.Equals, missing, lit(1))], False),
        "IsNull(NoSuchField)": ([_element(op.IsNull, missing)], True),
    }  # fmt: skip


def test_where_clauses_are_evaluated_as_part_4_says(
    tmp_path: Path, demo_run: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """Nine event monitored items on the Server object, each with a where clause a client
    written from OPC 10000-4 sends; one run archived: OfType matches the type and its
    subtypes (asyncua compared for equality: OfType ResultReadyEventType heard nothing),
    And, Or, Not, Equals, InList and IsNull decide the rest; a field the event lacks is
    NULL, never a traceback."""
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    heard = _with_server(url, lambda endpoint: _where_client(endpoint, url, demo_run))
    for name, (got, want) in heard.items():
        assert got == want, name
    err = capfd.readouterr().err
    assert "Traceback" not in err, err


async def _where_client(endpoint: str, url: str, run: Path) -> dict[str, tuple[bool, bool]]:
    from asyncua import Client, ua

    async with Client(endpoint) as client:
        ns, _ = await _machine(client, "stand-7")
        cases = _where_cases(ns)
        heard: dict[int, list[Any]] = {}

        class Handler:
            def __init__(self, k: int) -> None:
                self.k = k

            def event_notification(self, event: Any) -> None:
                heard.setdefault(self.k, []).append(event)

        server_node = client.get_node(ua.NodeId(SERVER_OBJECT))
        etype = client.get_node(ua.NodeId(RESULT_READY_EVENT_TYPE, ns["r"]))
        subs = []
        for k, (elements, _) in enumerate(cases.values()):  # one subscription per clause
            subs.append(await client.create_subscription(50, Handler(k)))
            await subs[-1].subscribe_events(server_node, etype, evfilter=_filter(ns, elements))
        await asyncio.sleep(0.5)
        proc = await asyncio.create_subprocess_exec(
            sys.executable, "-c", ARCHIVE_IN_ANOTHER_PROCESS, str(run), url,
            stdout=asyncio.subprocess.PIPE,
        )  # fmt: skip
        await proc.communicate()
        await asyncio.sleep(1.5)  # six polls: every event there is has come
        for sub in subs:
            await sub.delete()
    return {name: (k in heard, want) for k, (name, (_, want)) in enumerate(cases.items())}


def test_the_audit_trails_head_is_a_variable_the_plant_keeps(
    tmp_path: Path, demo_run: Path
) -> None:
    """The machine's AuditHead is the head the anchor beside the stand's key keeps: empty
    before any entry, the new head once a run is archived (journaled); given back to
    ``stand audit verify --head`` it verifies."""
    from stand.actions import archive_run, os_actor
    from stand.archive.audit import anchored_head
    from stand.solve import solve_recording

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"

    async def client(endpoint: str) -> tuple[str, str]:
        from asyncua import Client

        async with Client(endpoint) as c:
            uris = await c.get_namespace_array()
            _, machine = await _machine(c, "stand-7")
            own = uris.index(NAMESPACE)
            node = await machine.get_child([f"{own}:AuditHead"])
            before = await node.read_value()
            archive_run(solve_recording(str(demo_run)), url, os_actor())
            end = time.monotonic() + 10
            while (after := await node.read_value()) == before and time.monotonic() < end:
                await asyncio.sleep(0.05)
            return before, after

    before, after = _with_server(url, client)
    assert before == "" and after == anchored_head(url) and after.startswith("1:")
    assert main(["audit", "verify", "--archive", url, "--head", after]) == 0


@pytest.mark.parametrize("anonymous_read", [False, True])
def test_anonymous_clients_only_on_a_lone_stand_or_when_allowed(
    tmp_path: Path, anonymous_read: bool
) -> None:
    """Once the archive has accounts an anonymous client on this machine is refused (it
    read every result before); ``--anonymous-read`` lets it read."""
    from accounts import with_accounts

    from stand.plant import ResultServer

    url = with_accounts(f"sqlite:///{tmp_path / 'a.sqlite'}", ("kim", "operator", "a-long-pw1"))
    port = _port()
    server = ResultServer(url, "stand-9", "127.0.0.1", port, anonymous_read=anonymous_read)
    server.run_in_thread()

    async def read() -> None:
        from asyncua import Client

        async with Client(f"opc.tcp://127.0.0.1:{port}/stand/", timeout=5) as c:
            await _machine(c, "stand-9")

    try:
        if anonymous_read:
            asyncio.run(read())
        else:
            with pytest.raises(Exception):  # noqa: B017 - asyncua raises its own kinds
                asyncio.run(read())
    finally:
        server.stop()


def test_opcua_log_ins_are_braked_like_the_stations(tmp_path: Path) -> None:
    """A real OPC UA server with accounts: after 5 wrong passwords of an account the next
    try waits, unchecked, even with the right password (BadUserAccessDenied), and is not
    journaled; the 5 failures are, from ``opcua``."""
    from accounts import with_accounts

    from stand.archive.audit import entries
    from stand.plant import ResultServer

    url = with_accounts(f"sqlite:///{tmp_path / 'a.sqlite'}", ("kim", "operator", "a-long-pw1"))
    port = _port()
    server = ResultServer(url, "stand-9", "127.0.0.1", port)
    server.run_in_thread()

    async def log_in(password: str) -> bool:
        from asyncua import Client

        c = Client(f"opc.tcp://127.0.0.1:{port}/stand/", timeout=5)
        c.set_user("kim")
        c.set_password(password)
        try:
            async with c:
                return True
        except Exception:
            return False

    try:
        assert asyncio.run(log_in("a-long-pw1"))
        assert [asyncio.run(log_in("wrong-pw-1")) for _ in range(5)] == [False] * 5
        assert not asyncio.run(log_in("a-long-pw1"))  # the account waits
    finally:
        server.stop()
    failed = [(e["who"], e["source"]) for e in entries(url, action="login_failed")]
    assert failed == [("kim", "opcua")] * 5, failed


def test_runs_archived_between_two_polls_are_each_heard(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Three runs archived while the server waits between two polls (a slow poll, as on a
    busy machine): three ResultReady events, oldest first, and LatestResult the newest
    (one event for the latest alone lost the other two)."""
    import dataclasses

    from stand.actions import archive_run, os_actor
    from stand.plant.opcua import server as server_module
    from stand.solve import solve_recording

    monkeypatch.setattr(server_module, "POLL_S", 3.0)
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    results = []
    for k in range(3):  # three rotors
        run = tmp_path / f"r{k}.h5"
        assert main(["simulate", "demo", "--out", str(run), "--serial", f"UA-{k}"]) == 0
        r = solve_recording(str(run))
        prov = dataclasses.replace(r.provenance, stand_id="stand-7")
        results.append(dataclasses.replace(r, provenance=prov))

    async def client(endpoint: str) -> list[str]:
        from asyncua import Client, ua

        async with Client(endpoint) as c:
            ns, _ = await _machine(c, "stand-7")
            heard: list[Any] = []

            class Handler:
                def event_notification(self, event: Any) -> None:
                    heard.append(event)

            sub = await c.create_subscription(50, Handler())
            etype = c.get_node(ua.NodeId(RESULT_READY_EVENT_TYPE, ns["r"]))
            await sub.subscribe_events(c.get_node(ua.NodeId(SERVER_OBJECT)), etype)
            await asyncio.sleep(3.5)  # a poll has passed: the next one is 3 s away
            ids = [str(archive_run(r, url, os_actor())) for r in results]
            end = time.monotonic() + 30
            while len(heard) < 3 and time.monotonic() < end:
                await asyncio.sleep(0.1)
            assert [e.Result.ResultMetaData.ResultId for e in heard] == ids, ids
            return ids

    assert len(_with_server(url, client)) == 3
