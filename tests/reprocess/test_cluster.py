"""stand reprocess on a Dask cluster: the same bytes as this machine's processes, and a
worker lost mid-way costs only its retried tasks (every run lands in the revision once).

The cluster is a Dask ``LocalCluster`` of two worker processes on 127.0.0.1, started here.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import sqlite3
from pathlib import Path

import pytest

from stand.cli import main

distributed = pytest.importorskip("distributed", reason="pip install -e '.[cluster]'")

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "stand" / "data" / "scenes" / "production-drift.toml"


@pytest.fixture(scope="module")
def cluster() -> object:
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
        dashboard_address=None, silence_logs=50,
    ) as c:  # fmt: skip
        yield c


@pytest.fixture(scope="module")
def series(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, Path]:
    """16 rotors (32 runs) and a config with support 1 20 % softer."""
    d = tmp_path_factory.mktemp("series")
    url = f"sqlite:///{d / 'a.sqlite'}"
    (d / "runs").mkdir()
    args = ["simulate", "production-drift", "--series", "16", "--out-dir", str(d / "runs")]
    assert main([*args, "--archive", url]) == 0
    cfg = d / "stand.toml"
    assert main(["inspect", str(d / "runs" / "S-00001-a.h5"), "--config-out", str(cfg)]) == 0
    text = cfg.read_text()
    assert "C1 = 45000.0" in text
    new = d / "new.toml"
    new.write_text(text.replace("C1 = 45000.0", "C1 = 36000.0"))
    return url, new


def revision_rows(url: str, name: str) -> tuple[list, list]:
    """The revision's run rows (without its time) and plane rows, in run order: the bytes
    that must not depend on where the runs were solved."""
    con = sqlite3.connect(url.removeprefix("sqlite:///"))
    rid = "(SELECT id FROM revisions WHERE name = ?)"
    runs = con.execute(
        f"SELECT run_id, status, reason, verdict, result_json FROM revised "
        f"WHERE revision_id = {rid} ORDER BY run_id",
        (name,),
    ).fetchall()
    planes = con.execute(
        f"SELECT run_id, plane, U_re_kg_m, U_im_kg_m, radius95_kg_m, "
        f"permissible_kg_m, passed, leftover_kg_m, urr FROM revised_planes "
        f"WHERE revision_id = {rid} ORDER BY run_id, plane",
        (name,),
    ).fetchall()
    con.close()  # fmt: skip
    return runs, planes


def test_local_processes_and_the_cluster_give_the_same_bytes(
    cluster: object, series: tuple[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """One process, two processes and two Dask workers store byte-identical revisions (the
    floats compared as stored, the result's JSON as text)."""
    url, new = series
    base = ["reprocess", "--archive", url, "--config", str(new), "--json"]
    address = cluster.scheduler_address  # type: ignore[attr-defined]
    for name, how in (("one", ["--jobs", "1"]), ("two", ["--jobs", "2"]),
                      ("dask", ["--scheduler", address])):  # fmt: skip
        capsys.readouterr()
        assert main([*base, "--revision", name, *how]) == 0, capsys.readouterr().err
        assert json.loads(capsys.readouterr().out)["counts"]["ok"] == 32
    one = revision_rows(url, "one")
    assert len(one[0]) == 32 and len(one[1]) == 64
    assert revision_rows(url, "two") == one
    assert revision_rows(url, "dask") == one


def test_a_worker_killed_mid_way_costs_only_its_tasks(
    cluster: object, series: tuple[str, Path]
) -> None:
    """SIGKILL to one worker after the first task is written: the scheduler gives its tasks
    to the other (or to its restarted self); every run lands in the revision once."""
    from stand.reprocess import DaskEngine, Request, Selection, reprocess

    url, new = series
    engine = DaskEngine(cluster.scheduler_address)  # type: ignore[attr-defined]
    pids = list(engine.client.run(os.getpid).values())
    assert len(pids) == 2
    killed: list[int] = []

    def progress(done: int, total: int) -> None:
        if done and not killed:
            assert done < total  # mid-way, or the test shows nothing
            os.kill(pids[1], signal.SIGKILL)
            killed.append(done)

    try:
        out = reprocess(url, Request(Selection(), "killed", str(new)), engine, progress)
    finally:
        engine.close()
    assert killed and out["counts"]["ok"] == 32 and out["counts"]["solved_now"] == 32
    runs, planes = revision_rows(url, "killed")
    assert [r[0] for r in runs] == sorted({r[0] for r in runs}) and len(runs) == 32
    assert len(planes) == 64


def test_a_scheduler_that_does_not_answer_is_one_line(
    capsys: pytest.CaptureFixture[str], series: tuple[str, Path]
) -> None:
    """Nothing listens on the port, or a port accepts and stays silent: one line naming
    the scheduler and the 10 s the connection is given, exit 2 (no clock read here: the
    time-out is the socket's, and the words say it was the one that ended the wait)."""
    url, new = series
    silent = socket.socket()
    silent.bind(("127.0.0.1", 0))
    silent.listen(8)  # the kernel completes the connection; nobody ever answers
    try:
        for address in ("tcp://127.0.0.1:9", f"tcp://127.0.0.1:{silent.getsockname()[1]}"):
            capsys.readouterr()
            args = ["reprocess", "--archive", url, "--config", str(new), "--revision", "z"]
            assert main([*args, "--scheduler", address]) == 2
            err = capsys.readouterr().err
            assert err.count("\n") == 1, err
            assert f"scheduler {address}: did not answer within 10 s" in err, err
    finally:
        silent.close()
