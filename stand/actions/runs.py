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
    prev, prev_digest, solved = None, None, None
    if result.check is not None:  # the run it checks: solved here (slow) if not archived
        prev = result.check.previous_run
        prev_digest = file_digest(prev)
        with Archive(url) as archive, archive.transaction() as conn:
            if run_id_in(conn, prev_digest) is None:
                solved = solve_recording(prev, config)
    with door(url, actor, None, "archive a run") as p:
        checks = None
        if prev is not None and prev_digest is not None:
            checks = run_id_in(p.conn, prev_digest)
            if checks is None:  # not archived (or gone meanwhile): its own result, always
                solved = solved or solve_recording(prev, config)
                checks = _insert(p, solved, prev_digest, None)
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
