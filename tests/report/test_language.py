"""The plant's languages (:mod:`stand.report.language`): every message of the translated
modules is in every catalogue, translated, with the same placeholders, and no catalogue
holds a message no code uses; numbers in the locale's form."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from babel.messages.extract import extract_from_file
from babel.messages.pofile import read_po

from stand.errors import UsageError
from stand.report.language import LANGUAGES, catalogue_path, language

ROOT = Path(__file__).resolve().parents[2]
TRANSLATED = sorted((ROOT / "stand" / "station").glob("*.py"))
"""The modules whose every message is translated: the station's screens (the certificate
and the operator's CLI text are not yet: docs/people.md)."""
KEYWORDS = {"_": None, "N_": None}


def used() -> set[str]:
    """Every message the translated modules mark (``_("...")``, ``N_("...")``)."""
    found = set()
    for path in TRANSLATED:
        for _line, msg, _comments, _context in extract_from_file("python", str(path),
                                                                 keywords=KEYWORDS):  # fmt: skip
            found.add(msg if isinstance(msg, str) else msg[0])
    return found


def placeholders(text: str) -> set[str]:
    return set(re.findall(r"\{(\w*)\}", text))


@pytest.mark.parametrize("code", [c for c in LANGUAGES if c != "en"])
def test_every_message_translated_and_none_unused(code: str) -> None:
    with catalogue_path(code).open("rb") as f:
        catalog = read_po(f, locale=code)
    have = {str(m.id): m for m in catalog if m.id}
    need = used()
    assert not need - set(have), f"{code}: untranslated: {sorted(need - set(have))}"
    assert not set(have) - need, f"{code}: unused: {sorted(set(have) - need)}"
    for msgid, m in have.items():
        assert m.string and not m.fuzzy, f"{code}: {msgid!r} has no translation"
        assert placeholders(msgid) == placeholders(str(m.string)), (code, msgid, m.string)
    print(f"{code}: {len(have)} messages, all translated")


def test_languages_read_and_write_numbers_their_way() -> None:
    uk, de = language("uk"), language("de")
    assert uk("Start measuring") == "Почати вимірювання"
    assert de("Start measuring") == "Messung starten"
    assert language("en")("Start measuring") == "Start measuring"
    assert de("no such message") == "no such message"  # the English where none is
    assert de.number(1234.5) == "1.234,5" and language("en").number(1234.5) == "1,234.5"
    assert uk.number(1234.5).replace("\u00a0", " ") == "1 234,5"
    with pytest.raises(UsageError, match="one of en, uk, de"):
        language("xx")
