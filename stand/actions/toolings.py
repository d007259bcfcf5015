"""A tooling measured (a setter's right, ``load``): its file kept, its index runs marked
as tooling runs in the archive, and the change journaled, in one transaction."""

from __future__ import annotations

from pathlib import Path

from stand.actions.door import Actor, door
from stand.archive.audit import Change, file_sha256
from stand.archive.store import mark_tooling_runs
from stand.solve.tooling import Tooling, save_tooling, tooling_file


def keep_tooling(url: str, actor: Actor, tooling: Tooling, where: Path,
                 run_digests: list[str], *, force: bool = False,
                 reason: str | None = None) -> tuple[Path, list[int], int]:  # fmt: skip
    """Keep ``tooling`` in the folder ``where`` (an existing one only with ``force``), mark
    the archived runs with ``run_digests`` as its index runs, and journal it: the file,
    the runs marked and the audit entry."""
    target = tooling_file(tooling.name, where)
    old = file_sha256(target)
    with door(url, actor, "load", "measure a tooling") as p:
        p.track(target)
        path = save_tooling(tooling, where, force=force)
        marked = mark_tooling_runs(p.conn, run_digests)
        entry = p.journal(Change("tooling", f"tooling {tooling.name} ({path.name})", old,
                                 file_sha256(path), reason,
                                 detail={"file": path.name, "runs": marked}))  # fmt: skip
    return path, marked, entry
