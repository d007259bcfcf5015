"""Who is logged in at the station: sessions of the archive's accounts
(:mod:`stand.archive.accounts`), each ending :data:`IDLE_S` after its last use.

A station whose archive has no account is a lone stand: nobody logs in, the screens
say so, and the station serves this machine only (``stand station``'s bind rule).  Once
an account exists, every screen but the log-in needs a session, and each action the
role it takes (:func:`stand.archive.accounts.may`).  No UI code here.
"""

from __future__ import annotations

import logging
import secrets
import threading
import time
from dataclasses import dataclass, replace
from typing import Any

from stand.actions import (
    Actor,
    account_actor,
    log_in,
    log_in_badge,
    log_out,
    os_actor,
    session_ended,
)
from stand.archive.accounts import account, accounts_of, may
from stand.errors import RefusedError, StandError

log = logging.getLogger(__name__)
IDLE_S = 15 * 60.0
"""A session ends this long after its last use [s]."""
CHECK_ACCOUNTS_S = 5.0
"""How long the answer "are there accounts?" is kept before the archive is asked again [s]."""


@dataclass(frozen=True)
class Session:
    """One logged-in account."""

    name: str
    role: str
    token: str
    language: str | None
    """The account's language for the screens (None: the station's)."""
    expires_s: float
    """``time.monotonic()`` after which it has ended."""
    checked_s: float = 0.0
    """``time.monotonic()`` when its account was last read again."""

    def may(self, right: str) -> bool:
        return may(self.role, right)


def actor(session: Session | None) -> Actor:
    """Who acts at the station: the session's account, or (a lone stand, nobody logged
    in) the operating system's user the station runs as."""
    if session is None:
        return os_actor("station")
    return Actor(session.name, session.role, "station")


class Sessions:
    """The station's sessions (thread-safe: screens and routes ask from any thread)."""

    def __init__(self, archive_url: str, idle_s: float = IDLE_S) -> None:
        self.archive_url, self.idle_s = archive_url, idle_s
        self._by_token: dict[str, Session] = {}
        self._lock = threading.Lock()
        self._required: tuple[float, bool] = (-1e9, False)

    def required(self) -> bool:
        """Whether the archive has an account (then every screen needs a session).  An
        archive that does not answer keeps the last answer it gave (a lone stand goes on
        measuring; a stand with accounts stays closed); one that never answered requires
        them (never open by accident)."""
        at, answer = self._required
        if time.monotonic() - at < CHECK_ACCOUNTS_S:
            return answer
        try:
            answer = bool(accounts_of(self.archive_url))
        except StandError:
            answer = answer if at >= 0 else True
        self._required = (time.monotonic(), answer)
        return answer

    def log_in(self, name: str, password: str) -> Session | None:
        """A new session for ``name`` if ``password`` is its password (else None); both
        journaled (:func:`stand.actions.log_in`)."""
        found = log_in(self.archive_url, name, password, "station")
        return None if found is None else self._open(found)

    def log_in_badge(self, code: str) -> Session | None:
        """A new session for the account whose badge carries ``code`` (else None); both
        journaled."""
        found = log_in_badge(self.archive_url, code.strip(), "station")
        return None if found is None else self._open(found)

    def _open(self, account: dict[str, Any]) -> Session:
        now = time.monotonic()
        s = Session(account["name"], account["role"], secrets.token_urlsafe(24),
                    account.get("language"), now + self.idle_s, now)  # fmt: skip
        with self._lock:
            self._by_token[s.token] = s
        return s

    def get(self, token: str | None) -> Session | None:
        """The live session of ``token`` (its idle time starts again), or None: unknown,
        ended, logged out, or its account disabled or its role changed since it logged in
        (read again every :data:`CHECK_ACCOUNTS_S`; the end journaled)."""
        if not token:
            return None
        now = time.monotonic()
        with self._lock:
            s = self._by_token.get(token)
            if s is None or s.expires_s < now:
                self._by_token.pop(token, None)
                return None
            s = self._by_token[token] = replace(s, expires_s=now + self.idle_s)
        if now - s.checked_s >= CHECK_ACCOUNTS_S:
            return self._still(s, now)
        return s

    def _still(self, s: Session, now: float) -> Session | None:
        """``s`` if its account is still active in the same role (else it ends, journaled);
        an archive that does not answer keeps it until it does."""
        try:
            found = account(self.archive_url, s.name)
        except StandError:
            return s
        if found is not None and found["active"] and found["role"] == s.role:
            with self._lock:
                if s.token in self._by_token:
                    s = self._by_token[s.token] = replace(s, checked_s=now)
            return s
        with self._lock:
            self._by_token.pop(s.token, None)
        why = (
            "its account was disabled or removed"
            if found is None or not found["active"]
            else f"its role changed from {s.role} to {found['role']}"
        )
        try:
            session_ended(self.archive_url, s.name, why, "station")
        except StandError as exc:
            log.warning("session of %s ended (%s), not journaled: %s", s.name, why, exc)
        return None

    def signer(self, session: Session | None, password: str) -> Actor:
        """Who signs: the session's account once its password, entered again, checks
        (journaled either way; RefusedError when it does not); on a lone stand the
        operating system's user."""
        if not self.required():
            return os_actor("station")
        if session is None:
            raise RefusedError("log in to release a certificate", who="(none)", right="release")
        return account_actor(self.archive_url, session.name, password, "station")

    def log_out(self, token: str | None) -> None:
        """End the session of ``token`` (journaled)."""
        with self._lock:
            s = self._by_token.pop(token or "", None)
        if s is not None:
            try:
                log_out(self.archive_url, s.name, "station")
            except StandError as exc:
                log.warning("log-out of %s not journaled: %s", s.name, exc)


def allowed_roles(right: str) -> list[str]:
    """The roles that have ``right``, the least first."""
    return [r for r in ("operator", "setter", "engineer", "administrator") if may(r, right)]
