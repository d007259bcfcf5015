"""The plant's languages: the product's own words through gettext catalogues (Babel), and
numbers and dates in the locale's form.

The catalogues are ``stand/data/locale/<code>/LC_MESSAGES/stand.po`` (English is the
source language: no catalogue).  A message is marked in the code as ``_("...")`` where
``_`` is a :class:`Language` (or ``N_("...")`` where it is only named, to be translated
where it is shown); ``tests/report/test_language.py`` extracts them all (Babel) and fails
on a message a catalogue lacks, leaves empty or marks fuzzy, and on one no code uses.
A plant adds a language by adding a catalogue (docs/people.md says how).
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from stand.errors import UsageError

LANGUAGES = {"en": "English", "uk": "Українська", "de": "Deutsch"}
"""The languages shipped: code and name in the language itself."""
LOCALE_DIR = Path(__file__).resolve().parents[1] / "data" / "locale"
DOMAIN = "stand"


def catalogue_path(code: str) -> Path:
    """Where the catalogue of language ``code`` is kept."""
    return LOCALE_DIR / code / "LC_MESSAGES" / f"{DOMAIN}.po"


def N_(msgid: str) -> str:
    """Mark a message for the catalogues where it is named, not shown (no translation)."""
    return msgid


@dataclass(frozen=True)
class Language:
    """One language: its messages, and its way of writing numbers and times.

    Call it on a message (``_("Start measuring")``) for the message in this language
    (the English message where the catalogue has none).
    """

    code: str = "en"
    messages: Mapping[str, str] = field(default_factory=dict)

    def __call__(self, msgid: str) -> str:
        return self.messages.get(msgid) or msgid

    def number(self, value: float, digits: int = 1) -> str:
        """``1234.5`` as this language writes it (``1,234.5``; ``1.234,5``; ``1 234,5``)."""
        from babel.numbers import format_decimal

        pattern = "#,##0" + ("." + "0" * digits if digits > 0 else "")
        return str(format_decimal(value, format=pattern, locale=self.code))

    def when(self, t: dt.datetime) -> str:
        """A time with its zone as this language writes it (local time)."""
        from babel.dates import format_datetime

        return str(format_datetime(t.astimezone(), "medium", locale=self.code)) + " " + (
            t.astimezone().strftime("%Z"))  # fmt: skip


ENGLISH = Language()


def language(code: str | None) -> Language:
    """The language ``code`` (None: English), its catalogue read (UsageError for a code the
    product does not ship, or a catalogue that does not read)."""
    if code is None or code == "en":
        return ENGLISH
    if code not in LANGUAGES:
        raise UsageError(f"language {code!r}: one of {', '.join(LANGUAGES)}")
    from babel.messages.pofile import read_po

    path = catalogue_path(code)
    try:
        with path.open("rb") as f:
            catalog = read_po(f, locale=code)
    except (OSError, ValueError) as exc:
        raise UsageError(f"{path}: the {LANGUAGES[code]} catalogue does not read ({exc})") from exc
    found = {str(m.id): str(m.string) for m in catalog if m.id and m.string and not m.fuzzy}
    return Language(code, found)
