"""The OPC UA server read by a client of another implementation: node-opcua (JavaScript),
``tests/js/ua_client.js``, written from the namespace URIs and the OPC Foundation's NodeIds
alone.  It browses to the machine, reads its identification and state, subscribes on the
Server object with ``OfType ResultReadyEventType``, decodes each event's Result, calls the
three methods and decodes ResultDataType; then the same over the encrypted endpoint from
another network namespace."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from foreign import NodeUaClient

from stand.cli import main

ARCHIVER = """
import dataclasses, sys, time
from stand.actions import archive_run, os_actor
from stand.solve import solve_recording
url = sys.argv[1]
for path in sys.argv[2:]:
    r = solve_recording(path)
    r = dataclasses.replace(r, provenance=dataclasses.replace(r.provenance, stand_id="stand-7"))
    time.sleep(0.6)  # apart by more than the server's poll: one event each
    run_id = archive_run(r, url, os_actor())
    print(run_id, time.time(), flush=True)
"""
"""Another process that archives each run given, printing its id and when it was archived."""
EVALUATION_NAMES = {"pass": "OK", "fail": "NotOK", "undecided": "NotDecidable", "none": "Undefined"}


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    folder = tmp_path_factory.mktemp("foreign-ua")
    out = []
    for k in range(3):
        out.append(folder / f"r{k}.h5")
        assert main(["simulate", "demo", "--out", str(out[-1]), "--seed", str(k + 1),
                     "--serial", f"UA-{k}", "--order", "J-12"]) == 0  # fmt: skip
    return out


@contextmanager
def serving(url: str, stand: str, host: str = "127.0.0.1", access: Any = None,
            certs: Path | None = None, rotor_types: list[str] | None = None
            ) -> Iterator[str]:  # fmt: skip
    """A result server of ``stand`` on ``url`` (taking job orders for ``rotor_types``);
    its endpoint."""
    from stand.archive import Archive
    from stand.plant import ResultServer

    Archive(url).close()
    port = _port()
    kwargs: dict[str, Any] = {} if certs is None else {"cert_dir": certs}
    if rotor_types is not None:
        kwargs["rotor_types"] = lambda: rotor_types
    server = ResultServer(url, stand, host, port, access, **kwargs)
    server.run_in_thread()
    try:
        yield f"opc.tcp://{host}:{port}/stand/"
    finally:
        server.stop()


def archive_in_another_process(url: str, runs: list[Path]) -> list[tuple[str, float]]:
    done = subprocess.run([sys.executable, "-c", ARCHIVER, url, *map(str, runs)],
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert done.returncode == 0, done.stderr
    return [(a, float(b)) for a, b in (line.split() for line in done.stdout.split("\n") if line)]


def heard_events(url: str, runs: list[Path]) -> tuple[dict[str, Any], list[Any], dict[str, Any],
                                                        list[float], list[str]]:  # fmt: skip
    """node-opcua against a server: its ready line, the events it heard as runs were
    archived by another process, its calls, the latencies (archive -> event) [s], and the
    archived ids."""
    with serving(url, "stand-7") as endpoint:
        client = NodeUaClient(endpoint, "stand-7", len(runs))
        try:
            ready = client.next()
            archived = archive_in_another_process(url, runs)
            events = [client.next()["event"] for _ in runs]
            calls = client.next()["calls"]
        finally:
            client.close()
    latency = [e["t"] - t for e, (_, t) in zip(events, archived, strict=True)]
    return ready, events, calls, latency, [a for a, _ in archived]


def test_node_opcua_reads_results_and_hears_each_one(tmp_path: Path, runs: list[Path]) -> None:
    from stand.archive.query import Filters, history

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    ready, events, calls, latency, ids = heard_events(url, runs)
    ident = ready["identification"]
    assert ident["SerialNumber"] == "stand-7" and ident["Manufacturer"]
    assert ident["ProductInstanceUri"].endswith(":stand-7") and ready["state"] == "NotExecuting"
    assert ready["evaluationNames"] == {"0": "Undefined", "1": "OK", "2": "NotOK",
                                        "3": "NotDecidable"}  # fmt: skip
    rows = {str(r["id"]): r for r in history(url, Filters())}
    for event, run_id in zip(events, ids, strict=True):
        result, row = event["result"], rows[run_id]
        assert result["resultId"] == run_id and result["partId"] == row["serial"]
        assert result["jobId"] == "J-12" and result["isSimulated"] is True
        assert result["evaluationName"] == EVALUATION_NAMES[row["verdict"]]
        (content,) = result["content"]
        assert content["verdict"] == row["verdict"]
        assert content["runFileSha256"] == row["file_sha256"]
        for got, want in zip(content["planes"], row["planes"], strict=True):
            assert got["residualUnbalance_g_mm"] == pytest.approx(want["unbalance_g_mm"], abs=1e-9)
            assert got["residualAngle_deg"] == pytest.approx(want["angle_deg"], abs=1e-9)
    assert calls["latest"]["result"] == events[-1]["result"] and calls["latest"]["error"] == 0
    assert calls["byId"]["result"] == events[-1]["result"]
    assert calls["list"] == {"ids": ids[::-1], "error": 0}
    print("node-opcua event latency [s]: " + ", ".join(f"{x:.3f}" for x in latency))
    assert max(latency) < 30  # a hang guard: the figure is tests/bench/bench_ua_events.py's


@contextmanager
def network_namespace() -> Iterator[tuple[str, str, str]]:
    """A network namespace joined to this one by a veth pair: (name, this side's address,
    its side's address); skipped where the machine does not allow it."""
    ip = shutil.which("ip")
    if ip is None or os.geteuid() != 0:
        pytest.skip("a network namespace needs root and iproute2 (apt-get install iproute2)")
    tag = uuid.uuid4().hex[:6]
    name, here, there = f"stand-{tag}", f"vh{tag}", f"vn{tag}"
    net = 10 + int(tag[:2], 16) % 200
    steps = [[ip, "netns", "add", name],
             [ip, "link", "add", here, "type", "veth", "peer", "name", there],
             [ip, "link", "set", there, "netns", name],
             [ip, "addr", "add", f"10.231.{net}.1/24", "dev", here],
             [ip, "link", "set", here, "up"],
             [ip, "netns", "exec", name, ip, "addr", "add", f"10.231.{net}.2/24", "dev", there],
             [ip, "netns", "exec", name, ip, "link", "set", there, "up"],
             [ip, "netns", "exec", name, ip, "link", "set", "lo", "up"]]  # fmt: skip
    try:
        for step in steps:
            done = subprocess.run(step, capture_output=True, text=True, timeout=30)
            if done.returncode:
                pytest.skip(f"this machine makes no network namespace ({done.stderr.strip()})")
        yield name, f"10.231.{net}.1", f"10.231.{net}.2"
    finally:
        subprocess.run([ip, "link", "del", here], capture_output=True, timeout=30)
        subprocess.run([ip, "netns", "del", name], capture_output=True, timeout=30)


def test_node_opcua_over_the_encrypted_endpoint_from_another_host(
    tmp_path: Path, runs: list[Path]
) -> None:
    """Beyond loopback only Basic256Sha256 with SignAndEncrypt and a user: node-opcua in
    another network namespace, its application certificate not yet trusted, is refused
    and its certificate kept in ``rejected/``; trusted from there (``stand opcua trust``,
    as plant IT does), it logs in as the MES user and reads the machine and its latest
    result; without the password it is refused."""
    from stand.plant.opcua.security import Access

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    certs = tmp_path / "certs"
    certs.mkdir()
    with network_namespace() as (name, host, _):
        with serving(url, "stand-7", host, Access("mes", "a-long-password"), certs) as endpoint:
            archive_in_another_process(url, runs[:1])
            prefix = ("ip", "netns", "exec", name)
            untrusted = NodeUaClient(endpoint, "stand-7", 0, "mes", "a-long-password",
                                     prefix=prefix)  # fmt: skip
            try:
                with pytest.raises(AssertionError):
                    untrusted.next()
            finally:
                untrusted.close()
            (seen,) = (certs / "rejected").iterdir()
            assert main(["opcua", "trust", str(seen), "--cert-dir", str(certs),
                         "--archive", url]) == 0  # fmt: skip
            client = NodeUaClient(endpoint, "stand-7", 0, "mes", "a-long-password", prefix=prefix)
            try:
                ready = client.next()
                calls = client.next()["calls"]
            finally:
                client.close()
            wrong = NodeUaClient(endpoint, "stand-7", 0, "mes", "not-the-password", prefix=prefix)
            try:
                with pytest.raises(AssertionError):
                    wrong.next()
            finally:
                wrong.close()
    assert ready["identification"]["SerialNumber"] == "stand-7"
    assert calls["latest"]["result"]["partId"] == "UA-0" and calls["list"]["error"] == 0


def mes_round_trip(url: str, folder: Path, job_id: str) -> tuple[dict[str, Any], dict[str, Any],
                                                                   int, float]:  # fmt: skip
    """node-opcua as the MES (``tests/js/ua_jobs.js``) against a server of this host's
    stand taking the rotor type ``demo``: the job order stored, ``stand balance --scene demo
    --job`` run under it here; the client's lines ``stored`` and ``done``, the balance's
    exit code and how long it took [s]."""
    from stand.config import default_stand_id

    stand = default_stand_id()
    with serving(url, stand, rotor_types=["demo"]) as endpoint:
        client = NodeUaClient(endpoint, stand, "demo", job_id, script="ua_jobs.js")
        try:
            stored = client.next()["stored"]
            began = time.monotonic()
            code = main(["balance", "--scene", "demo", "--job", job_id, "--archive", url,
                         "--out", str(folder / f"{job_id}.h5"), "--quiet"])  # fmt: skip
            took = time.monotonic() - began
            done = client.next()["done"]
        finally:
            client.close()
    return stored, done, code, took


def test_a_mes_in_node_opcua_sends_a_job_and_reads_its_result(tmp_path: Path) -> None:
    """OPC 40001-3 from another implementation: the job order stored, three refused as
    ISA-95 says, the run made under it (``stand balance --job``), its response's ResultId
    giving the result whose JobId is the job's.  The round trip: Store -> the result
    readable, with the run's physics (2 s of revolutions) inside it."""
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    stored, done, code, took = mes_round_trip(url, tmp_path, "MES-1")
    assert code == 0 and stored["masters"] == ["demo"] and stored["status"] == 1
    assert stored["refused"] == {"duplicate": 16 | 1 << 32, "unknownRotorType": 16,
                                 "serialTooLong": 1 << 32}  # fmt: skip
    result, response = done["result"], done["response"]
    assert result == {"error": 0, "jobId": "MES-1", "partId": "SN-MES-1",
                      "resultId": response["data"]["ResultId"]}  # fmt: skip
    ended = response["data"]["Verdict"] == "pass"
    assert response["state"] == done["jobs"]["MES-1"] == ("Ended" if ended else "Running")
    print(
        f"job round trip (Store -> result readable): {done['roundTripS']:.2f} s, the "
        f"balance {took:.2f} s of it; Store answered in {1000 * stored['callS']:.0f} ms"
    )
