"""When the stand's next evaluation is due: ISO 21940-21's machine tests are repeated
periodically (monthly for a machine in daily use, as Bloch & Geitner quote it), the
interval is the config's ``[stand] evaluation_interval_days``."""

from __future__ import annotations

import datetime as dt

DEFAULT_INTERVAL_DAYS = 30
"""Monthly: a stand in daily use (Bloch & Geitner, p. 309)."""


def due_date(performed: dt.datetime, interval_days: int) -> dt.date:
    """The next evaluation's due date: ``interval_days`` after this one (its UTC date)."""
    return performed.astimezone(dt.UTC).date() + dt.timedelta(days=interval_days)


def due_words(due: dt.date | None, today: dt.date) -> tuple[str, str]:
    """(state, words): ``never`` (no evaluation), ``due`` (today or later), ``overdue``.

    >>> due_words(dt.date(2026, 12, 1), dt.date(2026, 11, 27))
    ('due', 'next due 2026-12-01 (in 4 days)')
    >>> due_words(dt.date(2026, 11, 20), dt.date(2026, 11, 27))
    ('overdue', 'OVERDUE since 2026-11-20 (7 days)')
    """
    if due is None:
        return "never", "never evaluated: run stand evaluate on the proving rotor's runs"
    days = (due - today).days
    if days >= 0:
        return "due", f"next due {due.isoformat()} (in {days} day{'s' if days != 1 else ''})"
    return "overdue", f"OVERDUE since {due.isoformat()} ({-days} day{'s' if days != -1 else ''})"
