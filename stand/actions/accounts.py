"""Accounts: added and changed by an administrator only, each change journaled with the
account's state (no secrets) in the same transaction.

The first account of an archive without accounts is made by the operating system's user
(the bootstrap: journaled as such) and must be an administrator; the last active
administrator can be neither disabled nor demoted.
"""

from __future__ import annotations

from typing import Any

from stand.actions.door import Actor, door
from stand.archive.accounts import (
    accounts_in,
    changes_of,
    digest,
    insert_account,
    new_row,
    state_of,
    update_account,
)
from stand.archive.audit import MAX_REASON, Change, checked_reason
from stand.archive.schema import accounts
from stand.errors import RefusedError


def add_account(url: str, actor: Actor, name: str, role: str, password: str, *,
                badge: str | None = None, pin: str | None = None, language: str | None = None,
                active: bool = True, reason: str | None = None
                ) -> tuple[dict[str, Any], int]:  # fmt: skip
    """A new account, active or not (an administrator's right; the first of an archive:
    the operating system's user, and it must be an active administrator); the account
    and its audit entry."""
    checked_reason(reason)  # the bootstrap's words come before it: its own length counts
    row = {
        **new_row(name, role, password, badge=badge, pin=pin, language=language),
        "active": active,
    }  # hashed now
    with door(url, actor, "accounts", "manage accounts") as p:
        first = not accounts_in(p.conn)
        if first and (role != "administrator" or not active):
            raise RefusedError(
                "the first account of an archive is its administrator, active (--role "
                "administrator): nobody else could manage the accounts after it",
                who=actor.name, right="accounts")  # fmt: skip
        after = insert_account(p.conn, row)
        said = f"bootstrap: the archive's first administrator{'; ' + reason if reason else ''}"
        why = said if first and len(said) <= MAX_REASON else reason
        entry = p.journal(Change("account", name, None, digest(after), why,
                                 detail={**state_of(after), "bootstrap": first}))  # fmt: skip
    return after, entry


def set_account(url: str, actor: Actor, name: str, *, role: str | None = None,
                password: str | None = None, active: bool | None = None,
                language: str | None = None, badge: str | None = None,
                pin: str | None = None, no_badge: bool = False,
                reason: str | None = None) -> tuple[dict[str, Any], int]:  # fmt: skip
    """Change an account (an administrator's right; ``no_badge``: its badge and PIN
    withdrawn); the account after and its audit entry.  The last active administrator
    stays one."""
    changes = changes_of(name, role=role, password=password, active=active,
                         language=language, badge=badge, pin=pin,
                         no_badge=no_badge)  # fmt: skip
    with door(url, actor, "accounts", "manage accounts") as p:
        _keep_an_administrator(p.conn, actor, name, changes)
        before, after = update_account(p.conn, name, changes)
        entry = p.journal(Change("account", name, digest(before), digest(after), reason,
                                 detail=state_of(after)))  # fmt: skip
    return after, entry


def lock_account(url: str, actor: Actor, name: str, why: str) -> bool:
    """Disable account ``name`` for ``why`` (too many failed log-ins), by the stand itself
    (``actor``: the process that saw them; no right asked: the stand protects an account,
    an administrator enables it again with ``stand users set NAME --enable``); journaled.
    False when there is no such active account."""
    from stand.archive.accounts import account_in

    with door(url, actor, None, "lock an account") as p:
        found = account_in(p.conn, name)
        if found is None or not found["active"]:
            p.unchanged = True
            return False
        before, after = update_account(p.conn, name, {"active": False})
        p.journal(Change("account", name, digest(before), digest(after), why,
                         detail=state_of(after)))  # fmt: skip
    return True


def _keep_an_administrator(conn: Any, actor: Actor, name: str, changes: dict[str, Any]) -> None:
    """Refuse a change that leaves the archive without an active administrator."""
    import sqlalchemy as sa

    demoted = changes.get("role", "administrator") != "administrator"
    if not (demoted or changes.get("active") is False):
        return
    active_admins = sa.select(accounts.c.name).where(
        accounts.c.role == "administrator", accounts.c.active.is_(True))  # fmt: skip
    if list(conn.execute(active_admins).scalars()) == [name]:
        raise RefusedError(
            f"{name} is the last active administrator: make another one first (nobody "
            "could manage the accounts after it)", who=actor.name, right="accounts")  # fmt: skip
