"""The stand's own evaluations (ISO 21940-21's machine tests, the capability study): an
engineer's right (``evaluate``), archived and journaled in one transaction."""

from __future__ import annotations

import datetime as dt
from typing import Any

from stand.actions.door import Actor, door
from stand.archive.audit import Change, sha256_of
from stand.archive.evaluations import add_evaluation
from stand.solve.result import json_text


def archive_evaluation(url: str, actor: Actor, kind: str, stand_id: str | None,
                       result: dict[str, Any], *, simulated: bool, software: str,
                       due: dt.date | None = None, performed_at: dt.datetime | None = None,
                       reason: str | None = None) -> tuple[int, str, int]:  # fmt: skip
    """Archive an evaluation (``result``: its JSON form, with its ``verdict``) and journal
    it: its id, the archive as messages show it, and the audit entry."""
    with door(url, actor, "evaluate", "archive an evaluation of the stand") as p:
        eid = add_evaluation(p.conn, kind, stand_id, result["verdict"], result,
                             simulated=simulated, software=software, due=due,
                             performed_at=performed_at)  # fmt: skip
        entry = p.journal(Change("evaluation", f"{kind} evaluation E{eid} ({result['verdict']})",
                                 None, sha256_of(json_text(result)), reason,
                                 detail={"id": eid, "verdict": result["verdict"]}))  # fmt: skip
        shown = str(p.conn.engine.url.render_as_string(hide_password=True))
    return eid, shown, entry
