"""Who comes and goes: a log-in (by password or badge), a failed one, a log-out and a
session ended because its account was disabled or changed, each journaled (the account
name as typed, where from; never a password or a badge's code)."""

from __future__ import annotations

from typing import Any

from stand.actions.door import Actor
from stand.archive.accounts import check_badge, check_password
from stand.archive.audit import Change, journal
from stand.errors import RefusedError

MAX_TYPED = 64
"""The most of a typed account name the journal keeps [characters]."""


def _typed(name: str) -> str:
    """An account name as typed, made printable and bounded for the journal."""
    shown = "".join(c if c.isprintable() else "?" for c in name[:MAX_TYPED])
    return shown or "(none)"


def log_in(url: str, name: str, password: str, source: str) -> dict[str, Any] | None:
    """The active account ``name`` if ``password`` is its password (journaled as a
    ``login``); else None (journaled as a ``login_failed``, the name as typed)."""
    found = check_password(url, name, password)
    if found is None:
        journal(url, Change("login_failed", _typed(name), None, None, "wrong account, "
                            "password, or a disabled account"), who=_typed(name),
                source=source)  # fmt: skip
        return None
    journal(url, Change("login", name, None, None, "password"), who=name, source=source)
    return found


def account_actor(url: str, name: str, password: str, source: str) -> Actor:
    """The :class:`Actor` of account ``name`` once ``password`` checks (:func:`log_in`,
    journaled); RefusedError, the failed try journaled, when it does not."""
    found = log_in(url, name, password, source)
    if found is None:
        raise RefusedError(f"--as {name}: wrong account or password, or the account is "
                           "disabled (the failed try is journaled)", who=name,
                           right="log in")  # fmt: skip
    return Actor(name, str(found["role"]), source)


def log_in_badge(url: str, code: str, pin: str, source: str) -> dict[str, Any] | None:
    """The active account whose badge carries ``code`` if ``pin`` is its PIN (journaled as
    a ``login``); else None (journaled as a ``login_failed``: under the badge's account
    when one carries it, else as ``(badge)``; neither code nor PIN is kept)."""
    found, owner = check_badge(url, code, pin)
    if found is None:
        why = (
            "a badge no active account carries"
            if owner is None
            else "badge: wrong PIN, or a disabled account"
        )
        journal(url, Change("login_failed", owner or "(badge)", None, None, why),
                who=owner or "(badge)", source=source)  # fmt: skip
        return None
    journal(url, Change("login", found["name"], None, None, "badge"), who=found["name"],
            source=source)  # fmt: skip
    return found


def log_out(url: str, name: str, source: str) -> None:
    """A ``logout`` of ``name``."""
    journal(url, Change("logout", name, None, None, None), who=name, source=source)


def session_ended(url: str, name: str, why: str, source: str) -> None:
    """A ``session_end``: the session of ``name`` ended by the stand (``why``: its account
    was disabled, or its role changed)."""
    journal(url, Change("session_end", name, None, None, why), who=name, source=source)
