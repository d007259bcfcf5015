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
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from stand.errors import UsageError
from stand.i18n.words import N_

__all__ = ["ENGLISH", "LANGUAGES", "N_", "Language", "catalogue_path", "language"]

LANGUAGES = {"en": "English", "uk": "Українська", "de": "Deutsch"}
"""The languages shipped: code and name in the language itself."""
LOCALE_DIR = Path(__file__).resolve().parents[1] / "data" / "locale"
DOMAIN = "stand"


def catalogue_path(code: str) -> Path:
    """Where the catalogue of language ``code`` is kept."""
    return LOCALE_DIR / code / "LC_MESSAGES" / f"{DOMAIN}.po"


AMBIGUOUS = N_(
    "{what}: {text} could be read two ways: write it without a thousands "
    "separator, with {sign} before the decimals"
)
NOT_A_NUMBER = N_("{what}: {text} is not a number")
"""What :meth:`Language.typed` says of a number it does not take."""


@dataclass(frozen=True)
class Language:
    """One language: its messages, and its way of writing numbers and times.

    Call it on a message (``_("Start measuring")``) for the message in this language
    (the English message where the catalogue has none).
    """

    code: str = "en"
    messages: Mapping[str, str] = field(default_factory=dict)
    patterns: tuple[tuple[re.Pattern[str], str], ...] = ()
    """The messages with placeholders, as patterns that find them in a sentence."""

    def __call__(self, msgid: str) -> str:
        found = self.messages.get(msgid)
        if found:
            return found
        return self._sentence(msgid) if self.patterns and "{" not in msgid else msgid

    def _sentence(self, text: str) -> str:
        """A sentence the engine wrote (:func:`stand.i18n.words.said`), in this language: its
        message found by pattern, its values put back (a number with this language's
        decimal sign, a value that is a message itself translated)."""
        for pattern, msgstr in self.patterns:
            if (m := pattern.fullmatch(text)) is not None:
                values = {k: self._value(v) for k, v in m.groupdict().items()}
                return msgstr.format(**values)
        return text

    def _value(self, v: str) -> str:
        return v.replace(".", self.decimal) if _DECIMAL.fullmatch(v) else self(v)

    @property
    def decimal(self) -> str:
        """This language's decimal sign (``.`` in English, ``,`` in German and Ukrainian)."""
        if self.code == "en":
            return "."
        from babel.numbers import get_decimal_symbol

        return str(get_decimal_symbol(self.code))

    def number(self, value: float, digits: int = 1) -> str:
        """``1234.5`` as this language writes it (``1,234.5``; ``1.234,5``; ``1 234,5``)."""
        from babel.numbers import format_decimal

        pattern = "#,##0" + ("." + "0" * digits if digits > 0 else "")
        return str(format_decimal(value, format=pattern, locale=self.code))

    def typed(self, text: str, what: str) -> float:
        """A number a person typed, read by this language's rules (the same that
        :meth:`number` writes by: ``2,5`` is 2.5 in German and Ukrainian, ``2.5`` in
        English).  UsageError, naming ``what``, for a text that is no number, and for one
        with the thousands separator: ``2,500`` in English, ``2.500`` in German could be
        either, and is never guessed."""
        from babel.numbers import NumberFormatError, get_group_symbol, parse_decimal

        from stand.errors import UsageError

        plain = text.strip()
        group = str(get_group_symbol(self.code))
        spaces = {group, "\u00a0", "\u202f", " "} if group.isspace() else {group}
        if any(g in plain for g in spaces):
            raise UsageError(self(AMBIGUOUS).format(what=what, text=plain[:40],
                                                    sign=self.decimal))  # fmt: skip
        try:
            value = float(parse_decimal(plain, locale=self.code, strict=True))
        except (NumberFormatError, ValueError):
            value = math.nan
        if not math.isfinite(value):
            raise UsageError(self(NOT_A_NUMBER).format(what=what, text=plain[:40]))
        return value

    def when(self, t: dt.datetime | str, *, seconds: bool = False) -> str:
        """A time in local time with its zone, its date as this language writes it
        (``27 Nov 2026 15:04 CET``, ``27.11.2026 15:04 CET``, ``27 лист. 2026 р. 15:04
        CET``); an ISO 8601 text is read first (one that does not read is given as it is).

        >>> ENGLISH.when("")
        ''
        """
        if isinstance(t, str):
            try:
                t = dt.datetime.fromisoformat(t)
            except ValueError:
                return str(t)
        from babel.dates import format_date

        local = t.astimezone()
        day = format_date(local, "medium", locale="en_GB" if self.code == "en" else self.code)
        clock = local.strftime("%H:%M:%S" if seconds else "%H:%M")
        return f"{day} {clock} {local:%Z}"


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
    sentences = sorted((str(m.id) for m in catalog if m.id and SENTENCE in m.auto_comments
                        and str(m.id) in found), key=len, reverse=True)  # fmt: skip
    return Language(code, found, tuple((_pattern(k), found[k]) for k in sentences))


SENTENCE = "engine sentence"
"""The comment (``#. engine sentence``) a catalogue gives a message the engine writes with
:func:`stand.i18n.words.said`: only these are found again in a sentence by their words (the
longest first), so that a screen's own text is never taken apart."""
_PLACEHOLDER = re.compile(r"\{(\w+)\}")
_DECIMAL = re.compile(r"[-+]?\d+\.\d+")


def _pattern(msgid: str) -> re.Pattern[str]:
    """The message ``msgid`` as a pattern: its words as they are, each placeholder any
    text (the same placeholder twice: the same text)."""
    out, seen, at = [], set(), 0
    for m in _PLACEHOLDER.finditer(msgid):
        out.append(re.escape(msgid[at : m.start()]))
        name = m.group(1)
        out.append(f"(?P={name})" if name in seen else f"(?P<{name}>.+?)")
        seen.add(name)
        at = m.end()
    out.append(re.escape(msgid[at:]))
    return re.compile("".join(out), re.DOTALL)
