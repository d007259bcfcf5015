"""A job order the line's MES sends (OPC 40001-3): kept and journaled with who sent it
(the OPC UA user) in one transaction.  Who may send jobs is the OPC UA server's check
(:mod:`stand.plant.opcua.security`), made before the call; the entry attributes it."""

from __future__ import annotations

import json
from typing import Any

from stand.actions.door import Actor, door
from stand.archive.audit import Change, sha256_of
from stand.archive.jobs import insert_job


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
        p.journal(Change("job", f"job order {fields['job_id']} for {stand}", None,
                         sha256_of(text), None,
                         detail={"job_order_id": fields["job_id"], "stand": stand,
                                 "rotor_type": fields["rotor_type"],
                                 "serial": fields["serial"], "start": start}))  # fmt: skip
    return None
