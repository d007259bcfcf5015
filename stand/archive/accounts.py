"""The people who work the stand: accounts with a role, kept in the archive so that the
station and the OPC UA server (other processes) know the same people.

Roles, each with the rights of the one before and more (:data:`RIGHTS`):

- ``operator``: measures, corrects and checks rotors; reads the history;
- ``setter``: also loads rotor types and toolings, sends jobs, releases certificates;
- ``engineer``: also calibrates, evaluates the stand and edits tolerances;
- ``administrator``: also manages the accounts.

Passwords are stored as argon2id hashes (argon2-cffi, the reference implementation's
binding).  A badge (a bar code a scanner types, at least :data:`MIN_BADGE` characters)
logs in with the account's PIN (:data:`PIN`, stored as argon2id like a password); the
badge is stored as its HMAC-SHA256 under a key kept outside the archive
(:func:`stand.archive.keys.badge_key`), so that the stand finds its account by it, no two
accounts carry one badge, and a copy of the archive gives no code away.  Badges stored
before revision 0011 (a plain SHA-256, ``badge_sha256``) no longer log in: issue them
again.  Every change to an account is made and journaled in one transaction by
:mod:`stand.actions.accounts`.
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
MIN_BADGE, MAX_BADGE = 8, 128
"""The shortest and the longest badge code an account takes [characters]."""
PIN = re.compile(r"[0-9]{4,12}")
"""A PIN: 4 to 12 digits (what a badge reader's keypad types)."""

__all__ = ["MAX_BADGE", "MIN_BADGE", "MIN_PASSWORD", "NAME", "PIN", "RIGHTS", "ROLES",
           "account", "account_in", "accounts_in", "accounts_of", "badge_mac", "badge_owner",
           "changes_of", "check_badge", "check_password", "digest", "has_badge",
           "insert_account", "may", "new_row", "public", "state_of", "update_account"]  # fmt: skip


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


def _checked_badge(badge: str | None, pin: str | None) -> None:
    if badge is not None and not (MIN_BADGE <= len(badge) <= MAX_BADGE and badge.isprintable()
                                  and badge == badge.strip()):  # fmt: skip
        raise UsageError(f"a badge code of {MIN_BADGE} to {MAX_BADGE} printable characters, "
                         "no space at either end")  # fmt: skip
    if pin is not None and not PIN.fullmatch(pin):
        raise UsageError("a PIN of 4 to 12 digits")


def badge_mac(code: str, key: bytes | None = None) -> str:
    """A badge's code as stored: its HMAC-SHA256 (hex) under the badges' key (``key``,
    default :func:`stand.archive.keys.badge_key`)."""
    import hashlib
    import hmac

    from stand.archive.keys import badge_key

    return hmac.new(key or badge_key(), code.encode(), hashlib.sha256).hexdigest()


def new_row(name: str, role: str, password: str, *, badge: str | None = None,
            pin: str | None = None, language: str | None = None) -> dict[str, Any]:  # fmt: skip
    """A new account's row, its password (and PIN) hashed, its badge's code kept as
    :func:`badge_mac` (UsageError if a field is refused, or a badge comes without PIN)."""
    _checked(name, role, password)
    _checked_badge(badge, pin)
    if badge is not None and pin is None:
        raise UsageError("a badge logs in with the account's PIN: give one (--pin-file)")
    return {"name": name, "role": role, "password_hash": _hasher().hash(password),
            "badge_sha256": None, "badge_hmac": None if badge is None else badge_mac(badge),
            "pin_hash": None if pin is None else _hasher().hash(pin), "active": True,
            "language": language, "created_at": _now(), "changed_at": _now()}  # fmt: skip


def _badge_free(conn: Any, name: str, mac: str | None) -> None:
    """Refuse a badge another account carries (its attribution would be lost)."""
    import sqlalchemy as sa

    if mac is None:
        return
    other = conn.execute(sa.select(accounts.c.name).where(
        accounts.c.badge_hmac == mac, accounts.c.name != name)).first()  # fmt: skip
    if other is not None:
        raise UsageError(f"account {other[0]!r} carries this badge already: one badge, "
                         "one person")  # fmt: skip


def insert_account(conn: Any, row: dict[str, Any]) -> dict[str, Any]:
    """Insert a new account's row (:func:`new_row`) in the open transaction ``conn``; the
    account as :func:`account` gives it (UsageError if the name is taken)."""
    import sqlalchemy as sa

    if conn.execute(sa.select(accounts.c.name).where(accounts.c.name == row["name"])).first():
        raise UsageError(f"account {row['name']!r} exists already")
    _badge_free(conn, row["name"], row["badge_hmac"])
    conn.execute(sa.insert(accounts).values(**row))
    return public(row)


def changes_of(name: str, *, role: str | None = None, password: str | None = None,
               active: bool | None = None, language: str | None = None,
               badge: str | None = None, pin: str | None = None,
               no_badge: bool = False) -> dict[str, Any]:  # fmt: skip
    """The columns a change of an account sets (a password and a PIN hashed, a badge as
    :func:`badge_mac`, ``no_badge``: its badge and PIN withdrawn; UsageError if a field
    is refused)."""
    _checked(name, role, password)
    _checked_badge(badge, pin)
    if no_badge and (badge is not None or pin is not None):
        raise UsageError("a badge withdrawn takes no new badge or PIN")
    changes: dict[str, Any] = {"changed_at": _now()}
    if role is not None:
        changes["role"] = role
    if password is not None:
        changes["password_hash"] = _hasher().hash(password)
    if active is not None:
        changes["active"] = active
    if language is not None:
        changes["language"] = language
    if badge is not None or no_badge:  # a badge of the old kind goes with it
        changes["badge_sha256"] = None
        changes["badge_hmac"] = None if no_badge else badge_mac(badge or "")
    if pin is not None or no_badge:
        changes["pin_hash"] = None if no_badge else _hasher().hash(pin or "")
    return changes


def update_account(conn: Any, name: str, changes: dict[str, Any]
                   ) -> tuple[dict[str, Any], dict[str, Any]]:  # fmt: skip
    """Change an account in the open transaction ``conn`` (``changes``:
    :func:`changes_of`); (before, after) as :func:`account` gives them."""
    import sqlalchemy as sa

    before = account_in(conn, name)
    if before is None:
        raise UsageError(f"no account {name!r}")
    _badge_free(conn, name, changes.get("badge_hmac"))
    conn.execute(sa.update(accounts).where(accounts.c.name == name).values(**changes))
    left = conn.execute(sa.select(accounts.c.badge_hmac, accounts.c.pin_hash)
                        .where(accounts.c.name == name)).first()  # fmt: skip
    if left is not None and left[0] is not None and left[1] is None:
        raise UsageError(f"account {name!r}: a badge logs in with the account's PIN: give "
                         "one (--pin-file)")  # fmt: skip
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
    secrets = f"{row['password_hash']}|{row.get('badge_sha256')}"
    if row.get("badge_hmac") or row.get("pin_hash"):  # revision 0011: a badge and its PIN
        secrets += f"|{row.get('badge_hmac')}|{row.get('pin_hash')}"
    state["credentials_sha256"] = sha256_of(secrets)
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


def check_badge(url: str, code: str, pin: str) -> tuple[dict[str, Any] | None, str | None]:
    """The active account whose badge carries ``code`` if ``pin`` is its PIN, else None;
    and the name of the account the badge belongs to (None: no account carries it).  An
    unknown badge takes as long as a known one (no hint which codes exist)."""
    from argon2.exceptions import InvalidHashError, VerificationError

    found = _rows(url, accounts.c.badge_hmac == badge_mac(code)) if code else []
    if not found or not found[0]["active"] or not found[0]["pin_hash"]:
        _hasher().hash(pin)
        return None, found[0]["name"] if found else None
    try:
        _hasher().verify(found[0]["pin_hash"], pin)
    except (VerificationError, InvalidHashError):
        return None, found[0]["name"]
    return public(found[0]), found[0]["name"]


def badge_owner(url: str, code: str) -> str | None:
    """The name of the account whose badge carries ``code``, active or not (None: none)."""
    found = _rows(url, accounts.c.badge_hmac == badge_mac(code)) if code else []
    return found[0]["name"] if found else None


def has_badge(url: str) -> dict[str, str]:
    """Each account's badge: ``badge`` (with a PIN), ``old`` (stored before revision
    0011: it no longer logs in, issue it again) or ``none``."""
    return {r["name"]: "badge" if r["badge_hmac"] else "old" if r["badge_sha256"] else "none"
            for r in _rows(url)}  # fmt: skip
