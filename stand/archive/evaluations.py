"""The stand's own evaluations in the archive: ISO 21940-21's machine tests and the
capability study, each with its date, verdict and (machine tests) the next one's due date;
read back checked, like every row (:mod:`stand.archive.validate`)."""

from __future__ import annotations

import datetime as dt
from typing import Any

from stand.archive.schema import evaluations
from stand.archive.store import Archive
from stand.archive.validate import evaluation_row, shown_url
from stand.health.due import due_words
from stand.solve.result import json_text


def add_evaluation(
    conn: Any, kind: str, stand_id: str | None, verdict: str, result: dict[str, Any], *,
    simulated: bool, software: str, due: dt.date | None = None,
    performed_at: dt.datetime | None = None,
) -> int:  # fmt: skip
    """Archive one evaluation in the open transaction ``conn``; its id
    (:func:`stand.actions.evaluations.archive_evaluation` journals it too)."""
    import sqlalchemy as sa

    when = (performed_at or dt.datetime.now(dt.UTC)).astimezone(dt.UTC)
    row = {
        "stand_id": stand_id, "kind": kind, "performed_at": when.isoformat(),
        "verdict": verdict, "due": None if due is None else due.isoformat(),
        "simulated": simulated, "software": software, "result_json": json_text(result),
    }  # fmt: skip
    return int(conn.execute(sa.insert(evaluations).values(**row)).inserted_primary_key[0])


def latest_evaluations(url: str, stand: str | None = None) -> list[dict[str, Any]]:
    """The latest evaluation of each kind and stand (of ``stand`` only, when given)."""
    last: dict[tuple[Any, str], dict[str, Any]] = {}
    for e in evaluations_of(url, None, stand):  # oldest first: the latest wins
        last[(e["stand"], e["kind"])] = e
    return list(last.values())


def evaluations_of(url: str, kind: str | None, stand: str | None = None) -> list[dict[str, Any]]:
    """Every evaluation of ``kind`` (any kind: None; of ``stand`` only, when given), checked,
    oldest first."""
    import sqlalchemy as sa

    with Archive(url) as archive, archive.transaction() as conn:
        q = sa.select(evaluations)
        if kind is not None:
            q = q.where(evaluations.c.kind == kind)
        if stand is not None:
            q = q.where(evaluations.c.stand_id == stand)
        rows = conn.execute(q.order_by(evaluations.c.performed_at, evaluations.c.id)).all()
        where = shown_url(conn)
    return [evaluation_row(row, where) for row in rows]


def evaluation_ids(archive: Archive, stand: str | None = None) -> list[int]:
    """The ids of an open archive's machine evaluations (of one stand), newest first (a
    cheap poll: anything new?)."""
    import sqlalchemy as sa

    with archive.transaction() as conn:
        q = sa.select(evaluations.c.id).where(evaluations.c.kind == "machine")
        if stand is not None:
            q = q.where(evaluations.c.stand_id == stand)
        order = (evaluations.c.performed_at.desc(), evaluations.c.id.desc())
        return [int(i) for i in conn.execute(q.order_by(*order)).scalars()]


def evaluation_by_id(archive: Archive, eval_id: int, stand: str | None = None
                     ) -> dict[str, Any] | None:  # fmt: skip
    """One machine evaluation of an open archive (of ``stand``), checked; None if none."""
    import sqlalchemy as sa

    with archive.transaction() as conn:
        q = sa.select(evaluations).where(evaluations.c.id == eval_id,
                                         evaluations.c.kind == "machine")  # fmt: skip
        if stand is not None:
            q = q.where(evaluations.c.stand_id == stand)
        row = conn.execute(q).first()
        return None if row is None else evaluation_row(row, shown_url(conn))


def evaluations_due(url: str, stand: str | None) -> list[dict[str, Any]]:
    """Each stand's latest machine evaluation and when the next is due (a line each)."""
    today = dt.datetime.now(dt.UTC).date()
    got = [e for e in latest_evaluations(url, stand) if e["kind"] == "machine"]
    if not got:
        state, words = due_words(None, today)
        return [{"stand": stand, "state": state, "line": f"machine evaluation: {words}"}]
    out = []
    for e in got:
        state, words = due_words(dt.date.fromisoformat(e["due"]) if e["due"] else None, today)
        sim = " (simulated runs)" if e["simulated"] else ""
        out.append({
            "stand": e["stand"], "evaluation": e["id"], "performed_at": e["performed_at"],
            "verdict": e["verdict"], "due": e["due"], "state": state,
            "line": f"stand {e['stand'] or '?'}: machine evaluation (ISO 21940-21) "
                    f"{e['verdict'].upper()} on {e['performed_at'][:10]}{sim}; {words}",
        })  # fmt: skip
    return out
