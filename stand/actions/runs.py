"""A run archived: its result, its planes and its journal entry (the verdict and the file's
SHA-256, which ``stand audit verify`` holds the ``runs`` table against) in one
transaction.  Archiving a measurement takes no right of its own: it is attributed to
whoever measured (the account at the station, ``--as`` or the operating system's user)."""

from __future__ import annotations

from pathlib import Path

from stand.actions.door import Actor, Passage, door
from stand.archive import Archive, file_digest, insert_result, run_id_in
from stand.archive.audit import Change
from stand.archive.schema import runs
from stand.solve import Result, solve_recording


def archive_run(result: Result, url: str, actor: Actor, *, config: str | None = None) -> int:
    """Archive one run's result (and the run it checks, if not archived yet); its id.  A
    run archived already (the same file digest) keeps its id and its entry."""
    run_file = result.provenance.run_file
    if not run_file:
        raise ValueError("only a recorded run is archived")
    digest = file_digest(run_file)
    before: tuple[Result, str] | None = None
    if result.check is not None:
        prev = result.check.previous_run
        prev_digest = file_digest(prev)
        with Archive(url) as archive, archive.transaction() as conn:
            known = run_id_in(conn, prev_digest) is not None
        before = (solve_recording(prev, config) if not known else result, prev_digest)
    with door(url, actor, None, "archive a run") as p:
        checks = None
        if before is not None:
            checks = run_id_in(p.conn, before[1])
            if checks is None:
                checks = _insert(p, before[0], before[1], None)
        return _insert(p, result, digest, checks)


def _insert(p: Passage, result: Result, digest: str, checks: int | None) -> int:
    import sqlalchemy as sa

    run_id, new = insert_result(p.conn, result, digest, checks)
    if not new:
        p.unchanged = True
        return run_id
    said = p.conn.execute(sa.select(runs.c.verdict).where(runs.c.id == run_id)).scalar_one()
    name = Path(result.provenance.run_file or "").name
    p.journal(Change("run", f"run {run_id} ({name})", None, digest, None,
                     detail={"id": run_id, "verdict": said, "file_sha256": digest}))  # fmt: skip
    return run_id


def import_runs(paths: list[str], url: str, actor: Actor,
                config: str | None = None) -> list[tuple[str, int]]:  # fmt: skip
    """Archive runs recorded before (solved with their stored config, or ``config``):
    ``(path, id)`` each; a run already archived keeps its id."""
    done = []
    for path in paths:
        digest = file_digest(path)
        with Archive(url) as archive, archive.transaction() as conn:
            found = run_id_in(conn, digest)
        if found is None:
            found = archive_run(solve_recording(path, config), url, actor, config=config)
        done.append((path, found))
    return done
