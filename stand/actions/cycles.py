"""The stand's cycle journaled: a cycle its supervision aborted (guard opened, emergency
stop, a drive fault, over-speed) is entered in the audit trail with its reason and the
digest of the run it kept, under the right to measure (the run's own right), in one
transaction."""

from __future__ import annotations

from pathlib import Path

from stand.actions.door import Actor, door
from stand.archive.audit import Change, file_sha256


def journal_abort(url: str, actor: Actor, reason: str, run_file: str) -> int:
    """Journal an aborted cycle; the audit entry.  ``run_file``: the run kept ("" or a
    path that does not exist: none was recorded)."""
    kept = run_file and Path(run_file).is_file()
    digest = file_sha256(run_file) if kept else None
    name = Path(run_file).name if kept else "nothing recorded"
    with door(url, actor, "measure", "abort the stand's cycle") as p:
        return p.journal(Change("cycle", f"cycle aborted ({name})", None, digest, reason,
                                detail={"aborted": reason, "file_sha256": digest}))  # fmt: skip
