"""The plant's languages (:mod:`stand.report.language`): every message of the translated
modules is in every catalogue, translated, with the same placeholders, and no catalogue
holds a message no code uses; numbers in the locale's form."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from babel.messages.pofile import read_po

from stand.errors import UsageError
from stand.report.language import LANGUAGES, catalogue_path, language

ROOT = Path(__file__).resolve().parents[2]
REPORT = ("certificate", "appendix", "release", "plots", "units")
TRANSLATED = [*sorted((ROOT / "stand" / "station").glob("*.py")),
              *(ROOT / "stand" / "report" / f"{m}.py" for m in REPORT)]  # fmt: skip
"""The modules whose messages are marked: the station's screens and the certificate (the
operator's CLI text is not yet: docs/people.md)."""


def marked(path: Path) -> set[str]:
    """The messages a module marks: ``_("...")`` and ``N_("...")`` with a literal text,
    in f-strings too (Python's own parser: Babel's extractor skips an f-string's inside
    before Python 3.12)."""
    import ast

    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                and node.func.id in ("_", "N_") and node.args
                and isinstance(node.args[0], ast.Constant)
                and isinstance(node.args[0].value, str)):  # fmt: skip
            found.add(node.args[0].value)
    return found


def used() -> set[str]:
    """Every message the translated modules mark."""
    return set().union(*(marked(p) for p in TRANSLATED))


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
