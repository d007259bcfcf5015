"""Log-ins of one process (a station, an OPC UA server), each checked and journaled
(:mod:`stand.actions.sessions`), with a brake on guessing: after :data:`FREE_FAILURES`
failures of an account, or of a source (an address, a client's certificate), each
further try of it waits longer (:func:`wait_after`: refused unchecked, with
:class:`stand.errors.ThrottledError`, until then), and after :data:`LOCK_FAILURES` of an
account the stand disables it, journaled (:func:`stand.actions.lock_account`).

The counts live in the process that checks (a station and an OPC UA server each keep
their own) and are forgotten at a success or a restart; the lock is in the archive.
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Any

from stand.actions.accounts import lock_account
from stand.actions.door import os_actor
from stand.actions.sessions import log_in, log_in_badge
from stand.archive.accounts import badge_owner
from stand.errors import StandError, ThrottledError

log = logging.getLogger(__name__)
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


class LogIns:
    """The log-ins checked by one process (thread-safe) against the archive ``url``;
    ``via`` names the process in the journal (``station``, ``opcua``)."""

    def __init__(self, url: str, via: str) -> None:
        self.url, self.via = url, via
        self._lock = threading.Lock()
        self._failures: dict[str, tuple[int, float]] = {}  # key -> (failures, next try at)

    def password(self, name: str, password: str, source: str) -> dict[str, Any] | None:
        """The active account ``name`` if ``password`` is its password, else None (both
        journaled); ThrottledError, unchecked, while the account or ``source`` waits."""
        keys = (f"account:{name.strip().lower()}", f"source:{source}")
        self._may_try(keys)
        found = log_in(self.url, name, password, self.via)
        if found is None:
            if self._failed(keys)[0] >= LOCK_FAILURES:
                self._lock_account(name.strip())
            return None
        self._forget(keys)
        return found

    def badge(self, code: str, pin: str, source: str) -> dict[str, Any] | None:
        """The active account whose badge carries ``code`` if ``pin`` is its PIN, else
        None (both journaled); ThrottledError, unchecked, while ``source`` or the badge's
        account waits.  A wrong PIN counts against the badge's account too (locked after
        :data:`LOCK_FAILURES`)."""
        owner = badge_owner(self.url, code)
        keys = (f"source:{source}",) + ((f"account:{owner.lower()}",) if owner else ())
        self._may_try(keys)
        found = log_in_badge(self.url, code, pin, self.via)
        if found is None:
            if self._failed(keys)[-1] >= LOCK_FAILURES and owner is not None:
                self._lock_account(owner)
            return None
        self._forget(keys)
        return found

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

    def _lock_account(self, name: str) -> None:
        why = f"locked after {LOCK_FAILURES} failed log-ins"
        try:
            if lock_account(self.url, os_actor(self.via), name, why):
                log.warning("account %s %s", name[:64], why)
        except StandError as exc:
            log.warning("account %s not locked: %s", name[:64], exc)
