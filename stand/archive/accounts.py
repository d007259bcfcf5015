"""The people who work the stand: accounts with a role, kept in the archive so that the
station and the OPC UA server (other processes) know the same people.

Roles, each with the rights of the one before and more (:data:`RIGHTS`):

- ``operator``: measures, corrects and checks rotors; reads the history;
- ``setter``: also loads rotor types and toolings, sends jobs, releases certificates;
- ``engineer``: also calibrates, evaluates the stand and edits tolerances;
- ``administrator``: also manages the accounts.

Passwords are stored as argon2id hashes (argon2-cffi, the reference implementation's
binding); a badge (a bar-code a scanner types) as its SHA-256.  Every change to an account
is made and journaled in one transaction by :mod:`stand.actions.accounts`.
"""

from __future__ import annotations

import datetime as dt
import re
from typing import Any

from stand.archive.schema import accounts
from stand.archive.store import Archive
from stand.archive.validate import account_row, as_stored, shown_url
from stand.errors import UsageError

ROLES = ("operator", "setter", "engineer", "administrator")
RIGHTS = {
    "operator": frozenset({"measure", "correct", "check", "read"}),
    "setter": frozenset({"measure", "correct", "check", "read", "load", "jobs", "release"}),
    "engineer": frozenset({"measure", "correct", "check", "read", "load", "jobs", "release",
                           "calibrate", "evaluate", "tolerance"}),
}  # fmt: skip
RIGHTS["administrator"] = RIGHTS["engineer"] | {"accounts"}
"""What each role may do."""
NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._@-]{0,63}")
"""An account's name: a letter or digit, then up to 63 of letters, digits, ``._@-``."""
MIN_PASSWORD = 8
"""The shortest password an account takes [characters]."""

__all__ = ["MIN_PASSWORD", "NAME", "RIGHTS", "ROLES", "account", "account_in", "accounts_in",
           "accounts_of", "changes_of", "check_badge", "check_password", "digest", "insert_account",
           "may", "new_row", "public", "state_of", "update_account"]  # fmt: skip


def _hasher() -> Any:
    from argon2 import PasswordHasher

    return PasswordHasher()


def _now() -> str:
    return dt.datetime.now(dt.UTC).isoformat(timespec="seconds")


def may(role: str | None, right: str) -> bool:
    """Whether an account of ``role`` has ``right`` (None: nobody logged in: no right)."""
    return role is not None and right in RIGHTS.get(role, frozenset())


def _checked(name: str, role: str | None, password: str | None) -> None:
    if not NAME.fullmatch(name):
        raise UsageError(f"account name {name[:70]!r}: a letter or digit, then up to 63 "
                         "letters, digits or . _ @ -")  # fmt: skip
    if role is not None and role not in ROLES:
        raise UsageError(f"role {role!r}: one of {', '.join(ROLES)}")
    if password is not None and (len(password) < MIN_PASSWORD or not password.isprintable()):
        raise UsageError(f"a password of at least {MIN_PASSWORD} printable characters")


def new_row(name: str, role: str, password: str, badge: str | None = None,
            language: str | None = None) -> dict[str, Any]:  # fmt: skip
    """A new account's row, its password hashed (UsageError if a field is refused)."""
    from stand.archive.audit import sha256_of

    _checked(name, role, password)
    return {"name": name, "role": role, "password_hash": _hasher().hash(password),
            "badge_sha256": None if badge is None else sha256_of(badge), "active": True,
            "language": language, "created_at": _now(), "changed_at": _now()}  # fmt: skip


def insert_account(conn: Any, row: dict[str, Any]) -> dict[str, Any]:
    """Insert a new account's row (:func:`new_row`) in the open transaction ``conn``; the
    account as :func:`account` gives it (UsageError if the name is taken)."""
    import sqlalchemy as sa

    if conn.execute(sa.select(accounts.c.name).where(accounts.c.name == row["name"])).first():
        raise UsageError(f"account {row['name']!r} exists already")
    conn.execute(sa.insert(accounts).values(**row))
    return public(row)


def changes_of(name: str, *, role: str | None = None, password: str | None = None,
               active: bool | None = None, language: str | None = None,
               badge: str | None = None) -> dict[str, Any]:  # fmt: skip
    """The columns a change of an account sets (a password hashed; UsageError if a field
    is refused)."""
    from stand.archive.audit import sha256_of

    _checked(name, role, password)
    changes: dict[str, Any] = {"changed_at": _now()}
    if role is not None:
        changes["role"] = role
    if password is not None:
        changes["password_hash"] = _hasher().hash(password)
    if active is not None:
        changes["active"] = active
    if language is not None:
        changes["language"] = language
    if badge is not None:
        changes["badge_sha256"] = sha256_of(badge)
    return changes


def update_account(conn: Any, name: str, changes: dict[str, Any]
                   ) -> tuple[dict[str, Any], dict[str, Any]]:  # fmt: skip
    """Change an account in the open transaction ``conn`` (``changes``:
    :func:`changes_of`); (before, after) as :func:`account` gives them."""
    import sqlalchemy as sa

    before = account_in(conn, name)
    if before is None:
        raise UsageError(f"no account {name!r}")
    conn.execute(sa.update(accounts).where(accounts.c.name == name).values(**changes))
    return before, account_in(conn, name) or before


def account_in(conn: Any, name: str) -> dict[str, Any] | None:
    """One account without secrets, read in the open transaction ``conn`` (None: none)."""
    row = conn.execute(_select().where(accounts.c.name == name)).first()
    return None if row is None else public(account_row(row, shown_url(conn), ROLES))


def accounts_in(conn: Any) -> list[dict[str, Any]]:
    """Every account without secrets, read in the open transaction ``conn``, by name."""
    shown = shown_url(conn)
    rows = conn.execute(_select().order_by(accounts.c.name)).all()
    return [public(account_row(r, shown, ROLES)) for r in rows]


def digest(account: dict[str, Any] | None) -> str | None:
    """An account (as :func:`public` gives it: no secrets) as the journal's SHA-256."""
    import json

    from stand.archive.audit import sha256_of

    return None if account is None else sha256_of(json.dumps(account, sort_keys=True))


def state_of(account: dict[str, Any]) -> dict[str, Any]:
    """What the journal keeps of an account (no secrets: a digest of them): its role,
    whether it is active, its language and its credentials' digest."""
    return {k: account[k] for k in ("role", "active", "language", "credentials_sha256")}


def _select() -> Any:
    """Every column, and ``active`` as stored too (:func:`as_stored`)."""
    import sqlalchemy as sa

    return sa.select(accounts, as_stored(accounts.c.active))


def _rows(url: str, *where: Any) -> list[dict[str, Any]]:
    """The accounts rows (matching ``where``), each checked, by name."""
    with Archive(url) as archive, archive.transaction() as conn:
        rows = conn.execute(_select().where(*where).order_by(accounts.c.name)).all()
        shown = shown_url(conn)
    return [account_row(r, shown, ROLES) for r in rows]


def public(row: dict[str, Any]) -> dict[str, Any]:
    """An account without its secrets (a digest of them, for the journal)."""
    from stand.archive.audit import sha256_of

    state = {k: row.get(k) for k in ("name", "role", "active", "language")}
    state["credentials_sha256"] = sha256_of(f"{row['password_hash']}|{row['badge_sha256']}")
    return {**state, "created_at": row["created_at"], "changed_at": row["changed_at"]}


def accounts_of(url: str) -> list[dict[str, Any]]:
    """Every account, by name, without secrets."""
    return [public(r) for r in _rows(url)]


def account(url: str, name: str) -> dict[str, Any] | None:
    """One account without secrets (None: no such account)."""
    return next((a for a in accounts_of(url) if a["name"] == name), None)


def check_password(url: str, name: str, password: str) -> dict[str, Any] | None:
    """The active account ``name`` if ``password`` is its password; else None (the same
    answer for no account, a disabled one and a wrong password)."""
    from argon2.exceptions import InvalidHashError, VerificationError

    found = _rows(url, accounts.c.name == name)
    if not found or not found[0]["active"]:
        _hasher().hash(password)  # as long as a check: no hint which names exist
        return None
    try:
        _hasher().verify(found[0]["password_hash"], password)
    except (VerificationError, InvalidHashError):
        return None
    return public(found[0])


def check_badge(url: str, code: str) -> dict[str, Any] | None:
    """The active account whose badge carries ``code`` (a scanner typed it); else None."""
    import sqlalchemy as sa

    from stand.archive.audit import sha256_of

    if not code:
        return None
    with Archive(url) as archive, archive.transaction() as conn:
        row = conn.execute(
            sa.select(accounts).where(
                accounts.c.badge_sha256 == sha256_of(code), accounts.c.active.is_(True)
            )
        ).first()
    return None if row is None else public(dict(row._mapping))
