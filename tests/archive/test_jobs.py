"""The job orders in the archive (OPC 40001-3 by way of :mod:`stand.archive.jobs`): their
states as ISA-95 moves them, the run that ends one, and rows no writer could have made."""

from __future__ import annotations

import dataclasses
import json
import sqlite3
from pathlib import Path

import pytest
import sqlalchemy as sa

from stand.actions import (
    Actor,
    archive_run,
    command_job,
    leave_job,
    os_actor,
    receive_job,
    start_job,
)
from stand.archive import Archive
from stand.archive.audit import entries
from stand.archive.jobs import MAX_JOBS, job_by_id, jobs_of
from stand.cli import main
from stand.errors import ArchiveRowError
from stand.solve import Job, solve_recording

STAND = "stand-9"
MES, OPERATOR = Actor("mes", None, "opcua"), Actor("olena", None, "station")
"""Who sends the job orders (an OPC UA user) and who runs them (the station's operator)."""


def store_job(archive: Archive, stand: str, fields: dict[str, str], *, start: bool) -> str | None:
    return receive_job(archive.url, MES, stand, fields, start=start)


def command(archive: Archive, stand: str, job_id: str, what: str) -> str:
    return command_job(archive.url, MES, stand, job_id, what)


def take_job(archive: Archive, stand: str, job_id: str) -> dict[str, object] | None:
    return start_job(archive.url, OPERATOR, stand, job_id)


def end_job(archive: Archive, stand: str, job_id: str) -> None:
    leave_job(archive.url, OPERATOR, stand, job_id)


def _job(job_id: str = "J-1", **more: str) -> dict[str, str]:
    return {"job_id": job_id, "rotor_type": "demo-auger", "serial": "SN-1", **more}


@pytest.fixture
def archive(tmp_path: Path) -> Archive:
    with Archive(f"sqlite:///{tmp_path / 'a.sqlite'}") as a:
        yield a


def test_a_job_order_moves_as_isa95_says(archive: Archive) -> None:
    assert store_job(archive, STAND, _job(order="PO-7", operator="Olena"), start=False) is None
    assert store_job(archive, STAND, _job(), start=False) == "duplicate"
    assert store_job(archive, "stand-other", _job(), start=False) is None  # another stand's
    (job,) = jobs_of(archive, STAND)
    assert (job["state"], job["order"], job["operator"], job["start_requested"]) == (
        "AllowedToStart", "PO-7", "Olena", False)  # fmt: skip
    assert command(archive, STAND, "J-1", "clear") == "state"  # not ended yet
    assert command(archive, STAND, "J-1", "start") == "ok"
    assert job_by_id(archive, STAND, "J-1")["start_requested"] is True
    assert take_job(archive, STAND, "J-1")["state"] == "Running"
    assert take_job(archive, STAND, "J-1")["state"] == "Running"  # a check run: still it
    assert command(archive, STAND, "J-1", "cancel") == "state"  # running: abort, not cancel
    end_job(archive, STAND, "J-1")
    assert job_by_id(archive, STAND, "J-1")["state"] == "Ended"
    assert take_job(archive, STAND, "J-1") is None  # the end is final
    assert command(archive, STAND, "J-1", "abort") == "state"
    assert command(archive, STAND, "J-1", "clear") == "ok"
    assert command(archive, STAND, "J-1", "clear") == "unknown"
    assert [j["stand"] for j in jobs_of(archive, "stand-other")] == ["stand-other"]
    # every step that moved a job, journaled by who made it; a refused command none
    steps = [(e["who"], e["source"], json.loads(e["detail"])["step"])
             for e in entries(archive.url, action="job")
             if json.loads(e["detail"])["stand"] == STAND]  # fmt: skip
    assert steps == [("mes", "opcua", "stored"), ("mes", "opcua", "start"),
                     ("olena", "station", "running"), ("olena", "station", "ended"),
                     ("mes", "opcua", "clear")], steps  # fmt: skip


def test_aborted_and_cancelled(archive: Archive) -> None:
    for name in ("A", "B"):
        store_job(archive, STAND, _job(name), start=True)
    assert command(archive, STAND, "A", "abort") == "ok"
    assert take_job(archive, STAND, "A") is None
    assert command(archive, STAND, "B", "cancel") == "ok"
    assert [j["job_id"] for j in jobs_of(archive, STAND)] == ["A"]
    assert jobs_of(archive, STAND, ("Aborted",))[0]["ended_at"] is not None


def test_the_stand_keeps_at_most_max_jobs(archive: Archive) -> None:
    for i in range(MAX_JOBS):
        assert store_job(archive, STAND, _job(f"J{i}"), start=False) is None
    assert store_job(archive, STAND, _job("one-more"), start=False) == "full"


def test_a_passing_run_under_the_job_ends_it(archive: Archive, tmp_path: Path) -> None:
    run = tmp_path / "r.h5"
    assert main(["simulate", "demo", "--out", str(run), "--serial", "SN-1"]) == 0
    result = solve_recording(str(run))
    store_job(archive, STAND, _job(), start=False)
    take_job(archive, STAND, "J-1")
    prov = dataclasses.replace(result.provenance, stand_id=STAND,
                               job=Job(serial="SN-1", job_id="J-1"))  # fmt: skip
    run_id = archive_run(dataclasses.replace(result, provenance=prov), archive.url, os_actor())
    job = job_by_id(archive, STAND, "J-1")
    verdict = archive.engine.connect().execute(sa.text(
        f"select verdict, job_id from runs where id = {run_id}")).one()  # fmt: skip
    assert (job["run_id"], job["verdict"], verdict.job_id) == (run_id, verdict.verdict, "J-1")
    # the demo run without a correction: its verdict says whether the job ended
    assert job["state"] == ("Ended" if verdict.verdict == "pass" else "Running")


@pytest.mark.parametrize(("column", "value"), [
    ("state", "Paused"), ("serial", ""), ("job_order_id", "x" * 65), ("stored_at", "today"),
    ("run_id", 0), ("verdict", "maybe"), ("start_requested", 7),
])  # fmt: skip
def test_a_job_row_no_writer_made_is_refused(archive: Archive, column: str, value: object
                                             ) -> None:  # fmt: skip
    store_job(archive, STAND, _job(), start=False)
    with sqlite3.connect(archive.url.removeprefix("sqlite:///")) as db:  # another program
        db.execute(f"UPDATE jobs SET {column} = ?", (value,))
    with pytest.raises(ArchiveRowError, match=column):
        jobs_of(archive, STAND)
