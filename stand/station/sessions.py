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

from stand.actions import (
    Actor,
    account_actor,
    lock_account,
    log_in,
    log_in_badge,
    log_out,
    os_actor,
    session_ended,
)
from stand.archive.accounts import account, accounts_of, may
from stand.errors import RefusedError, StandError, ThrottledError

log = logging.getLogger(__name__)
IDLE_S = 15 * 60.0
"""A session ends this long after its last use [s]."""
LIFETIME_S = 8 * 3600.0
"""A session ends this long after its log-in, used or not [s] (a shift; ``stand station
--session-hours``)."""
CHECK_ACCOUNTS_S = 5.0
"""How long the answer "are there accounts?" is kept before the archive is asked again [s]."""


FREE_FAILURES = 5
"""Failed log-ins (per account, and per source) before each further try waits."""
LOCK_FAILURES = 20
"""Failed log-ins of one account after which the stand disables it (an administrator
enables it again: ``stand users set NAME --enable``)."""
MAX_WAIT_S = 300.0
"""The longest wait between tries [s]: 1 s after the sixth failure, doubling."""


def wait_after(failures: int) -> float:
    """The wait before the next try after ``failures`` failed ones [s].

    >>> [wait_after(n) for n in (4, 5, 6, 8, 20)]
    [0.0, 1.0, 2.0, 8.0, 300.0]
    """
    if failures < FREE_FAILURES:
        return 0.0
    return min(2.0 ** (failures - FREE_FAILURES), MAX_WAIT_S)


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
        self._failures: dict[str, tuple[int, float]] = {}  # key -> (failures, next try at)

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
        journaled (:func:`stand.actions.log_in`).  ``source``: where the try came from (the
        client's address): after :data:`FREE_FAILURES` failures of the account or the
        source each try waits longer (:class:`stand.errors.ThrottledError`), and after
        :data:`LOCK_FAILURES` of the account it is disabled, journaled."""
        keys = (f"account:{name.strip().lower()}", f"source:{source}")
        self._may_try(keys)
        found = log_in(self.archive_url, name, password, "station")
        if found is None:
            if self._failed(keys)[0] >= LOCK_FAILURES:
                self._disable(name)
            return None
        self._forget(keys)
        return self._open(found)

    def log_in_badge(self, code: str, source: str = "") -> Session | None:
        """A new session for the account whose badge carries ``code`` (else None); both
        journaled; a source's failed badges wait like passwords."""
        keys = (f"source:{source}",)
        self._may_try(keys)
        found = log_in_badge(self.archive_url, code.strip(), "station")
        if found is None:
            self._failed(keys)
            return None
        self._forget(keys)
        return self._open(found)

    def _may_try(self, keys: tuple[str, ...]) -> None:
        now = time.monotonic()
        with self._lock:
            wait = max((self._failures.get(k, (0, 0.0))[1] - now for k in keys), default=0.0)
        if wait > 0:
            raise ThrottledError(f"too many failed log-ins: try again in {wait:.0f} s",
                            who=keys[0].split(":", 1)[1], right="log in")  # fmt: skip

    def _failed(self, keys: tuple[str, ...]) -> tuple[int, ...]:
        now, counts = time.monotonic(), []
        with self._lock:
            for k in keys:
                n = self._failures.get(k, (0, 0.0))[0] + 1
                self._failures[k] = (n, now + wait_after(n))
                counts.append(n)
        return tuple(counts)

    def _forget(self, keys: tuple[str, ...]) -> None:
        with self._lock:
            for k in keys:
                self._failures.pop(k, None)

    def _disable(self, name: str) -> None:
        why = f"locked after {LOCK_FAILURES} failed log-ins"
        try:
            if lock_account(self.archive_url, os_actor("station"), name.strip(), why):
                log.warning("account %s %s", name.strip()[:64], why)
        except StandError as exc:
            log.warning("account %s not locked: %s", name.strip()[:64], exc)

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
