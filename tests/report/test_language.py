"""The plant's languages (:mod:`stand.i18n.language`): every message of the translated
modules is in every catalogue, translated, with the same placeholders, and no catalogue
holds a message no code uses; numbers in the locale's form."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from babel.messages.pofile import read_po
from hypothesis import given
from hypothesis import strategies as st
from messages import SENTENCE, used

from stand.errors import UsageError
from stand.i18n.language import LANGUAGES, catalogue_path, language


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
    sentences = used(("said",))
    for msgid, m in have.items():
        assert m.string and not m.fuzzy, f"{code}: {msgid!r} has no translation"
        assert placeholders(msgid) == placeholders(str(m.string)), (code, msgid, m.string)
        assert (SENTENCE in m.auto_comments) == (msgid in sentences and "{" in msgid), (
            f"{code}: {msgid!r}: '#. {SENTENCE}' marks exactly the engine's sentences with "
            "placeholders"
        )
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


@pytest.mark.parametrize("code", [c for c in LANGUAGES if c != "en"])
def test_gnu_gettext_compiles_every_catalogue(code: str, tmp_path: Path) -> None:
    """Another implementation reads the catalogues: GNU gettext's ``msgfmt --check``
    (header, plural forms, each message's {placeholders} against its translation)."""
    import shutil
    import subprocess

    msgfmt = shutil.which("msgfmt")
    if msgfmt is None:
        pytest.skip("GNU gettext's msgfmt is not installed (apt-get install gettext)")
    done = subprocess.run([msgfmt, "--check", "--statistics", "-o", str(tmp_path / "m.mo"),
                           str(catalogue_path(code))], capture_output=True, text=True)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert re.fullmatch(r"\d+ translated messages\.\n", done.stderr), done.stderr  # all of them


@pytest.mark.parametrize(("code", "typed", "value"), [
    ("en", "2.5", 2.5), ("de", "2,5", 2.5), ("uk", "2,5", 2.5), ("en", "1500", 1500.0),
    ("de", "0,75", 0.75), ("en", " 6.3 ", 6.3),
])  # fmt: skip
def test_a_number_is_read_as_the_language_writes_it(code: str, typed: str, value: float) -> None:
    assert language(code).typed(typed, "G") == value


@pytest.mark.parametrize(("code", "typed", "says"), [
    ("en", "2,500", "could be read two ways"), ("de", "2.500", "could be read two ways"),
    ("de", "2.5", "could be read two ways"), ("uk", "2\u00a0500", "could be read two ways"),
    ("en", "abc", "is not a number"), ("en", "nan", "is not a number"),
    ("en", "1e999", "is not a number"), ("en", "", "is not a number"),
])  # fmt: skip
def test_a_number_that_could_be_misread_is_refused(code: str, typed: str, says: str) -> None:
    """The Setup screen once saved German "2,5" as 25: a figure with a thousands separator
    is never guessed, one that is no number refused (the message in the language)."""
    with pytest.raises(UsageError) as caught:
        language(code).typed(typed, "G")
    if code == "en":
        assert says in str(caught.value)


@given(st.floats(0.001, 1e5, allow_nan=False), st.sampled_from(["en", "de", "uk"]))
def test_a_figure_shown_for_editing_reads_back(value: float, code: str) -> None:
    """What the Setup screen shows in a field (the language's decimal sign, no grouping)
    reads back to the same figure to its shown decimals."""
    from stand.station.setup import _digits, _shown

    _ = language(code)
    assert _.typed(_shown(_, value), "G") == pytest.approx(round(value, _digits(value)))
