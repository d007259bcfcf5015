"""The job orders the line's MES sends (OPC 40001-3), each step journaled with who made
it in the transaction that makes it: a job order stored (by the OPC UA user who sent
it), the MES's Start, Abort, Cancel and Clear, the station's operator starting it and
leaving its rotor.  Who may send jobs is the OPC UA server's check
(:mod:`stand.plant.opcua.security`), made before the call; the entries attribute it."""

from __future__ import annotations

import json
from typing import Any

from stand.actions.door import Actor, Passage, door
from stand.archive.audit import Change, sha256_of
from stand.archive.jobs import command, end_job, insert_job, take_job


def _journal(p: Passage, stand: str, job_id: str, step: str, **more: Any) -> None:
    p.journal(Change("job", f"job order {job_id} for {stand}: {step}", None, None, None,
                     detail={"job_order_id": job_id, "stand": stand, "step": step,
                             **more}))  # fmt: skip


def receive_job(url: str, actor: Actor, stand: str, fields: dict[str, Any], *,
                start: bool) -> str | None:  # fmt: skip
    """Keep the job order ``fields`` for ``stand`` (:func:`stand.archive.jobs.insert_job`)
    and journal it; None when kept, else why not (``duplicate``, ``full``: nothing
    journaled)."""
    with door(url, actor, None, "send a job order") as p:
        why = insert_job(p.conn, stand, fields, start=start)
        if why is not None:
            p.unchanged = True
            return why
        text = json.dumps(fields, sort_keys=True, default=str)
        _journal(
            p,
            stand,
            fields["job_id"],
            "stored",
            rotor_type=fields["rotor_type"],
            serial=fields["serial"],
            start=start,
            fields_sha256=sha256_of(text),
        )
    return None


def command_job(url: str, actor: Actor, stand: str, job_id: str, what: str) -> str:
    """The MES's ``what`` (start, abort, cancel, clear) on a job order, journaled when it
    applies: ``ok``, ``unknown`` or ``state`` (:func:`stand.archive.jobs.command`)."""
    with door(url, actor, None, "command a job order") as p:
        said = command(p.conn, stand, job_id, what)
        if said == "ok":
            _journal(p, stand, job_id, what)
        else:
            p.unchanged = True
    return said


def start_job(url: str, actor: Actor, stand: str, job_id: str) -> dict[str, Any] | None:
    """The operator runs the job order (:func:`stand.archive.jobs.take_job`): the job
    (None: no longer waiting), journaled when it starts now."""
    with door(url, actor, None, "start a job order") as p:
        job, started = take_job(p.conn, stand, job_id)
        if started:
            _journal(p, stand, job_id, "running")
        else:
            p.unchanged = True
    return job


def leave_job(url: str, actor: Actor, stand: str, job_id: str) -> None:
    """The operator leaves the rotor of a Running job order: Ended, journaled."""
    with door(url, actor, None, "end a job order") as p:
        if end_job(p.conn, stand, job_id):
            _journal(p, stand, job_id, "ended")
        else:
            p.unchanged = True
