"""The audit trail: one append-only journal in the archive of every change to what the
stand measures with (a rotor type's configuration, a calibration, an influence matrix, a
tooling, an account, an evaluation): who, when (UTC and the local zone), what, the old and
new SHA-256 of the thing changed, and the reason typed.

Hash-chained: each entry's ``entry_sha256`` is the SHA-256 of its own fields and the
previous entry's ``entry_sha256`` (the first's previous is 64 zeros), so an entry edited,
deleted or moved breaks the chain at that row, and :func:`verify_journal` names it.  The
newest entries deleted leave a shorter chain that is whole: :func:`verify_journal` gives
the head (the last entry's id and hash) for a plant to keep apart, and checks the chain
against a head kept before (``expect_head``).
"""

from __future__ import annotations

import datetime as dt
import getpass
import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stand.archive.schema import audit
from stand.archive.store import Archive
from stand.archive.validate import audit_row, shown_url
from stand.errors import ArchiveError

GENESIS = "0" * 64
"""The previous hash of the first entry."""
ACTIONS = ("config", "calibration", "matrix", "tooling", "account", "evaluation", "release")
"""What an entry records a change of (``release``: a certificate released)."""
FIELDS = ("id", "at_utc", "zone", "who", "action", "subject", "old_sha256", "new_sha256",
          "reason", "previous_sha256")  # fmt: skip
"""The fields an entry's hash covers, in this order."""


@dataclass(frozen=True)
class Change:
    """One change to journal.

    Parameters
    ----------
    action
        One of :data:`ACTIONS`.
    subject
        What changed, in words a reader finds it by: a file's name, an account, an
        evaluation's id.
    old_sha256, new_sha256
        The SHA-256 of the thing before and after (None: it did not exist / no longer).
    reason
        The reason typed (None: none given).
    who
        The account or the operating system's user that made it (default: this OS user).
    """

    action: str
    subject: str
    old_sha256: str | None
    new_sha256: str | None
    reason: str | None = None
    who: str | None = None


def sha256_of(data: bytes | str) -> str:
    """The SHA-256 of a text (UTF-8) or bytes, as hex."""
    return hashlib.sha256(data.encode() if isinstance(data, str) else data).hexdigest()


def entry_hash(entry: dict[str, Any]) -> str:
    """An entry's hash: SHA-256 of its :data:`FIELDS` as one line of JSON."""
    return sha256_of(json.dumps([entry[f] for f in FIELDS], ensure_ascii=True,
                                separators=(",", ":")))  # fmt: skip


def file_sha256(path: str | Path) -> str | None:
    """The SHA-256 of a file as it is now (None: there is none, or it is ``-``, stdout)."""
    if str(path) == "-" or not Path(path).is_file():
        return None
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def record(url: str, change: Change) -> int:
    """:func:`journal`, for a change already made: ArchiveError saying that it was made
    but not journaled, when the journal cannot be written."""
    try:
        return journal(url, change)
    except ArchiveError as exc:
        raise ArchiveError(
            f"{change.subject}: changed, but the audit trail could not "
            f"record it ({str(exc).split(': ', 1)[-1]}): record it by hand",
            url=exc.url,
        ) from exc


def config_seen(url: str, path: str | Path, user: str | None = None) -> int | None:
    """A rotor type's configuration about to be measured with: one ``config`` entry when
    its SHA-256 is not the one the journal last recorded for that file (edited on disk
    since, or first used); the entry's id, or None when nothing changed.  Who edited it
    is not known here: the entry says who found it."""
    import sqlalchemy as sa

    name = Path(path).name
    new = file_sha256(path)
    with Archive(url) as archive, archive.transaction() as conn:
        last = conn.execute(sa.select(audit.c.new_sha256).where(
            audit.c.action.in_(("config", "calibration")), audit.c.subject == name)
            .order_by(audit.c.id.desc()).limit(1)).scalar()  # fmt: skip
    if new is None or last == new:
        return None
    why = "first used" if last is None else "changed on disk since the last entry"
    return record(url, Change("config", name, last, new,
                              f"{why}; found by {user or os_user()} before a run",
                              who=user or os_user()))  # fmt: skip


def os_user() -> str:
    """Who runs this process, as the journal names a CLI user (``os:name``)."""
    try:
        return f"os:{getpass.getuser()}"
    except (KeyError, OSError):
        return "os:unknown"


def _zone() -> str:
    """The local zone now: its name and UTC offset (``CET +01:00``)."""
    now = dt.datetime.now().astimezone()
    offset = now.strftime("%z")
    return f"{now.tzname()} {offset[:3]}:{offset[3:]}"


def journal(url: str, change: Change) -> int:
    """Append one entry for ``change`` to the archive's journal; its id."""
    import sqlalchemy as sa

    if change.action not in ACTIONS:
        raise ValueError(f"no audit action {change.action!r}")
    with Archive(url) as archive, archive.transaction() as conn:
        if conn.dialect.name == "postgresql":  # one writer at a time: the chain is a line
            conn.execute(sa.text("LOCK TABLE audit IN EXCLUSIVE MODE"))
        last = conn.execute(sa.select(audit.c.id, audit.c.entry_sha256)
                            .order_by(audit.c.id.desc()).limit(1)).first()  # fmt: skip
        number = 1 if last is None else int(last.id) + 1
        entry: dict[str, Any] = {
            "id": number,
            "at_utc": dt.datetime.now(dt.UTC).isoformat(timespec="milliseconds"),
            "zone": _zone(), "who": (change.who or os_user())[:64], "action": change.action,
            "subject": change.subject[:400], "old_sha256": change.old_sha256,
            "new_sha256": change.new_sha256,
            "reason": None if change.reason is None else change.reason[:1000],
            "previous_sha256": GENESIS if last is None else last.entry_sha256,
        }  # fmt: skip
        conn.execute(sa.insert(audit).values(**entry, entry_sha256=entry_hash(entry)))
        return number


def entries(url: str, *, who: str | None = None, action: str | None = None,
            since: dt.date | None = None, until: dt.date | None = None
            ) -> list[dict[str, Any]]:  # fmt: skip
    """The journal's entries (filtered), oldest first, as stored."""
    import sqlalchemy as sa

    q = sa.select(audit).order_by(audit.c.id)
    if who is not None:
        q = q.where(audit.c.who == who)
    if action is not None:
        q = q.where(audit.c.action == action)
    if since is not None:
        q = q.where(audit.c.at_utc >= since.isoformat())
    if until is not None:
        q = q.where(audit.c.at_utc < (until + dt.timedelta(days=1)).isoformat())
    with Archive(url) as archive, archive.transaction() as conn:
        where = shown_url(conn)
        return [audit_row(r, where) for r in conn.execute(q)]


@dataclass(frozen=True)
class Verdict:
    """What :func:`verify_journal` found."""

    entries: int
    problem: str | None
    """None: the chain is whole; else the first row that breaks it, and how."""
    head: str
    """``<id>:<entry_sha256>`` of the last entry that verified (``0:`` + zeros: none)."""


def verify_journal(url: str, expect_head: str | None = None) -> Verdict:
    """Walk the chain from the first entry: each entry's id one more than the last's, its
    previous hash the last's hash, its own hash its fields' (an edited, deleted or moved
    row breaks one of them, and is named); with ``expect_head`` (an ``id:hash`` kept
    before), that entry must still be in the chain as it was."""
    import sqlalchemy as sa

    with Archive(url) as archive, archive.transaction() as conn:
        rows = conn.execute(sa.select(audit).order_by(audit.c.id)).all()
        where = shown_url(conn)
    previous, expected_id, head = GENESIS, 1, f"0:{GENESIS}"
    heads = {head}
    for row in rows:
        entry = dict(row._mapping)
        name = f"{where}: audit row {entry['id']}"
        if entry["id"] != expected_id:
            why = "deleted or moved" if entry["id"] > expected_id else "duplicated or moved"
            return Verdict(len(rows), f"{name}: expected row {expected_id} ({why})", head)
        if entry["previous_sha256"] != previous:
            return Verdict(
                len(rows),
                f"{name}: does not follow row {expected_id - 1} "
                "(a row before it was changed, deleted or reordered)",
                head,
            )
        if entry["entry_sha256"] != entry_hash(entry):
            return Verdict(
                len(rows),
                f"{name}: its fields were changed after it was written (its hash does not match)",
                head,
            )
        previous, expected_id = entry["entry_sha256"], expected_id + 1
        head = f"{entry['id']}:{previous}"
        heads.add(head)
    if expect_head is not None and expect_head not in heads:
        return Verdict(
            len(rows),
            f"{where}: the head kept before ({expect_head[:20]}...) is "
            "not in the chain: entries after it were deleted or rewritten",
            head,
        )
    return Verdict(len(rows), None, head)
