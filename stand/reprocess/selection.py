"""Which archived runs to re-judge, and where their files are now.

A selection is the archive's own filters (stand, rotor type, dates, serial) and two of its
own: the first run id (``--from-run``) and the kind (a production run, a check run, or
all).  Each selected run becomes an :class:`Item`, the little a worker needs (its id, its
file, the file's digest); what the archive said of it (verdict and planes) stays with the
client as :class:`Archived`.
"""

from __future__ import annotations

import datetime as dt
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stand.archive import Archive
from stand.archive.query import Filters, plane_rows, select_runs
from stand.errors import UsageError

KINDS = ("production", "check", "all")
"""A production run checks no other run; a check run checks the run before its correction."""


@dataclass(frozen=True)
class Selection:
    """The runs ``stand reprocess`` re-judges; None matches anything."""

    stand: str | None = None
    rotor_type: str | None = None
    since: dt.date | None = None
    until: dt.date | None = None
    serial: str | None = None
    from_run: int | None = None
    kind: str = "all"


@dataclass(frozen=True)
class Item:
    """One run for a worker: the archive's id, its file (where it is now) and its digest."""

    run_id: int
    run_file: str
    file_sha256: str


@dataclass(frozen=True)
class Archived:
    """What the archive says of a run: its job, verdict and planes (plane rows)."""

    run_id: int
    run_file: str
    file_sha256: str
    serial: str | None
    start_time: str
    kind: str
    verdict: str
    planes: tuple[Any, ...]


def select(archive: Archive, sel: Selection) -> list[Archived]:
    """The archived runs of a selection, oldest first, with their planes."""
    if sel.kind not in KINDS:
        raise UsageError(f"--kind {sel.kind}: one of {', '.join(KINDS)}")
    f = Filters(serial=sel.serial, rotor_type=sel.rotor_type, since=sel.since,
                until=sel.until, stand=sel.stand,
                kind=None if sel.kind == "all" else "production")  # fmt: skip
    with archive.transaction() as conn:
        rows = [
            r for r in select_runs(conn, f)
            if (sel.from_run is None or r.id >= sel.from_run)
            and (sel.kind == "all" or (r.checks_run_id is None) == (sel.kind == "production"))
        ]  # fmt: skip
        planes: dict[int, list[Any]] = {r.id: [] for r in rows}
        for p in plane_rows(conn, list(planes)):
            planes[p.run_id].append(p)
    return [
        Archived(
            run_id=r.id, run_file=r.run_file, file_sha256=r.file_sha256, serial=r.serial,
            start_time=r.start_time,
            kind="production" if r.checks_run_id is None else "check", verdict=r.verdict,
            planes=tuple(planes[r.id]),
        )
        for r in rows
    ]  # fmt: skip


def items(found: list[Archived], runs_root: str | None) -> list[Item]:
    """The workers' view of the runs: each file where it is now (:func:`relocate`)."""
    common = _common_folder([a.run_file for a in found]) if runs_root else None
    return [Item(a.run_id, relocate(a.run_file, runs_root, common), a.file_sha256) for a in found]


def relocate(archived: str, runs_root: str | None, common: str | None) -> str:
    """Where an archived run file is looked for: as archived; with ``--runs-root DIR``, its
    path below the selection's common folder under DIR, or, if that is not a file, its
    name directly in DIR (a folder moved whole, or one share holding every stand's runs)."""
    if not runs_root:
        return archived
    root = Path(runs_root)
    if common:
        below = root / os.path.relpath(archived, common)
        if below.is_file():
            return str(below)
    return str(root / Path(archived).name)


def _common_folder(paths: list[str]) -> str | None:
    try:
        return os.path.commonpath([str(Path(p).parent) for p in paths]) if paths else None
    except ValueError:  # relative and absolute, or other drives
        return None
