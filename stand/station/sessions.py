"""Who is logged in at the station: sessions of the archive's accounts
(:mod:`stand.archive.accounts`), each ending :data:`IDLE_S` after its last use and at the
latest :data:`LIFETIME_S` after its log-in (a shift), and at once when its account is
disabled or its role changed: the account is read again on every use.

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

from stand.actions import Actor, log_out, os_actor, session_ended
from stand.actions.logins import LogIns
from stand.archive.accounts import account, accounts_of, may
from stand.errors import RefusedError, StandError

log = logging.getLogger(__name__)
IDLE_S = 15 * 60.0
"""A session ends this long after its last use [s]."""
LIFETIME_S = 8 * 3600.0
"""A session ends this long after its log-in, used or not [s] (a shift; ``stand station
--session-hours``)."""
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
    ends_s: float = float("inf")
    """``time.monotonic()`` after which it has ended, used or not (its lifetime)."""

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

    def __init__(
        self, archive_url: str, idle_s: float = IDLE_S, lifetime_s: float = LIFETIME_S
    ) -> None:
        self.archive_url, self.idle_s, self.lifetime_s = archive_url, idle_s, lifetime_s
        self._by_token: dict[str, Session] = {}
        self._lock = threading.Lock()
        self._required: tuple[float, bool] = (-1e9, False)
        self.logins = LogIns(archive_url, "station")

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

    def log_in(self, name: str, password: str, source: str = "") -> Session | None:
        """A new session for ``name`` if ``password`` is its password (else None); both
        journaled.  ``source``: where the try came from (the client's address): failures
        of the account or the source make the next try wait, and lock the account after
        many (:class:`stand.actions.logins.LogIns`)."""
        found = self.logins.password(name, password, source)
        return None if found is None else self._open(found)

    def log_in_badge(self, code: str, pin: str, source: str = "") -> Session | None:
        """A new session for the account whose badge carries ``code`` if ``pin`` is its
        PIN (else None); both journaled, failures braked like passwords."""
        found = self.logins.badge(code.strip(), pin.strip(), source)
        return None if found is None else self._open(found)

    def _open(self, account: dict[str, Any]) -> Session:
        now = time.monotonic()
        s = Session(account["name"], account["role"], secrets.token_urlsafe(24),
                    account.get("language"), now + self.idle_s,
                    now + self.lifetime_s)  # fmt: skip
        with self._lock:
            self._by_token[s.token] = s
        return s

    def get(self, token: str | None) -> Session | None:
        """The live session of ``token`` (its idle time starts again), or None: unknown,
        idle too long, past its lifetime, logged out, or its account disabled or its role
        changed since it logged in (read again on every use; an end journaled)."""
        if not token:
            return None
        now = time.monotonic()
        with self._lock:
            s = self._by_token.get(token)
            if s is None or s.expires_s < now:
                self._by_token.pop(token, None)
                return None
            if s.ends_s < now:
                self._by_token.pop(token, None)
            else:
                s = self._by_token[token] = replace(s, expires_s=now + self.idle_s)
        if s.ends_s < now:
            self._ended(s, f"its lifetime of {self.lifetime_s / 3600:g} h passed")
            return None
        return self._still(s)

    def _still(self, s: Session) -> Session | None:
        """``s`` if its account is still active in the same role (else it ends, journaled);
        an archive that does not answer keeps it until it does."""
        try:
            found = account(self.archive_url, s.name)
        except StandError:
            return s
        if found is not None and found["active"] and found["role"] == s.role:
            return s
        with self._lock:
            self._by_token.pop(s.token, None)
        why = (
            "its account was disabled or removed"
            if found is None or not found["active"]
            else f"its role changed from {s.role} to {found['role']}"
        )
        self._ended(s, why)
        return None

    def _ended(self, s: Session, why: str) -> None:
        """Journal that the stand ended ``s`` (``why``)."""
        try:
            session_ended(self.archive_url, s.name, why, "station")
        except StandError as exc:
            log.warning("session of %s ended (%s), not journaled: %s", s.name, why, exc)

    def signer(self, session: Session | None, password: str, badge: str = "", pin: str = "",
               source: str = "") -> Actor:  # fmt: skip
        """Who signs: the session's account once its password (or its badge and PIN),
        entered again, checks: journaled and braked like a log-in, RefusedError when it
        does not (a badge of another account included); on a lone stand the operating
        system's user."""
        if not self.required():
            return os_actor("station")
        if session is None:
            raise RefusedError("log in to release a certificate", who="(none)", right="release")
        if badge:
            found = self.logins.badge(badge.strip(), pin.strip(), source)
            what = "badge or PIN"
        else:
            found = self.logins.password(session.name, password, source)
            what = "password"
        if found is None or found["name"] != session.name:
            raise RefusedError(f"{session.name}: wrong {what} (the failed try is journaled)",
                               who=session.name, right="release")  # fmt: skip
        return Actor(found["name"], str(found["role"]), "station")

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
