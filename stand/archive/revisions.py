"""Revisions: archived runs re-judged (``stand reprocess``), stored beside the originals.

A revision has a name, the digest of the config its runs were re-solved with (None: each
run's own stored config, a software update's re-run), the software and the time.  Each run
it re-solved has one row (its status: ``ok``, ``missing``, ``altered``, ``unreadable`` or
``refused``, and for ``ok`` the new verdict and result) and one row per plane, in the
columns of the archive's own plane rows.  A run is written into a revision once: a second
write of it is skipped (or, asked to replace, replaces it in one transaction).  The runs and
planes of the archive itself are never changed.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterable
from typing import Any

from stand.archive.schema import revised, revised_planes, revisions
from stand.archive.store import Archive
from stand.errors import UsageError

STATUSES = ("ok", "missing", "altered", "unreadable", "refused")
"""What became of a run in a revision: re-solved; its file gone; its file not the one
archived (digest); its file not readable as a run; or refused by the solve (named why)."""


def _now() -> str:
    return dt.datetime.now(dt.UTC).isoformat(timespec="seconds")


def revision_id_in(conn: Any, name: str) -> int:
    """The id of the revision ``name`` (UsageError naming the ones there are if none)."""
    import sqlalchemy as sa

    found = conn.execute(sa.select(revisions.c.id).where(revisions.c.name == name)).scalar()
    if found is None:
        names = [r.name for r in conn.execute(sa.select(revisions.c.name).order_by("id"))]
        there = ", ".join(names) if names else "none yet"
        raise UsageError(f"--revision {name}: no such revision in the archive (there: {there})")
    return int(found)


def open_revision(
    archive: Archive, name: str, config_sha256: str | None, config_source: str | None,
    software: str,
) -> tuple[int, bool]:  # fmt: skip
    """The revision ``name``, made if new: ``(id, new)``.  An existing one must have been
    made with the same config (UsageError otherwise: its runs would mix two judgements)."""
    import sqlalchemy as sa

    if not name or len(name) > 64 or not name.isprintable():
        raise UsageError(f"--revision {name!r}: a name of 1 to 64 printable characters")
    with archive.transaction() as conn:
        row = conn.execute(sa.select(revisions).where(revisions.c.name == name)).first()
        if row is None:
            new = conn.execute(revisions.insert().values(
                name=name, config_sha256=config_sha256, config_source=config_source,
                software=software, created_at=_now(),
            ))  # fmt: skip
            return int(new.inserted_primary_key[0]), True
    if row.config_sha256 != config_sha256:
        was = "each run's stored config" if row.config_sha256 is None else (
            f"the config {row.config_source} (sha256 {row.config_sha256[:12]})")  # fmt: skip
        raise UsageError(
            f"--revision {name}: that revision was made with {was}, not this one: name "
            "another revision (or give the same config)"
        )
    return int(row.id), False


def revised_ids(archive: Archive, revision_id: int) -> set[int]:
    """The runs already in a revision (whatever their status)."""
    import sqlalchemy as sa

    with archive.transaction() as conn:
        found = conn.execute(
            sa.select(revised.c.run_id).where(revised.c.revision_id == revision_id)
        ).scalars()
        return {int(i) for i in found}


def add_revised(
    archive: Archive, revision_id: int, outcomes: Iterable[dict[str, Any]], *, replace: bool
) -> int:
    """Write re-judged runs into a revision in one transaction; how many were written.

    Each outcome is ``{"run_id", "status", "reason", "verdict", "result_json", "planes"}``
    (``planes`` the plane rows without their keys).  A run already there is skipped, or with
    ``replace`` written over (its old rows deleted in the same transaction)."""
    import sqlalchemy as sa

    outcomes = list(outcomes)
    ids = [o["run_id"] for o in outcomes]
    if not ids:
        return 0
    with archive.transaction() as conn:
        mine = sa.and_(revised.c.revision_id == revision_id, revised.c.run_id.in_(ids))
        there = set(conn.execute(sa.select(revised.c.run_id).where(mine)).scalars())
        if replace and there:
            conn.execute(
                revised_planes.delete().where(
                    revised_planes.c.revision_id == revision_id, revised_planes.c.run_id.in_(there)
                )
            )
            conn.execute(revised.delete().where(mine))  # fmt: skip
            there = set()
        stamp = _now()
        run_rows, plane_rows = [], []
        for o in outcomes:
            if o["run_id"] in there:
                continue
            there.add(o["run_id"])
            run_rows.append({
                "revision_id": revision_id, "run_id": o["run_id"], "status": o["status"],
                "reason": o.get("reason"), "verdict": o.get("verdict"),
                "result_json": o.get("result_json"), "solved_at": stamp,
            })  # fmt: skip
            plane_rows += [
                {**p, "revision_id": revision_id, "run_id": o["run_id"]}
                for p in o.get("planes") or ()
            ]
        if run_rows:  # one statement per table (executemany): a task's writes cost little
            conn.execute(revised.insert(), run_rows)
        if plane_rows:
            conn.execute(revised_planes.insert(), plane_rows)
        written = len(run_rows)
    return written


def revision_list(archive: Archive) -> list[dict[str, Any]]:
    """Every revision with its counts per status, oldest first."""
    import sqlalchemy as sa

    with archive.transaction() as conn:
        revs = conn.execute(sa.select(revisions).order_by(revisions.c.id)).all()
        counts = conn.execute(
            sa.select(revised.c.revision_id, revised.c.status, sa.func.count()).group_by(
                revised.c.revision_id, revised.c.status
            )
        ).all()
    per: dict[int, dict[str, int]] = {}
    for rid, status, n in counts:
        per.setdefault(rid, {})[status] = int(n)
    return [
        {"name": r.name, "config_sha256": r.config_sha256, "config_source": r.config_source,
         "software": r.software, "created_at": r.created_at, "runs": per.get(r.id, {})}
        for r in revs
    ]  # fmt: skip
