"""Reading the archive: runs by job, type, date and verdict, with their links and planes."""

from __future__ import annotations

import cmath
import datetime as dt
import json
import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from stand.archive.revisions import revision_id_in
from stand.archive.schema import planes, revised, revised_planes, runs
from stand.archive.store import Archive
from stand.archive.validate import as_stored, checked_planes, checked_runs, run_row, shown_url


@dataclass(frozen=True)
class Filters:
    """What ``stand history`` looks for; None matches anything.

    ``since`` and ``until`` are dates (``YYYY-MM-DD``, UTC), both included.  ``revision``:
    the runs as that revision (``stand reprocess``) re-judged them, its verdicts and planes
    in place of the archived ones; only the runs it re-solved (status ``ok``).
    """

    serial: str | None = None
    rotor_type: str | None = None
    order: str | None = None
    operator: str | None = None
    since: dt.date | None = None
    until: dt.date | None = None
    verdict: str | None = None
    limit: int | None = None
    stand: str | None = None
    revision: str | None = None
    kind: str | None = None
    """``production`` or ``tooling`` (a tooling's index runs); None: both."""


def _where(f: Filters) -> list[Any]:
    conds = []
    for column, value in (
        (runs.c.serial, f.serial),
        (runs.c.rotor_type, f.rotor_type),
        (runs.c.order_no, f.order),
        (runs.c.operator, f.operator),
        (runs.c.verdict if f.revision is None else revised.c.verdict, f.verdict),
        (runs.c.stand_id, f.stand),
        (runs.c.kind, f.kind),
    ):
        if value is not None:
            conds.append(column == value)
    if f.since is not None:
        conds.append(runs.c.start_time >= f.since.isoformat())
    if f.until is not None:
        conds.append(runs.c.start_time < (f.until + dt.timedelta(days=1)).isoformat())
    return conds


def plane_json(p: Any) -> dict[str, Any]:
    """A plane row (the archive's or a revision's) as the JSON shows it: g mm, degrees."""
    U = complex(p.U_re_kg_m, p.U_im_kg_m)
    return {
        "plane": p.plane,
        "unbalance_g_mm": round(abs(U) * 1e6, 3),
        "angle_deg": round(math.degrees(-cmath.phase(U)) % 360, 3),
        "uncertainty_g_mm": round(p.radius95_kg_m * 1e6, 3),
        "permissible_g_mm": None
        if p.permissible_kg_m is None
        else round(p.permissible_kg_m * 1e6, 3),
        "pass": p.passed,
        "leftover_g_mm": round(p.leftover_kg_m * 1e6, 3),
        "urr": None if p.urr is None else round(p.urr, 5),
    }


IN_CHUNK = 500
"""Runs asked for at a time in an ``IN (...)`` list (databases bound its length)."""


def _row_columns() -> list[Any]:
    """A run's columns but the result's JSON (the listings never need it)."""
    return [c for c in runs.c if c.name != "result_json"]


def select_runs(conn: Any, f: Filters) -> list[Any]:
    """The runs that match (every column but the result's JSON), oldest first; with a
    limit, the newest that many."""
    import sqlalchemy as sa

    cols: list[Any] = _row_columns()
    q = sa.select(*cols)
    if f.revision is not None:
        rid = revision_id_in(conn, f.revision)
        cols = [c for c in cols if c.name != "verdict"] + [revised.c.verdict.label("verdict")]
        q = sa.select(*cols).join(revised, sa.and_(
            revised.c.run_id == runs.c.id, revised.c.revision_id == rid,
            revised.c.status == "ok"))  # fmt: skip
    q = q.where(*_where(f))
    url = shown_url(conn)
    if f.limit is not None:  # the newest N, still listed oldest first
        newest = q.order_by(runs.c.start_time.desc(), runs.c.id.desc()).limit(f.limit)
        return checked_runs(conn.execute(newest).all(), url)[::-1]
    return checked_runs(conn.execute(q.order_by(runs.c.start_time, runs.c.id)).all(), url)


def runs_by_id(conn: Any, ids: list[int]) -> list[Any]:
    """The runs with these ids (every column but the result's JSON), each checked, in id
    order; an id not in the archive is left out."""
    import sqlalchemy as sa

    cols = _row_columns()
    url, out = shown_url(conn), []
    for part in chunks(sorted(set(ids))):
        q = sa.select(*cols).where(runs.c.id.in_(part)).order_by(runs.c.id)
        out += checked_runs(conn.execute(q).all(), url)
    return out


def chunks(ids: list[int]) -> Iterator[list[int]]:
    """``ids`` in pieces of at most :data:`IN_CHUNK`."""
    for k in range(0, len(ids), IN_CHUNK):
        yield ids[k : k + IN_CHUNK]


def plane_rows(conn: Any, ids: list[int], revision: str | None = None) -> Iterator[Any]:
    """The plane rows of these runs, plane 1 before plane 2 within each run (as the
    revision ``revision`` re-judged them, if one is named), each checked
    (:mod:`stand.archive.validate`)."""
    import sqlalchemy as sa

    table, where = planes, []
    if revision is not None:
        table = revised_planes
        where = [revised_planes.c.revision_id == revision_id_in(conn, revision)]
    raw = as_stored(table.c.passed)
    url = shown_url(conn)
    for part in chunks(ids):
        found = conn.execute(
            sa.select(table, raw).where(table.c.run_id.in_(part), *where).order_by(table.c.plane)
        )
        yield from checked_planes(found, url, str(table.name))


def history(url: str, f: Filters) -> list[dict[str, Any]]:
    """The runs that match, oldest first, each with its planes, the run it checks and the
    runs that check it."""
    import sqlalchemy as sa

    with Archive(url) as archive, archive.transaction() as conn:
        found = select_runs(conn, f)
        ids = [r.id for r in found]
        by_run: dict[int, list[dict[str, Any]]] = {i: [] for i in ids}
        checked_by: dict[int, list[int]] = {i: [] for i in ids}
        for p in plane_rows(conn, ids, f.revision):
            by_run[p.run_id].append(plane_json(p))
        for part in chunks(ids):
            for c in conn.execute(
                sa.select(runs.c.id, runs.c.checks_run_id).where(runs.c.checks_run_id.in_(part))
            ):
                checked_by[c.checks_run_id].append(c.id)
    return [
        {
            "id": r.id,
            "start_time": r.start_time,
            "serial": r.serial,
            "order": r.order_no,
            "operator": r.operator,
            "note": r.note,
            "rotor_type": r.rotor_type,
            "stand": r.stand_id,
            "rpm": r.rpm,
            "verdict": r.verdict,
            "checks_run": r.checks_run_id,
            "checked_by": checked_by[r.id],
            "planes": by_run[r.id],
            "run_file": r.run_file,
            "file_sha256": r.file_sha256,
            "kind": r.kind,
            "job": r.job_id,
        }
        for r in found
    ]


def serials_by_digest(url: str, file_sha256s: list[str]) -> dict[str, str]:
    """The serial of each archived run with one of these file digests (runs without a
    serial left out)."""
    import sqlalchemy as sa

    with Archive(url) as archive, archive.transaction() as conn:
        found = conn.execute(sa.select(runs.c.file_sha256, runs.c.serial)
                             .where(runs.c.file_sha256.in_(file_sha256s))).all()  # fmt: skip
    return {str(d): str(s) for d, s in found if s}


def serials_starting(url: str, prefix: str) -> list[str]:
    """Every archived serial that starts with ``prefix`` (a serial rule's day)."""
    import sqlalchemy as sa

    like = prefix.replace("\\", "\\\\").replace("%", "\\%").replace("_", "\\_") + "%"
    with Archive(url) as archive, archive.transaction() as conn:
        found = conn.execute(sa.select(runs.c.serial).distinct()
                             .where(runs.c.serial.like(like, escape="\\"))).scalars()  # fmt: skip
        return [str(s) for s in found if s]


def run_digest(url: str, run_id: int) -> str | None:
    """The SHA-256 the archive keeps of run ``run_id``'s file (None: no such run)."""
    import sqlalchemy as sa

    with Archive(url) as archive, archive.transaction() as conn:
        found = conn.execute(sa.select(runs.c.file_sha256).where(runs.c.id == run_id)).first()
    return None if found is None else str(found.file_sha256)


def run_file(url: str, run_id: int) -> str | None:
    """The run file archived as ``run_id`` (None if there is no such run)."""
    import sqlalchemy as sa

    with Archive(url) as archive, archive.transaction() as conn:
        found = conn.execute(sa.select(runs.c.run_file).where(runs.c.id == run_id)).first()
    return None if found is None else str(found.run_file)


def _run_dict(r: Any, planes_: list[dict[str, Any]]) -> dict[str, Any]:
    """One archived run's row as :func:`history` gives it (without its links' lists)."""
    return {
        "id": r.id, "start_time": r.start_time, "serial": r.serial, "order": r.order_no,
        "operator": r.operator, "rotor_type": r.rotor_type, "stand": r.stand_id, "rpm": r.rpm,
        "verdict": r.verdict, "checks_run": r.checks_run_id, "planes": planes_,
        "run_file": r.run_file, "file_sha256": r.file_sha256, "kind": r.kind, "job": r.job_id,
    }  # fmt: skip


def latest(
    archive: Archive, stand: str | None = None, run_id: int | None = None
) -> dict[str, Any] | None:
    """The latest production run in an open archive (of one stand, or of any), or the
    production run ``run_id`` (of that stand), as :func:`history` gives it, with
    ``initial``, the planes of the run it checks (its own when it checks none), and
    ``result``, its whole JSON form; None when there is none.  A tooling's index runs are
    no results (kind ``tooling``)."""

    import sqlalchemy as sa

    with archive.transaction() as conn:
        q = sa.select(runs).where(runs.c.kind == "production")
        if stand is not None:
            q = q.where(runs.c.stand_id == stand)
        if run_id is not None:
            q = q.where(runs.c.id == run_id)
        row = conn.execute(q.order_by(runs.c.id.desc()).limit(1)).first()
        if row is None:
            return None
        run_row(row, shown_url(conn))
        ids = [row.id] + ([row.checks_run_id] if row.checks_run_id is not None else [])
        found: dict[int, list[dict[str, Any]]] = {i: [] for i in ids}
        for p in plane_rows(conn, ids):
            found[p.run_id].append(plane_json(p))
    run = _run_dict(row, found[row.id])
    run["initial"] = found[ids[-1]] if len(found[ids[-1]]) == len(found[row.id]) else found[row.id]
    run["result"] = json.loads(row.result_json)  # checked as strict JSON above
    return run


def newest_ids(archive: Archive, stand: str | None = None, limit: int | None = None) -> list[int]:
    """The ids of an open archive's production runs (of one stand, or of any), newest
    first; at most ``limit`` of them."""
    import sqlalchemy as sa

    with archive.transaction() as conn:
        q = sa.select(runs.c.id).where(runs.c.kind == "production")
        if stand is not None:
            q = q.where(runs.c.stand_id == stand)
        q = q.order_by(runs.c.id.desc())
        if limit:
            q = q.limit(limit)
        return [int(i) for i in conn.execute(q).scalars()]


def latest_id(archive: Archive, stand: str | None = None) -> int | None:
    """The id of the latest production run in an open archive (a cheap poll: anything
    new?)."""
    import sqlalchemy as sa

    with archive.transaction() as conn:
        q = sa.select(sa.func.max(runs.c.id)).where(runs.c.kind == "production")
        if stand is not None:
            q = q.where(runs.c.stand_id == stand)
        found = conn.execute(q).scalar()
    return None if found is None else int(found)
