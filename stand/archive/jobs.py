"""The job orders a line's MES sends the stand (OPC 40001-3, Machinery Job Management),
kept in the archive so that the OPC UA server that receives them and the station or CLI
that runs them (other processes) share one list.

A job order names the stand, the rotor type, the rotor's serial, where given the order
and the operator.  Its state moves as ISA95JobOrderReceiverObjectType's does::

    stored (Store, StoreAndStart)  -> AllowedToStart
    the station or CLI runs it     -> Running        (:func:`take_job`)
    a run under it passes          -> Ended          (:func:`job_ran`, when it is archived)
    the operator leaves the rotor  -> Ended          (:func:`end_job`)
    the MES aborts it              -> Aborted        (from AllowedToStart or Running)

Cancel removes a job not yet started, Clear one that ended or was aborted.  Every row
read back is checked (:func:`stand.archive.validate.job_row`).
"""

from __future__ import annotations

import datetime as dt
from typing import Any

from stand.archive.schema import jobs
from stand.archive.store import Archive
from stand.archive.validate import JOB_STATES, as_stored, job_row, shown_url

MAX_JOBS = 100
"""The most job orders a stand keeps at once (MaxDownloadableJobOrders)."""
COMMANDS = {
    "start": ("AllowedToStart",),
    "abort": ("AllowedToStart", "Running"),
    "cancel": ("AllowedToStart",),
    "clear": ("Ended", "Aborted"),
}
"""The states a job order must be in for each command of the MES."""

__all__ = [
    "COMMANDS",
    "JOB_STATES",
    "MAX_JOBS",
    "command",
    "end_job",
    "insert_job",
    "job_by_id",
    "job_ran",
    "jobs_of",
    "take_job",
]  # fmt: skip


def _now() -> str:
    return dt.datetime.now(dt.UTC).isoformat(timespec="milliseconds")


def _where(stand: str, job_id: str) -> Any:
    return (jobs.c.stand_id == stand) & (jobs.c.job_order_id == job_id)


def _select() -> Any:
    """Every column, and ``start_requested`` as stored too (:func:`as_stored`)."""
    import sqlalchemy as sa

    return sa.select(jobs, as_stored(jobs.c.start_requested))


def insert_job(conn: Any, stand: str, fields: dict[str, Any], *, start: bool) -> str | None:
    """Keep a new job order (``fields``: ``job_id``, ``rotor_type``, ``serial``, ``order``,
    ``operator``, ``description``, checked by the caller) in the state AllowedToStart,
    to be started at once when ``start``, in the open transaction ``conn``.  None when
    kept; else why not: ``duplicate`` (the stand has a job order of that id) or ``full``
    (:data:`MAX_JOBS` kept)."""
    import sqlalchemy as sa

    if conn.execute(sa.select(jobs.c.id).where(_where(stand, fields["job_id"]))).first():
        return "duplicate"
    kept = conn.execute(
        sa.select(sa.func.count()).select_from(jobs).where(jobs.c.stand_id == stand)
    ).scalar_one()
    if kept >= MAX_JOBS:
        return "full"
    conn.execute(sa.insert(jobs).values(
        stand_id=stand, job_order_id=fields["job_id"], rotor_type=fields["rotor_type"],
        serial=fields["serial"], order_no=fields.get("order"),
        operator=fields.get("operator"), description=fields.get("description"),
        state="AllowedToStart", start_requested=start, stored_at=_now(),
    ))  # fmt: skip
    return None


def command(conn: Any, stand: str, job_id: str, what: str) -> str:
    """The MES's ``what`` (a key of :data:`COMMANDS`) on a job order, in the open
    transaction ``conn``: ``ok``, ``unknown`` (no such job order) or ``state`` (not in a
    state the command applies to)."""
    import sqlalchemy as sa

    state = conn.execute(sa.select(jobs.c.state).where(_where(stand, job_id))).scalar()
    if state is None:
        return "unknown"
    if state not in COMMANDS[what]:
        return "state"
    if what in ("cancel", "clear"):
        conn.execute(sa.delete(jobs).where(_where(stand, job_id)))
    elif what == "start":
        conn.execute(sa.update(jobs).where(_where(stand, job_id)).values(start_requested=True))
    else:
        conn.execute(sa.update(jobs).where(_where(stand, job_id))
                     .values(state="Aborted", ended_at=_now()))  # fmt: skip
    return "ok"


def jobs_of(archive: Archive, stand: str, states: tuple[str, ...] | None = None
            ) -> list[dict[str, Any]]:  # fmt: skip
    """The stand's job orders (in ``states`` only, when given), checked, oldest first."""

    with archive.transaction() as conn:
        q = _select().where(jobs.c.stand_id == stand)
        if states is not None:
            q = q.where(jobs.c.state.in_(states))
        rows = conn.execute(q.order_by(jobs.c.stored_at, jobs.c.id)).all()
        where = shown_url(conn)
    return [job_row(r, where) for r in rows]


def job_by_id(archive: Archive, stand: str, job_id: str) -> dict[str, Any] | None:
    """One job order of the stand, checked; None if there is none of that id."""

    with archive.transaction() as conn:
        row = conn.execute(_select().where(_where(stand, job_id))).first()
        return None if row is None else job_row(row, shown_url(conn))


def take_job(conn: Any, stand: str, job_id: str) -> tuple[dict[str, Any] | None, bool]:
    """The station or CLI runs the job order, in the open transaction ``conn``: Running
    from AllowedToStart (Running stays Running: a check run under the same job).  The job
    (None when there is no such job order or it ended or was aborted: the MES's word is
    final), and whether it was started now."""
    import sqlalchemy as sa

    started = conn.execute(sa.update(jobs)
                           .where(_where(stand, job_id) & (jobs.c.state == "AllowedToStart"))
                           .values(state="Running", started_at=_now())).rowcount  # fmt: skip
    row = conn.execute(_select().where(_where(stand, job_id))).first()
    job = None if row is None else job_row(row, shown_url(conn))
    return (job if job is not None and job["state"] == "Running" else None), bool(started)


def job_ran(conn: Any, stand: str, job_id: str, run_id: int, verdict: str) -> None:
    """A run under the job order was archived (in the archive's open transaction ``conn``):
    it is the job's latest run; the job is Running, and Ended when the run passed."""
    import sqlalchemy as sa

    now = _now()
    running = _where(stand, job_id) & jobs.c.state.in_(("AllowedToStart", "Running"))
    conn.execute(sa.update(jobs).where(running).values(
        run_id=run_id, verdict=verdict, state="Ended" if verdict == "pass" else "Running",
        started_at=sa.func.coalesce(jobs.c.started_at, now),
        ended_at=now if verdict == "pass" else None,
    ))  # fmt: skip


def end_job(conn: Any, stand: str, job_id: str) -> bool:
    """The operator left the rotor of a Running job order (its last verdict stays), in the
    open transaction ``conn``; whether one was ended."""
    import sqlalchemy as sa

    return bool(conn.execute(sa.update(jobs)
                             .where(_where(stand, job_id) & (jobs.c.state == "Running"))
                             .values(state="Ended", ended_at=_now())).rowcount)  # fmt: skip
