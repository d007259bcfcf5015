"""Accounts for a test's archive, made as an administrator would: the first (``admin``)
by this computer's user (the bootstrap), the others by ``admin``."""

from __future__ import annotations

from stand.actions import Actor, add_account, os_actor, set_account
from stand.archive.accounts import accounts_of

ADMIN = Actor("admin", "administrator", "cli")
"""The administrator every test archive with accounts has."""
ADMIN_PASSWORD = "admin-password"


def with_accounts(url: str, *people: tuple[str, ...]) -> str:
    """Add ``(name, role, password[, badge, pin])`` each to the archive ``url`` (and its
    administrator first, where it has none); the URL."""
    if not accounts_of(url):
        add_account(url, os_actor(), "admin", "administrator", ADMIN_PASSWORD)
    for name, role, password, *badge in people:
        code, pin = badge if badge else (None, None)
        add_account(url, ADMIN, name, role, password, badge=code, pin=pin)
    return url


def change(url: str, name: str, **changes: object) -> None:
    """An account changed by the administrator (:func:`stand.actions.set_account`)."""
    set_account(url, ADMIN, name, **changes)  # type: ignore[arg-type]
