"""The audit trail: one append-only journal in the archive of every change to what the
stand measures with (a rotor type's configuration, a calibration, an influence matrix, a
tooling, an account, an evaluation, a run archived, a job order) and of the security
events (log-ins, log-outs, failed log-ins, refused actions): who, from where (the CLI, the
station, the OPC UA server), when (UTC and the local zone), what, the old and new SHA-256
of the thing changed, the state it left (no secrets), and the reason typed.

Hash-chained and signed: each entry's ``entry_sha256`` is the SHA-256 of its own fields
and the previous entry's ``entry_sha256`` (the first's previous is 64 zeros), and its
``signature`` is the stand's Ed25519 signature of that hash, by a key that is not in the
archive (:mod:`stand.archive.keys`).  An entry edited, deleted or moved breaks the chain at
that row; a chain recomputed without the key breaks at the first rewritten row's
signature; entries deleted from the end are found against the anchor kept beside the key
(or a head kept elsewhere): :func:`verify_journal` names the row.

Entries are written only by :func:`append`, inside the transaction that makes the change
(:mod:`stand.actions` opens it); the front ends never write the journal themselves.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from stand.archive.keys import (
    StandKey,
    read_anchor,
    stand_key,
    trusted_keys,
    verify_signature,
    write_anchor,
)
from stand.archive.schema import audit
from stand.archive.store import Archive
from stand.archive.validate import audit_row, shown_url
from stand.errors import UsageError

GENESIS = "0" * 64
"""The previous hash of the first entry."""
ACTIONS = ("config", "calibration", "matrix", "tooling", "account", "evaluation", "release",
           "run", "job", "trust", "cycle")  # fmt: skip
"""What an entry records a change of (``release``: a certificate released; ``cycle``: the
stand's cycle aborted by its supervision, the run it kept)."""
EVENTS = ("login", "logout", "login_failed", "refused", "session_end")
"""The security events an entry records (nothing changed: someone came, went, or was
refused)."""
SOURCES = ("cli", "station", "opcua", "mqtt")
"""Where a change or an event came from."""
FIELDS = ("id", "at_utc", "zone", "who", "action", "subject", "old_sha256", "new_sha256",
          "reason", "previous_sha256")  # fmt: skip
"""The fields an unsigned entry's hash covers, in this order (entries written before the
journal was signed)."""
SIGNED_FIELDS = (*FIELDS, "source", "key_id", "detail")
"""The fields a signed entry's hash covers, in this order."""
MAX_REASON = 1000
"""The longest reason kept [characters]: a longer one is refused, never cut."""


@dataclass(frozen=True)
class Change:
    """One change (or security event) to journal.

    Parameters
    ----------
    action
        One of :data:`ACTIONS` or :data:`EVENTS`.
    subject
        What changed, in words a reader finds it by: a file's name, an account, a run.
    old_sha256, new_sha256
        The SHA-256 of the thing before and after (None: it did not exist / no longer).
    reason
        The reason typed (None: none given).
    detail
        The state the change left, as a JSON object without secrets (an account's role
        and state, a run's verdict): what ``stand audit verify`` holds the tables against.
    """

    action: str
    subject: str
    old_sha256: str | None
    new_sha256: str | None
    reason: str | None = None
    detail: dict[str, Any] | None = field(default=None, compare=False)


def sha256_of(data: bytes | str) -> str:
    """The SHA-256 of a text (UTF-8) or bytes, as hex."""
    return hashlib.sha256(data.encode() if isinstance(data, str) else data).hexdigest()


def entry_hash(entry: dict[str, Any]) -> str:
    """An entry's hash: SHA-256 of its fields (:data:`SIGNED_FIELDS` when it names a key,
    else :data:`FIELDS`) as one line of JSON."""
    fields = SIGNED_FIELDS if entry.get("key_id") else FIELDS
    return sha256_of(json.dumps([entry[f] for f in fields], ensure_ascii=True,
                                separators=(",", ":")))  # fmt: skip


def file_sha256(path: str | Path) -> str | None:
    """The SHA-256 of a file as it is now (None: there is none, or it is ``-``, stdout)."""
    if str(path) == "-" or not Path(path).is_file():
        return None
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def archive_id(conn: Any) -> str:
    """What names an archive for its anchor: an SQLite file's resolved path, else the URL
    without its password."""
    return engine_archive_id(conn.engine)


def engine_archive_id(engine: Any) -> str:
    """:func:`archive_id` of an SQLAlchemy engine."""
    url = engine.url
    if url.get_backend_name() == "sqlite" and url.database not in (None, "", ":memory:"):
        return f"sqlite:{Path(url.database).resolve()}"
    return str(url.render_as_string(hide_password=True))


def _zone() -> str:
    """The local zone now: its name and UTC offset (``CET +01:00``)."""
    now = dt.datetime.now().astimezone()
    offset = now.strftime("%z")
    return f"{now.tzname()} {offset[:3]}:{offset[3:]}"


def detail_text(detail: dict[str, Any] | None) -> str | None:
    """A change's detail as stored: compact JSON with sorted keys."""
    if detail is None:
        return None
    return json.dumps(detail, sort_keys=True, separators=(",", ":"), ensure_ascii=True)


def checked_reason(reason: str | None) -> str | None:
    """``reason`` as typed, refused (UsageError) when it is longer than the journal keeps:
    a reason is never cut."""
    if reason is not None and len(reason) > MAX_REASON:
        raise UsageError(f"a reason of {len(reason)} characters: at most {MAX_REASON} are "
                         "kept, and a reason is never cut: shorten it")  # fmt: skip
    return reason


def append(conn: Any, change: Change, *, who: str, source: str, key: StandKey
           ) -> dict[str, Any]:  # fmt: skip
    """Append one signed entry for ``change`` inside the open transaction ``conn`` (the
    one that makes the change); the entry as stored.  Keep its head in the anchor once
    the transaction is committed (:func:`anchor`)."""
    import sqlalchemy as sa

    if change.action not in ACTIONS + EVENTS:
        raise ValueError(f"no audit action {change.action!r}")
    if source not in SOURCES:
        raise ValueError(f"no audit source {source!r}")
    checked_reason(change.reason)
    if conn.dialect.name == "postgresql":  # one writer at a time: the chain is a line
        conn.execute(sa.text("LOCK TABLE audit IN EXCLUSIVE MODE"))
    last = conn.execute(sa.select(audit.c.id, audit.c.entry_sha256)
                        .order_by(audit.c.id.desc()).limit(1)).first()  # fmt: skip
    entry: dict[str, Any] = {
        "id": 1 if last is None else int(last.id) + 1,
        "at_utc": dt.datetime.now(dt.UTC).isoformat(timespec="milliseconds"),
        "zone": _zone(), "who": who[:64], "action": change.action,
        "subject": change.subject[:400], "old_sha256": change.old_sha256,
        "new_sha256": change.new_sha256, "reason": change.reason,
        "previous_sha256": GENESIS if last is None else last.entry_sha256,
        "source": source, "key_id": key.id, "detail": detail_text(change.detail),
    }  # fmt: skip
    entry["entry_sha256"] = entry_hash(entry)
    entry["signature"] = key.sign(entry["entry_sha256"].encode("ascii"))
    conn.execute(sa.insert(audit).values(**entry))
    return entry


def anchor(conn_or_id: Any, entry: dict[str, Any]) -> None:
    """Keep ``entry``'s head as the archive's anchor beside the stand's key (after its
    transaction was committed)."""
    aid = conn_or_id if isinstance(conn_or_id, str) else archive_id(conn_or_id)
    write_anchor(aid, f"{entry['id']}:{entry['entry_sha256']}")


def anchored_head(url: str) -> str | None:
    """The head the anchor beside the stand's key keeps for the archive ``url`` (None:
    none kept)."""
    with Archive(url) as archive, archive.transaction() as conn:
        aid = archive_id(conn)
    kept = read_anchor(aid)
    return None if kept is None else str(kept["head"])


def journal(url: str, change: Change, *, who: str, source: str) -> int:
    """One entry for ``change`` in a transaction of its own (a security event, where
    nothing else changes); its id.  Changes are journaled in their own transaction by
    :mod:`stand.actions`."""
    key = stand_key()
    with Archive(url) as archive:
        with archive.transaction() as conn:
            entry = append(conn, change, who=who, source=source, key=key)
            aid = archive_id(conn)
        anchor(aid, entry)
    return int(entry["id"])


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
    unsigned: int = 0
    """Entries written before the journal was signed (only ever the first ones)."""
    anchored: str | None = None
    """The head the anchor beside the stand's key keeps (None: none kept)."""
    signatures: int = 0
    """The signatures checked one by one (those the anchor does not vouch for)."""


def _chain_problem(entry: dict[str, Any], expected_id: int, previous: str,
                   signed_seen: bool) -> str | None:  # fmt: skip
    """Why one row breaks the hash chain (None: it holds)."""
    if entry["id"] != expected_id:
        why = "deleted or moved" if entry["id"] > expected_id else "duplicated or moved"
        return f"expected row {expected_id} ({why})"
    if entry["previous_sha256"] != previous:
        return (f"does not follow row {expected_id - 1} "
                "(a row before it was changed, deleted or reordered)")  # fmt: skip
    if entry["entry_sha256"] != entry_hash(entry):
        return "its fields were changed after it was written (its hash does not match)"
    if not entry.get("key_id") and signed_seen:
        return "not signed, after signed rows (written without the stand's key)"
    return None


def _signature_problem(entry: dict[str, Any], keys: dict[str, Any]) -> str | None:
    """Why one signed row's signature does not hold (None: it does)."""
    kid = entry["key_id"]
    if kid not in keys:
        return (f"signed by key {str(kid)[:16]}, which this stand does not trust (another "
                "stand's: stand audit trust ITS-KEY.pem; else forged)")  # fmt: skip
    if not verify_signature(keys[kid], str(entry.get("signature") or ""),
                            entry["entry_sha256"].encode("ascii")):  # fmt: skip
        return "its signature does not verify (rewritten without the stand's key)"
    return None


def signed_by_trusted_key(entry: dict[str, Any]) -> bool:
    """Whether ``entry`` (as stored) is signed by the stand's key or a trusted one, over
    its own fields' hash."""
    keys = trusted_keys()
    kid = entry.get("key_id")
    return (bool(kid) and kid in keys and entry["entry_sha256"] == entry_hash(entry)
            and verify_signature(keys[kid], str(entry.get("signature") or ""),
                                 entry["entry_sha256"].encode("ascii")))  # fmt: skip


def verify_journal(url: str, expect_head: str | None = None, *,
                   every_signature: bool = False) -> Verdict:  # fmt: skip
    """Walk the chain from the first entry: each entry's id one more than the last's, its
    previous hash the last's hash, its own hash its fields'; then each signature the
    anchor does not vouch for is checked against the stand's key (or a trusted stand's):
    the anchor beside the key holds the hash of an entry that itself hashes every entry
    before it, so the entries up to it are the ones the stand wrote; those after it (and
    all of them, when the anchor is missing or not in the chain, or ``every_signature``)
    are checked one by one.  Last, the anchor and ``expect_head`` (an ``id:hash`` kept
    elsewhere) must still be in the chain.  An edited, deleted, moved, re-hashed or forged
    row is named."""
    import sqlalchemy as sa

    keys = trusted_keys()
    with Archive(url) as archive, archive.transaction() as conn:
        rows = conn.execute(sa.select(audit).order_by(audit.c.id)).all()
        where, aid = shown_url(conn), archive_id(conn)
    kept = read_anchor(aid)
    anchored = None if kept is None else str(kept["head"])
    previous, head, unsigned, signed = GENESIS, f"0:{GENESIS}", 0, False
    walked: list[dict[str, Any]] = []
    heads = {head: 0}
    for row in rows:
        entry = dict(row._mapping)
        why = _chain_problem(entry, len(walked) + 1, previous, signed)
        if why is not None:
            return Verdict(len(rows), f"{where}: audit row {entry['id']}: {why}", head,
                           unsigned, anchored)  # fmt: skip
        signed = signed or bool(entry.get("key_id"))
        unsigned += not entry.get("key_id")
        walked.append(entry)
        previous, head = entry["entry_sha256"], f"{entry['id']}:{entry['entry_sha256']}"
        heads[head] = len(walked)
    vouched = 0 if every_signature or anchored not in heads else heads[str(anchored)]
    checked = 0
    for entry in walked[vouched:]:
        if entry.get("key_id"):
            checked += 1
            if (why := _signature_problem(entry, keys)) is not None:
                return Verdict(len(rows), f"{where}: audit row {entry['id']}: {why}", head,
                               unsigned, anchored, checked)  # fmt: skip
    for name, kept_head in (("the anchor kept beside the stand's key", anchored),
                            ("the head kept before", expect_head)):  # fmt: skip
        if kept_head is not None and kept_head not in heads:
            return Verdict(len(rows), (
                f"{where}: {name} ({kept_head[:20]}...) is not in the chain: entries "
                "after it were deleted or rewritten"), head, unsigned, anchored,
                checked)  # fmt: skip
    return Verdict(len(rows), None, head, unsigned, anchored, checked)
